// `reliefsim safety`: the safety profile on a map whose answers are known.
#include "app/safety.h"

#include <gtest/gtest.h>

#include "core/error.h"

using namespace reliefsim;

namespace {

// Depth 1 with a one-texel ridge of depth 0 across it.
DepthField Ridge() {
    DepthField f;
    f.width = f.height = 64;
    f.name = "ridge";
    f.depth.assign(64 * 64, 1.0f);
    for (int j = 0; j < 64; ++j) f.depth[size_t(j) * 64 + 32] = 0.0f;
    return f;
}

}  // namespace

// A vertical ray meets a height field once, so at 0 degrees nothing can be missed; at a
// slant, 4 linear steps jump over the ridge; the exact reference never misses.
TEST(Safety, ProfileOnARidge) {
    RenderSettings s;
    s.width = 96;
    s.height = 64;
    s.azimuth = 90.0f;
    s.threads = 1;
    s.set = {"linear_steps=4"};
    const SafetyProfile p =
        ComputeSafetyProfile(Ridge(), s, {"linear", "relief"}, {0, 60});
    ASSERT_EQ(p.missedShare.size(), 2u);
    for (size_t m = 0; m < 2; ++m) {
        EXPECT_EQ(p.missedShare[m][0], 0.0) << p.methods[m];
        EXPECT_GT(p.missedShare[m][1], 0.01) << p.methods[m];
    }
    s.set.clear();
    const SafetyProfile e = ComputeSafetyProfile(Ridge(), s, {"exact"}, {0, 45, 80});
    for (double share : e.missedShare[0]) EXPECT_EQ(share, 0.0);
    const std::string table = FormatSafetyProfile(p);
    EXPECT_NE(table.find("| linear | 0.000 |"), std::string::npos) << table;
    EXPECT_THROW(ComputeSafetyProfile(Ridge(), s, {"cheese"}, {45}), Error);
    EXPECT_THROW(ComputeSafetyProfile(Ridge(), s, {"linear"}, {95}), Error);
}
