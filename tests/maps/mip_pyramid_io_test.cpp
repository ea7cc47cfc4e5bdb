// MIP pyramid files: one MIP-mapped EXR written and read back bit for bit, bad files
// refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>

#include "core/error.h"
#include "maps/mip_pyramid.h"
#include "tests/common/test_files.h"
#include "texture/image_io.h"

using namespace reliefsim;
namespace fs = std::filesystem;

namespace {

fs::path Scratch() { return reliefsim::testing::Scratch("rs_mip_io_"); }

/// Depth-like values with awkward bit patterns (fixed seed).
std::vector<float> Values(int w, int h) {
    std::vector<float> v(size_t(w) * size_t(h));
    uint32_t state = 2024u;
    for (float& x : v) {
        state = state * 1664525u + 1013904223u;
        x = float(state >> 8) * (1.0f / 16777216.0f);
    }
    v[0] = 0.0f;
    if (v.size() > 1) v[1] = std::numeric_limits<float>::denorm_min();
    if (v.size() > 2) v[2] = 1.0f;
    if (v.size() > 3) v[3] = -0.0f;
    return v;
}

std::string ErrorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected Error";
    return {};
}

bool BitEqual(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * 4) == 0;
}

}  // namespace

TEST(MipPyramidFile, RoundTripsBitExactlyForPowerOfTwoOddAndTinySizes) {
    const fs::path d = Scratch();
    for (const auto& [w, h] : {std::pair{16, 16}, std::pair{13, 7}, std::pair{1, 9},
                               std::pair{1, 1}, std::pair{70, 3}}) {
        for (const MipReduce op : {MipReduce::Min, MipReduce::Max}) {
            const auto levels = BuildMipPyramid(Values(w, h), w, h, 1, op);
            const std::string path =
                (d / ("p" + std::to_string(w) + "x" + std::to_string(h) + ".exr"))
                    .string();
            WriteMipPyramidFile(path, levels, op == MipReduce::Min ? "maxmip" : "minmip");
            const auto back = ReadMipPyramidFile(path);
            ASSERT_EQ(back.size(), levels.size()) << w << "x" << h;
            for (size_t l = 0; l < levels.size(); ++l) {
                EXPECT_EQ(back[l].width, levels[l].width) << l;
                EXPECT_EQ(back[l].height, levels[l].height) << l;
                EXPECT_EQ(back[l].channels, 1);
                EXPECT_TRUE(BitEqual(back[l].values, levels[l].values))
                    << w << "x" << h << " level " << l;
            }
        }
    }
    for (const auto& e : fs::directory_iterator(d))  // one file per pyramid, no temporary
        EXPECT_EQ(e.path().filename().string().find(".rs-"), std::string::npos)
            << e.path();
}

TEST(MipPyramidFile, OnlyExrHoldsLevels) {
    EXPECT_NO_THROW(CheckMipPyramidPath("a/m.exr"));
    EXPECT_NO_THROW(CheckMipPyramidPath("M.EXR"));
    const std::string msg = ErrorOf([] { CheckMipPyramidPath("m.png"); });
    EXPECT_NE(msg.find("\"m.png\""), std::string::npos) << msg;
    EXPECT_NE(msg.find("MIP"), std::string::npos) << msg;
    EXPECT_THROW(CheckMipPyramidPath("m.tif"), Error);
    EXPECT_THROW(CheckMipPyramidPath("m"), Error);
}

TEST(MipPyramidFile, WriterRefusesABrokenPyramidAndWritesNothing) {
    const fs::path d = Scratch();
    auto levels = BuildMipPyramid(Values(8, 8), 8, 8, 1, MipReduce::Min);
    auto shortChain = levels;
    shortChain.pop_back();  // stops at 2x2
    EXPECT_THROW(WriteMipPyramidFile((d / "a.exr").string(), shortChain, "minmip"),
                 Error);
    auto wrongSize = levels;
    wrongSize[1].width = 3;
    EXPECT_THROW(WriteMipPyramidFile((d / "b.exr").string(), wrongSize, "minmip"), Error);
    EXPECT_THROW(WriteMipPyramidFile((d / "c.exr").string(), {}, "minmip"), Error);
    EXPECT_THROW(WriteMipPyramidFile((d / "d.png").string(), levels, "minmip"), Error);
    EXPECT_TRUE(fs::is_empty(d));
}

TEST(MipPyramidFile, ReaderRefusesFilesThatAreNoPyramid) {
    const fs::path d = Scratch();
    // Missing file, or not an image.
    EXPECT_NE(
        ErrorOf([&] { ReadMipPyramidFile((d / "none.exr").string()); }).find("none.exr"),
        std::string::npos);
    std::ofstream(d / "junk.exr") << "not an image";
    EXPECT_THROW(ReadMipPyramidFile((d / "junk.exr").string()), Error);
    // One level of a 13x7 image: no MIP levels.
    const auto v = Values(13, 7);
    WriteFloatImage((d / "flat.exr").string(), 13, 7, 1, v.data());
    std::string msg = ErrorOf([&] { ReadMipPyramidFile((d / "flat.exr").string()); });
    EXPECT_NE(msg.find("1x1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("flat.exr"), std::string::npos) << msg;
    // Three channels.
    std::vector<float> rgb(4 * 4 * 3, 0.5f);
    WriteFloatImage((d / "rgb.exr").string(), 4, 4, 3, rgb.data());
    msg = ErrorOf([&] { ReadMipPyramidFile((d / "rgb.exr").string()); });
    EXPECT_NE(msg.find("3 channels"), std::string::npos) << msg;
    // A non-finite depth in a deeper level.
    auto levels = BuildMipPyramid(Values(4, 4), 4, 4, 1, MipReduce::Min);
    levels[1].values[3] = std::numeric_limits<float>::quiet_NaN();
    WriteMipPyramidFile((d / "nan.exr").string(), levels, "maxmip");
    msg = ErrorOf([&] { ReadMipPyramidFile((d / "nan.exr").string()); });
    EXPECT_NE(msg.find("level 1 texel (1, 1)"), std::string::npos) << msg;
}
