// The method registry: names, parameter validation, kernel construction.
#include "kernels/registry.h"

#include <gtest/gtest.h>

#include "core/error.h"

using namespace reliefsim;

TEST(Registry, FirstKernelsArePresent) {
    for (const char* name : {"linear", "relief", "secant", "interval", "pom"})
        EXPECT_NO_THROW(FindMethod(name)) << name;
}

TEST(Registry, UnknownMethodListsValidNames) {
    try {
        FindMethod("cheese");
        FAIL();
    } catch (const Error& e) {
        std::string m = e.what();
        EXPECT_NE(m.find("cheese"), std::string::npos);
        EXPECT_NE(m.find("relief"), std::string::npos);
    }
}

TEST(Registry, DefaultsAndOverrides) {
    const MethodInfo& m = FindMethod("relief");
    ParamValues v = ResolveParams(m, {"linear_steps=10", "refine_steps=3"});
    EXPECT_EQ(v.at("linear_steps"), 10);
    EXPECT_EQ(v.at("refine_steps"), 3);
    EXPECT_EQ(v.at("budget"), 0);
    Kernel k = MakeKernel(m, v);
    EXPECT_EQ(&k.Info(), &m);
    const bool isRelief = VisitKernelType(k.index, [](auto type) {
        return std::is_same_v<typename decltype(type)::type, ReliefKernel>;
    });
    EXPECT_TRUE(isRelief);
    const ReliefKernel::Params p = ReliefKernel::FromValues(k.values);
    EXPECT_EQ(p.linearSteps, 10);
    EXPECT_EQ(p.refineSteps, 3);
}

// The catalogue is derived from the type list: every kernel's self-description is
// complete and its parameters' defaults lie in their ranges, with a uniform for the GLSL
// twin.
TEST(Registry, EveryKernelDescribesItself) {
    ASSERT_EQ(int(Methods().size()), KernelTypes::kCount);
    for (const KernelInfo* m : Methods()) {
        EXPECT_FALSE(m->name.empty());
        EXPECT_FALSE(m->title.empty()) << m->name;
        EXPECT_FALSE(m->source.empty()) << m->name;
        EXPECT_FALSE(m->glslFile.empty()) << m->name;
        EXPECT_EQ(&FindMethod(m->name), m);
        bool hasBudget = false;
        for (const ParamSpec& p : m->params) {
            EXPECT_LE(p.minValue, p.defaultValue) << m->name << " " << p.name;
            EXPECT_LE(p.defaultValue, p.maxValue) << m->name << " " << p.name;
            EXPECT_FALSE(p.uniform.empty()) << m->name << " " << p.name;
            if (!p.choices.empty()) {  // the value is the index of a name
                EXPECT_TRUE(p.integer) << p.name;
                EXPECT_EQ(p.minValue, 0.0) << p.name;
                EXPECT_EQ(p.maxValue, double(p.choices.size() - 1)) << p.name;
            }
            hasBudget = hasBudget || p.name == "budget";
        }
        EXPECT_TRUE(hasBudget) << m->name;  // the driver reads it
    }
}

TEST(Registry, BadSettingsNameTheCulprit) {
    const MethodInfo& m = FindMethod("relief");
    auto message = [&](const std::string& s) {
        try {
            ResolveParams(m, {s});
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(message("linear_steps=-4").find("linear_steps"), std::string::npos);
    EXPECT_NE(message("linear_steps=-4").find("range"), std::string::npos);
    EXPECT_NE(message("linear_steps=2.5").find("integer"), std::string::npos);
    EXPECT_NE(message("linear_steps=abc").find("not a number"), std::string::npos);
    EXPECT_NE(message("nope=1").find("refine_steps"), std::string::npos);
    EXPECT_NE(message("linear_steps").find("key=value"), std::string::npos);
    // A parameter of another method: cone_steps belongs to the cone kernels.
    EXPECT_NE(message("cone_steps=4").find("not a parameter"), std::string::npos);
    EXPECT_EQ(message("refine=secant"), "");  // every coarse search takes any refinement
}
