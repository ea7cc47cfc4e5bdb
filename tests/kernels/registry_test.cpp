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
    const auto& lk = std::get<LinearSearchKernel>(k);
    EXPECT_EQ(lk.params.linearSteps, 10);
    EXPECT_EQ(lk.params.refinement, Refinement::Binary);
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
    EXPECT_NE(message("secant_tolerance=0.1").find("not a parameter"), std::string::npos);
}
