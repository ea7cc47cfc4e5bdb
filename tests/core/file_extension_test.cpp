// LowerExtension: the extension that picks a file format, in either case.
#include "core/file_extension.h"

#include <gtest/gtest.h>

namespace reliefsim {
namespace {

TEST(LowerExtension, LowerCasesTheLastExtensionOnly) {
    EXPECT_EQ(LowerExtension("m.exr"), ".exr");
    EXPECT_EQ(LowerExtension("out/M.EXR"), ".exr");
    EXPECT_EQ(LowerExtension("a.Png"), ".png");
    EXPECT_EQ(LowerExtension("maps.v2/cone.tar.GZ"), ".gz");
    EXPECT_EQ(LowerExtension("maps.v2/cone"), "");  // the folder's dot is not it
    EXPECT_EQ(LowerExtension(".exr"), "");          // a hidden file's name
    EXPECT_EQ(LowerExtension("cone."), ".");
    EXPECT_EQ(LowerExtension(""), "");
}

}  // namespace
}  // namespace reliefsim
