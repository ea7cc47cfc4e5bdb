// Library errors name their parameters; a front end (the command line) names them its
// way.
#include "core/param_name.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "maps/cone_map.h"

namespace reliefsim {
namespace {

std::string ValidationMessage() {
    ConeMapParams p;
    p.searchSteps = 5000;
    try {
        ValidateConeMapParams(p);
    } catch (const Error& e) {
        return e.what();
    }
    return {};
}

TEST(ParamName, LibrariesNameParametersAndTheCommandLineNamesFlags) {
    SetParamNamer(nullptr);
    EXPECT_EQ(ParamName("search_steps"), "search_steps");
    EXPECT_EQ(ValidationMessage().rfind("search_steps 5000: out of range", 0), 0u)
        << ValidationMessage();
    SetParamNamer(&FlagName);
    EXPECT_EQ(ParamName("search_steps"), "--search-steps");
    EXPECT_EQ(ValidationMessage().rfind("--search-steps 5000: out of range", 0), 0u)
        << ValidationMessage();
    SetParamNamer(nullptr);
    EXPECT_EQ(ParamName("cone_map_encoding"), "cone_map_encoding");
    EXPECT_EQ(FlagName("cone_map_encoding"), "--cone-map-encoding");
}

}  // namespace
}  // namespace reliefsim
