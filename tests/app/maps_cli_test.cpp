// `reliefsim maps`: outputs (map, stats JSON), cache, animate, and bad input (non-zero
// exit, one stderr line naming the culprit, nothing written).
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "tests/app/cli_util.h"
#include "texture/image_io.h"

namespace fs = std::filesystem;
namespace OIIO = OIIO_NAMESPACE;

namespace {

using reliefsim::testing::CountLines;
using reliefsim::testing::RunCli;
using reliefsim::testing::Slurp;
using Result = reliefsim::testing::CliResult;

fs::path Scratch() { return reliefsim::testing::Scratch("rs_maps_cli_"); }

/// Runs `maps ARGS --out <scratch>/out/m.EXT` and expects a clean failure naming
/// `culprit`, with neither the map, its statistics nor the output folder written.
void ExpectCleanFailure(const std::string& args, const std::string& culprit,
                        const std::string& ext = ".exr") {
    const fs::path d = Scratch();
    const fs::path outDir = d / "out";
    const Result r =
        RunCli("maps " + args + " --out " + (outDir / ("m" + ext)).string(), d);
    EXPECT_NE(r.exitCode, 0) << args;
    EXPECT_EQ(CountLines(r.err), 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(culprit), std::string::npos) << args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(outDir)) << args;
}

}  // namespace

TEST(MapsCli, WritesMapAndStatisticsIntoANewFolder) {
    const fs::path d = Scratch();
    const fs::path out = d / "new" / "acm.exr";
    const Result r = RunCli(
        "maps --map builtin:shapes:32 --kind acm4 --encoding u8 --out " + out.string(),
        d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(out));
    const std::string json = Slurp(d / "new" / "acm.stats.json");
    for (const char* key : {"\"kind\": \"acm4\"", "\"encoding\": \"u8\"", "\"histogram\"",
                            "\"mean\"", "\"cone_bounds\": \"texel\""})
        EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
    EXPECT_NE(r.out.find("acm4 32x32 x4"), std::string::npos) << r.out;
    // Not a terminal: no progress bar on stderr.
    EXPECT_TRUE(r.err.empty()) << r.err;
    reliefsim::MapLoadOptions lo;
    lo.channel = reliefsim::Channel::R;
    lo.stores = reliefsim::Stores::Depth;
    const reliefsim::DepthField back = reliefsim::LoadHeightMapFile(out.string(), lo);
    EXPECT_EQ(back.width, 32);
    EXPECT_EQ(back.height, 32);
}

TEST(MapsCli, PngAndEveryKindRun) {
    const fs::path d = Scratch();
    for (const char* kind : {"cone", "relaxed", "relaxed-exact", "quad", "acm4", "acm8",
                             "cone-normal", "stacked", "minmip", "maxmip"}) {
        // stacked has more channels than a PNG holds; the pyramids are one MIP-mapped
        // EXR.
        const std::string k = kind;
        const std::string ext =
            k == "stacked" || k == "minmip" || k == "maxmip" ? ".exr" : ".png";
        const fs::path out = d / (std::string(kind) + ext);
        // --search-steps applies to the relaxed kind only (elsewhere it is refused).
        const std::string steps =
            std::string(kind) == "relaxed" ? "--search-steps 16 " : "";
        const Result r = RunCli("maps --map builtin:bumps:16 " + steps + "--kind " +
                                    kind + " --out " + out.string(),
                                d);
        EXPECT_EQ(r.exitCode, 0) << kind << "\n" << r.err;
    }
    EXPECT_TRUE(fs::exists(d / "acm8.png"));
    EXPECT_TRUE(fs::exists(d / "minmip.exr"));
    EXPECT_FALSE(fs::exists(d / "minmip_L0.exr"));
}

