// Built-in maps: names, sizes, range, determinism, bad specs.
#include "texture/procedural.h"

#include <gtest/gtest.h>

#include "core/error.h"

using namespace reliefsim;

TEST(Procedural, EveryBuiltinIsInRangeAndDeterministic) {
    for (const std::string& name : BuiltinMapNames()) {
        DepthField a = MakeBuiltinMap(name, 64, 48);
        DepthField b = MakeBuiltinMap(name, 64, 48);
        ASSERT_EQ(a.depth.size(), 64u * 48u) << name;
        EXPECT_EQ(a.depth, b.depth) << name;
        EXPECT_NO_THROW(ValidateDepthField(a)) << name;
    }
}

TEST(Procedural, DefaultSizeAndSpecParsing) {
    DepthField d = MakeBuiltinMap("builtin:shapes");
    EXPECT_EQ(d.width, kDefaultBuiltinSize);
    DepthField s = MakeBuiltinMap("builtin:noise:100");
    EXPECT_EQ(s.width, 100);
    EXPECT_EQ(s.height, 100);
}

TEST(Procedural, ShapesHasTopAndFloorAndSteps) {
    DepthField f = MakeBuiltinMap("shapes", 256, 256);
    float lo = 1, hi = 0;
    for (float d : f.depth) {
        lo = std::min(lo, d);
        hi = std::max(hi, d);
    }
    EXPECT_LT(lo, 0.02f);          // reaches the top
    EXPECT_NEAR(hi, 0.8f, 1e-6f);  // the floor
}

TEST(Procedural, AnalyticFieldsHaveClosedForms) {
    DepthField flat = MakeBuiltinMap("flat", 8, 8);
    for (float d : flat.depth) EXPECT_EQ(d, 0.5f);
    DepthField ramp = MakeBuiltinMap("ramp", 8, 2);
    EXPECT_FLOAT_EQ(ramp.At(3, 1), 3.5f / 8.0f);
}

TEST(Procedural, BadSpecsThrowWithValidNames) {
    try {
        MakeBuiltinMap("builtin:cheese");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("shapes"), std::string::npos);
    }
    EXPECT_THROW(MakeBuiltinMap("builtin:shapes:0"), Error);
    EXPECT_THROW(MakeBuiltinMap("builtin:shapes:abc"), Error);
    EXPECT_THROW(MakeBuiltinMap("builtin:shapes:-4"), Error);
}