TEST(MapsCli, RelaxedStackedAndConeNormal) {
    // --relaxed switches stacked and cone-normal to the Listing's relaxed cones: the
    // stacked map's first channel is then the relaxed map.
    const fs::path d = Scratch();
    const std::string base = "maps --map builtin:shapes:24 --search-steps 32 ";
    ASSERT_EQ(RunCli(base + "--kind relaxed --out " + (d / "r.exr").string(), d).exitCode,
              0);
    const Result st = RunCli(base + "--kind stacked --stacked-count 3 --relaxed --out " +
                                 (d / "s.exr").string(),
                             d);
    ASSERT_EQ(st.exitCode, 0) << st.err;
    EXPECT_NE(st.out.find("stacked 24x24 x3"), std::string::npos) << st.out;
    reliefsim::MapLoadOptions lo;
    lo.channel = reliefsim::Channel::R;
    lo.stores = reliefsim::Stores::Depth;
    const reliefsim::DepthField r =
        reliefsim::LoadHeightMapFile((d / "r.exr").string(), lo);
    const reliefsim::DepthField s0 =
        reliefsim::LoadHeightMapFile((d / "s.exr").string(), lo);
    EXPECT_EQ(r.depth, s0.depth);
    const Result cn =
        RunCli(base + "--kind cone-normal --relaxed --out " + (d / "n.exr").string(), d);
    EXPECT_EQ(cn.exitCode, 0) << cn.err;
}

TEST(MapsCli, RelaxedFlagOnAnotherKind) {
    ExpectCleanFailure("--map builtin:shapes:16 --kind acm4 --relaxed", "--relaxed");
    ExpectCleanFailure("--map builtin:shapes:16 --kind cone-normal --normal", "--normal");
}

TEST(MapsCli, BilinearBoundsWriteAndRefuse) {
    const fs::path d = Scratch();
    const std::string base = "maps --map builtin:shapes:32 --cone-bounds bilinear ";
    const Result r = RunCli(base + "--kind acm8 --out " + (d / "b.exr").string(), d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("acm8 32x32 x8"), std::string::npos) << r.out;
    EXPECT_NE(Slurp(d / "b.stats.json").find("\"cone_bounds\": \"bilinear\""),
              std::string::npos);
    // Cached apart from the texel-bound map of the same kind and field.
    const std::string cache = " --cache-dir " + (d / "c").string();
    for (const char* bounds : {"bilinear", "texel"}) {
        const Result c =
            RunCli("maps --map builtin:shapes:32 --kind cone --cone-bounds " +
                       std::string(bounds) + cache,
                   d);
        ASSERT_EQ(c.exitCode, 0) << c.err;
        EXPECT_NE(c.out.find("cache: miss"), std::string::npos) << bounds << c.out;
    }
    ExpectCleanFailure("--map builtin:shapes:16 --kind relaxed --cone-bounds bilinear",
                       "--cone-bounds bilinear");
    ExpectCleanFailure("--map builtin:shapes:16 --kind stacked --cone-bounds bilinear",
                       "--cone-bounds bilinear");
    ExpectCleanFailure(
        "--map builtin:shapes:16 --kind acm4 --adaptive --cone-bounds bilinear",
        "--adaptive");
    ExpectCleanFailure(
        "--map builtin:shapes:16 --kind cone --safety --cone-bounds bilinear",
        "--safety");
    ExpectCleanFailure("--map builtin:shapes:16 --kind cone --cone-bounds exact",
                       "--cone-bounds");
    ExpectCleanFailure("--map builtin:shapes:16 --kind maxmip --cone-bounds texel",
                       "--cone-bounds");
}

TEST(MapsCli, CacheMissThenHit) {
    const fs::path d = Scratch();
    const std::string args =
        "maps --map builtin:shapes:32 --kind quad --cache-dir " + (d / "c").string();
    const Result a = RunCli(args, d);
    ASSERT_EQ(a.exitCode, 0) << a.err;
    EXPECT_NE(a.out.find("cache: miss"), std::string::npos) << a.out;
    const Result b = RunCli(args, d);
    ASSERT_EQ(b.exitCode, 0) << b.err;
    EXPECT_NE(b.out.find("cache: hit"), std::string::npos) << b.out;
}

TEST(MapsCli, AnimateReportsPerFrameTimes) {
    const fs::path d = Scratch();
    const Result r = RunCli("maps --map builtin:flat:64 --animate 3", d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 4) << r.out;
    EXPECT_NE(r.out.find("frame 2:"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("animate: 3 frames, mean"), std::string::npos) << r.out;
}

TEST(MapsCli, UnknownKind) {
    ExpectCleanFailure("--map builtin:shapes:16 --kind cones",
                       "--kind: \"cones\" is unknown");
}

TEST(MapsCli, UnknownEncoding) {
    ExpectCleanFailure("--map builtin:shapes:16 --encoding u7",
                       "--encoding: \"u7\" is unknown");
}

TEST(MapsCli, BadOutputExtension) {
    ExpectCleanFailure("--map builtin:shapes:16", "m.jpg", ".jpg");
}

TEST(MapsCli, OutputExtensionInEitherCase) {
    // The writer picks the format by the extension in either case, and so does the check
    // before it (".EXR" was refused as unsupported while the writer took it).
    const fs::path d = Scratch();
    for (const char* name : {"m.EXR", "m.Png"}) {
        const fs::path out = d / name;
        const Result r =
            RunCli("maps --map builtin:shapes:16 --kind cone --out " + out.string(), d);
        ASSERT_EQ(r.exitCode, 0) << name << "\n" << r.err;
        const std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(out.string());
        ASSERT_TRUE(in) << name;
        const bool exr = std::string(name) == "m.EXR";
        EXPECT_STREQ(in->format_name(), exr ? "openexr" : "png") << name;
        EXPECT_EQ(in->spec().format, exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8)
            << name;
        const std::string json =
            Slurp(d / (fs::path(name).stem().string() + ".stats.json"));
        EXPECT_NE(json.find(exr ? "\"encoding\": \"float\"" : "\"encoding\": \"u8\""),
                  std::string::npos)
            << name << "\n"
            << json;
    }
    // An upper-case PNG still refuses a float encoding.
    ExpectCleanFailure("--map builtin:shapes:16 --encoding float", "is a PNG", ".PNG");
}

TEST(MapsCli, TooManyChannelsForPng) {
    ExpectCleanFailure("--map builtin:shapes:16 --kind stacked --stacked-count 6",
                       "stacked", ".png");
}

TEST(MapsCli, SearchStepsOutOfRange) {
    ExpectCleanFailure("--map builtin:shapes:16 --kind relaxed --search-steps 0",
                       "--search-steps");
}

TEST(MapsCli, MissingMapFile) {
    ExpectCleanFailure("--map /nonexistent/height.png", "height.png");
}

TEST(MapsCli, NanHeights) {
    const fs::path d = Scratch();
    const fs::path nan = d.parent_path() / "rs_maps_cli_nan.exr";
    float px[4] = {0.1f, std::nanf(""), 0.3f, 0.4f};
    reliefsim::WriteFloatImage(nan.string(), 2, 2, 1, px);
    ExpectCleanFailure("--map " + nan.string(), "NaN");
}

TEST(MapsCli, ZeroSizeMap) {
    const fs::path d = Scratch();
    const fs::path zero = d.parent_path() / "rs_maps_cli_zero.tga";
    unsigned char header[18] = {};  // uncompressed grey TGA, 0x0 pixels, 8 bits
    header[2] = 3;
    header[16] = 8;
    std::ofstream(zero, std::ios::binary).write(reinterpret_cast<char*>(header), 18);
    ExpectCleanFailure("--map " + zero.string(), "rs_maps_cli_zero.tga");
}

TEST(MapsCli, ExternalMapOfTheWrongSize) {
    const fs::path d = Scratch();
    const fs::path ext = d.parent_path() / "rs_maps_cli_ext16.png";
    std::vector<uint8_t> px(16 * 16 * 4, 100);
    reliefsim::WriteRgb8Image(ext.string(), 16, 16, 4, px.data());
    ExpectCleanFailure("--map builtin:shapes:32 --external " + ext.string(),
                       "rs_maps_cli_ext16.png");
}

TEST(MapsCli, ExternalAcm8MapsRoundTrip) {
    // An acm8 map written as a PNG (two RGBA halves side by side) or an EXR (eight
    // channels) reads back as the same map: its statistics equal the generated map's.
    const fs::path d = Scratch();
    const std::string gen = "maps --map builtin:shapes:32 --kind acm8 --encoding u8";
    for (const char* ext : {".png", ".exr"}) {
        const fs::path map = d / (std::string("a") + ext);
        const Result w = RunCli(gen + " --out " + map.string(), d);
        ASSERT_EQ(w.exitCode, 0) << w.err;
        const Result r = RunCli("maps --map builtin:shapes:32 --kind acm8 --external " +
                                    map.string() + " --external-channel all",
                                d);
        ASSERT_EQ(r.exitCode, 0) << ext << ": " << r.err;
        // The report (ratio statistics and histogram) is the generated map's.
        const Result g = RunCli(gen, d);
        ASSERT_EQ(g.exitCode, 0) << g.err;
        EXPECT_NE(r.out.find("acm8 32x32 x8: min"), std::string::npos) << r.out;
        EXPECT_EQ(r.out, g.out) << ext;
    }
}
