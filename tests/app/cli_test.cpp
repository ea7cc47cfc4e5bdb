// The command line: help, methods, and bad input (one error line, non-zero exit, no
// output).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/app/cli_util.h"
#include "texture/image_io.h"

namespace fs = std::filesystem;

namespace {

using reliefsim::testing::CountLines;
using reliefsim::testing::RunCli;
using Result = reliefsim::testing::CliResult;
using reliefsim::testing::Slurp;

fs::path Scratch() { return reliefsim::testing::Scratch("rs_cli_"); }

void ExpectCleanFailure(const std::string& args, const std::string& culprit) {
    fs::path d = Scratch();
    fs::path outDir = d / "out";
    Result r = RunCli(args + " --out " + outDir.string(), d);
    EXPECT_NE(r.exitCode, 0) << args;
    EXPECT_EQ(CountLines(r.err), 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(culprit), std::string::npos) << args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(outDir)) << args;
    for (const auto& e : fs::directory_iterator(d))
        EXPECT_EQ(e.path().filename().string().find("staging"), std::string::npos);
}

}  // namespace

TEST(Cli, HelpOnEveryCommand) {
    fs::path d = Scratch();
    for (const char* cmd : {"--help", "methods --help", "render --help", "summary --help",
                            "trace --help", "maps --help"}) {
        Result r = RunCli(cmd, d);
        EXPECT_EQ(r.exitCode, 0) << cmd;
        EXPECT_NE(r.out.find("Usage"), std::string::npos) << cmd;
    }
}

TEST(Cli, MethodsListsParametersWithRanges) {
    Result r = RunCli("methods", Scratch());
    EXPECT_EQ(r.exitCode, 0);
    for (const char* s : {"linear", "relief", "secant", "interval", "pom", "linear_steps",
                          "refine_steps", "early_exit", "budget", "[1, 1024]"})
        EXPECT_NE(r.out.find(s), std::string::npos) << s;
}

TEST(Cli, RenderWritesTheFiveOutputs) {
    fs::path d = Scratch();
    Result r =
        RunCli("render --map builtin:shapes:64 --method relief --size 64x48 --out " +
                   (d / "o").string(),
               d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* name :
         {"color.png", "iterations.png", "fetches.png", "record.exr", "metrics.json",
          "warp_trips.png", "warp_utilisation.png", "missed_geometry.png"})
        EXPECT_TRUE(fs::exists(d / "o" / name)) << name;
    const char* groups[] = {"quad_trips.png",     "quad_utilisation.png",
                            "group4x2_trips.png", "group4x2_utilisation.png",
                            "wave_trips.png",     "wave_utilisation.png"};
    for (const char* name : groups) EXPECT_FALSE(fs::exists(d / "o" / name)) << name;
    // --group-heatmaps adds the other lane groups' heatmaps, and says so.
    r = RunCli("render --map builtin:shapes:64 --size 64x48 --group-heatmaps --out " +
                   (d / "o").string(),
               d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* name : groups) {
        EXPECT_TRUE(fs::exists(d / "o" / name)) << name;
        EXPECT_NE(r.out.find(name), std::string::npos) << name;
    }
    // A folder where one of them goes: one error, nothing written.
    fs::create_directories(d / "p" / "wave_trips.png");
    r = RunCli("render --map builtin:shapes:64 --size 64x48 --group-heatmaps --out " +
                   (d / "p").string(),
               d);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("wave_trips.png"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(d / "p" / "color.png"));
}

TEST(Cli, TracePrintsEveryFetchOfThePixel) {
    fs::path d = Scratch();
    Result r = RunCli(
        "trace --map builtin:flat:16 --method relief --size 32x32 --view-angle 0 "
        "--set linear_steps=8 --set refine_steps=3 --pixel 16,16",
        d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // flat at depth 0.5: samples t = 0..4/8 (5), then 3 binary steps
    EXPECT_NE(r.out.find("8 fetches"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("5 coarse + 3 refine"), std::string::npos) << r.out;
    Result bad = RunCli("trace --map builtin:flat:16 --size 32x32 --pixel 40,1", d);
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.err.find("--pixel"), std::string::npos);
}

TEST(Cli, ParseErrorsAreOneLine) {
    ExpectCleanFailure("render --map builtin:shapes:32 --bogus", "--bogus");
    ExpectCleanFailure("render --map builtin:shapes:32 --view-angle abc", "--view-angle");
    Result r = RunCli("", Scratch());
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(CountLines(r.err), 1) << r.err;
}

TEST(Cli, MissingFile) {
    ExpectCleanFailure("render --map /nonexistent/height.png --method relief",
                       "height.png");
}

TEST(Cli, CorruptFile) {
    fs::path d = Scratch();
    fs::path bad = d.parent_path() / "rs_cli_corrupt.png";
    std::ofstream(bad) << "\x89PNG garbage";
    ExpectCleanFailure("render --map " + bad.string() + " --method relief",
                       "rs_cli_corrupt.png");
}

TEST(Cli, ZeroSizeImage) {
    fs::path d = Scratch();
    fs::path zero = d.parent_path() / "rs_cli_zero.tga";
    std::array<unsigned char, 18> header{};  // uncompressed grey TGA, 0x0 pixels, 8 bits
    header[2] = 3;
    header[16] = 8;
    std::ofstream(zero, std::ios::binary)
        .write(reinterpret_cast<char*>(header.data()), 18);
    ExpectCleanFailure("render --map " + zero.string() + " --method relief",
                       "rs_cli_zero.tga");
}

TEST(Cli, NanHeights) {
    fs::path d = Scratch();
    fs::path nan = d.parent_path() / "rs_cli_nan.exr";
    float px[4] = {0.1f, std::nanf(""), 0.3f, 0.4f};
    reliefsim::WriteFloatImage(nan.string(), 2, 2, 1, px);
    ExpectCleanFailure("render --map " + nan.string() + " --method relief", "NaN");
}

TEST(Cli, UnknownMethod) {
    ExpectCleanFailure("render --map builtin:shapes:32 --method cheese", "cheese");
}

TEST(Cli, NegativeSteps) {
    ExpectCleanFailure(
        "render --map builtin:shapes:32 --method relief --set linear_steps=-3",
        "linear_steps");
}

TEST(Cli, NonPositiveDepthScale) {
    ExpectCleanFailure("render --map builtin:shapes:32 --method relief --depth-scale 0",
                       "--depth-scale");
    ExpectCleanFailure("render --map builtin:shapes:32 --method relief --depth-scale -1",
                       "--depth-scale");
}

TEST(Cli, ViewAngleOutsideRange) {
    ExpectCleanFailure("render --map builtin:shapes:32 --method relief --view-angle 90",
                       "--view-angle");
    ExpectCleanFailure("render --map builtin:shapes:32 --method relief --view-angle -5",
                       "--view-angle");
}

TEST(Cli, BadSize) {
    ExpectCleanFailure("render --map builtin:shapes:32 --method relief --size 0x10",
                       "--size");
}

TEST(Cli, ExactMethodIsListedRenderedAndTraced) {
    Result m = RunCli("methods --names", Scratch());
    EXPECT_NE(m.out.find("exact\n"), std::string::npos);
    fs::path d = Scratch();
    Result r =
        RunCli("render --map builtin:shapes:64 --method exact --size 64x48 --out " +
                   (d / "o").string(),
               d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* name :
         {"color.png", "iterations.png", "fetches.png", "record.exr", "metrics.json"})
        EXPECT_TRUE(fs::exists(d / "o" / name)) << name;
    Result t = RunCli(
        "trace --map builtin:shapes:64 --method exact --size 64x48 --pixel 30,20", d);
    ASSERT_EQ(t.exitCode, 0) << t.err;
    EXPECT_NE(t.out.find("exact first hit: t "), std::string::npos) << t.out;
}

TEST(Cli, ReferenceMetricsAndTheirSwitch) {
    fs::path d = Scratch();
    Result r =
        RunCli("render --map builtin:shapes:64 --method linear --size 64x48 --out " +
                   (d / "on").string(),
               d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(d / "on" / "missed_geometry.png"));
    std::ifstream on(d / "on" / "metrics.json");
    const std::string json((std::istreambuf_iterator<char>(on)), {});
    for (const char* key :
         {"\"mse_exact_depth\"", "\"uv_error_texels_mean\"", "\"uv_error_texels_max\"",
          "\"missed_geometry_pixels\"", "\"psnr_color\"", "\"lane_utilisation_warp32\""})
        EXPECT_NE(json.find(key), std::string::npos) << key;
    Result off = RunCli(
        "render --map builtin:shapes:64 --method linear --size 64x48 --no-reference "
        "--out " +
            (d / "off").string(),
        d);
    ASSERT_EQ(off.exitCode, 0) << off.err;
    EXPECT_FALSE(fs::exists(d / "off" / "missed_geometry.png"));
}

TEST(Cli, ExactMethodRefusesWhatItCannotDo) {
    ExpectCleanFailure(
        "render --map builtin:shapes:32 --method exact --set linear_steps=8",
        "method exact takes no parameters");
    ExpectCleanFailure("render --map builtin:shapes:32 --method exact --filter nearest",
                       "--filter nearest");
    ExpectCleanFailure("render --map builtin:shapes:32 --method exact --filter min4",
                       "--filter min4");
    Result g = RunCli("glcompare --map builtin:shapes:32 --method exact", Scratch());
    EXPECT_NE(g.exitCode, 0);
    EXPECT_EQ(CountLines(g.err), 1) << g.err;
    EXPECT_NE(g.err.find("not a kernel"), std::string::npos) << g.err;
}

TEST(Cli, SweepWithABadConfigWritesNothing) {
    const fs::path d = reliefsim::testing::Scratch("rs_sweep_cfg_");
    {
        std::ofstream(d / "bad.json")
            << R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief", "set": {"linear_steps": 0}}]})";
    }
    ExpectCleanFailure("sweep --config " + (d / "bad.json").string(), "linear_steps");
    ExpectCleanFailure("sweep --config " + (d / "missing.json").string(), "no such file");
    ExpectCleanFailure("sweep --config " + d.string(), "not a regular file");
}

namespace {

std::string ReadAll(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
}

}  // namespace

TEST(Cli, ConeMapFromAFileRendersAsTheGeneratedOne) {
    // A map written by `maps` (8-bit PNG, the kernel's own encoding) and read back with
    // --cone-map gives the record the generated map gives, for a one-ratio kernel (csm:
    // u8sqrt in R) and directional ones (acm4: four sectors in RGBA; acm8: two RGBA
    // halves side by side, and eight channels in an EXR).
    fs::path d = Scratch();
    const std::string scene =
        " --map builtin:shapes:64 --size 64x48 --no-reference --quiet";
    struct Case {
        const char* method;
        const char* kind;
        const char* encoding;
    };
    for (const Case& c : {Case{"csm", "cone", "u8sqrt"}, Case{"acm4", "acm4", "u8"},
                          Case{"acm8", "acm8", "u8"}}) {
        const fs::path map = d / (std::string(c.kind) + ".png");
        Result m = RunCli("maps --map builtin:shapes:64 --kind " + std::string(c.kind) +
                              " --encoding " + c.encoding + " --out " + map.string(),
                          d);
        ASSERT_EQ(m.exitCode, 0) << m.err;
        const fs::path gen = d / (std::string(c.method) + "_gen");
        const fs::path ext = d / (std::string(c.method) + "_ext");
        Result g = RunCli("render --method " + std::string(c.method) + scene +
                              " --no-cache --out " + gen.string(),
                          d);
        ASSERT_EQ(g.exitCode, 0) << g.err;
        Result e = RunCli("render --method " + std::string(c.method) + scene +
                              " --cone-map " + map.string() + " --out " + ext.string(),
                          d);
        ASSERT_EQ(e.exitCode, 0) << e.err;
        EXPECT_TRUE(ReadAll(gen / "record.exr") == ReadAll(ext / "record.exr"))
            << c.method;
        EXPECT_TRUE(ReadAll(gen / "fetches.png") == ReadAll(ext / "fetches.png"))
            << c.method;
        if (std::string(c.kind) == "acm8") {
            const fs::path exr = d / "acm8.exr", viaExr = d / "acm8_exr";
            ASSERT_EQ(
                RunCli("maps --map builtin:shapes:64 --kind acm8 --encoding u8 --out " +
                           exr.string(),
                       d)
                    .exitCode,
                0);
            Result x = RunCli("render --method acm8" + scene + " --cone-map " +
                                  exr.string() + " --out " + viaExr.string(),
                              d);
            ASSERT_EQ(x.exitCode, 0) << x.err;
            EXPECT_TRUE(ReadAll(gen / "record.exr") == ReadAll(viaExr / "record.exr"));
            // An RGBA map of the height map's size is not two halves: one error line,
            // nothing written.
            const fs::path bad = d / "acm8_bad";
            Result b = RunCli("render --method acm8" + scene + " --cone-map " +
                                  (d / "acm4.png").string() + " --out " + bad.string(),
                              d);
            EXPECT_NE(b.exitCode, 0);
            EXPECT_EQ(CountLines(b.err), 1) << b.err;
            EXPECT_NE(b.err.find("two RGBA halves"), std::string::npos) << b.err;
            EXPECT_FALSE(fs::exists(bad));
        }
        // The same file read as linear ratios is a different map: the record differs.
        if (std::string(c.encoding) == "u8sqrt") {
            const fs::path lin = d / "lin";
            Result l =
                RunCli("render --method csm" + scene + " --cone-map " + map.string() +
                           " --cone-map-encoding u8 --out " + lin.string(),
                       d);
            ASSERT_EQ(l.exitCode, 0) << l.err;
            EXPECT_FALSE(ReadAll(gen / "record.exr") == ReadAll(lin / "record.exr"));
        }
    }
}

TEST(Cli, BadConeMapsAreOneError) {
    // The inputs live beside the scratch folder, which every ExpectCleanFailure renews.
    const fs::path d = Scratch().parent_path() / "rs_cli_cone_map_inputs";
    fs::remove_all(d);
    fs::create_directories(d);
    const fs::path small = d / "small.png";
    ASSERT_EQ(RunCli("maps --map builtin:shapes:32 --kind cone --encoding u8 --out " +
                         small.string(),
                     d)
                  .exitCode,
              0);
    const fs::path one = d / "one.png";
    ASSERT_EQ(RunCli("maps --map builtin:shapes:64 --kind cone --encoding u8 --out " +
                         one.string(),
                     d)
                  .exitCode,
              0);
    const fs::path flt = d / "cone.exr";
    ASSERT_EQ(RunCli("maps --map builtin:shapes:64 --kind cone --encoding float --out " +
                         flt.string(),
                     d)
                  .exitCode,
              0);
    const std::string base = "render --map builtin:shapes:64 --size 32x32 --quiet ";
    ExpectCleanFailure(base + "--method csm --cone-map " + small.string(), "32x32");
    ExpectCleanFailure(base + "--method csm --cone-map " + (d / "none.png").string(),
                       "none.png");
    ExpectCleanFailure(base + "--method csm --cone-map " + d.string(), "--cone-map");
    ExpectCleanFailure(base + "--method relief --cone-map " + one.string(),
                       "reads no cone map");
    ExpectCleanFailure(base + "--method acm4 --cone-map " + one.string(), "channel");
    ExpectCleanFailure(base + "--method acm8 --cone-map " + one.string(), "acm8 reads 8");
    ExpectCleanFailure(
        base + "--method csm --cone-map " + one.string() + " --cone-map-channel B",
        "channel B");
    ExpectCleanFailure(
        base + "--method csm --cone-map " + one.string() + " --cone-map-channel Q",
        "--cone-map-channel");
    ExpectCleanFailure(
        base + "--method acm4 --cone-map " + one.string() + " --cone-map-channel R",
        "--cone-map-channel");
    ExpectCleanFailure(base + "--method csm --cone-map-channel R", "--cone-map");
    ExpectCleanFailure(base + "--method csm --cone-map-encoding u8", "--cone-map");
    ExpectCleanFailure(
        base + "--method csm --cone-map " + one.string() + " --cone-encoding u8",
        "--cone-encoding");
    ExpectCleanFailure(
        base + "--method csm --cone-map " + one.string() + " --cone-map-encoding zz",
        "--cone-map-encoding");
    // Float ratios are not 8-bit codes.
    ExpectCleanFailure(
        base + "--method csm --cone-map " + flt.string() + " --cone-map-encoding u8",
        "8-bit");
    ExpectCleanFailure(
        base + "--method csm --cone-bounds bilinear --cone-map " + one.string(),
        "--cone-bounds bilinear");
    ExpectCleanFailure(base + "--method rcs --cone-bounds bilinear", "rcs");
    ExpectCleanFailure(base + "--method mcns --cone-bounds bilinear", "mcns");
    ExpectCleanFailure(base + "--method relief --cone-bounds bilinear",
                       "reads no cone map");
    ExpectCleanFailure(base + "--method exact --cone-bounds bilinear",
                       "reads no cone map");
    ExpectCleanFailure(base + "--method csm --cone-bounds bilinaer", "--cone-bounds");
    const fs::path out = d / "bil";
    ASSERT_EQ(
        RunCli(base + "--method acm8 --cone-bounds bilinear --out " + out.string(), d)
            .exitCode,
        0);
    EXPECT_NE(Slurp(out / "metrics.json").find("\"cone_bounds\": \"bilinear\""),
              std::string::npos);
    ExpectCleanFailure(base + "--method csm --texture-format r8 --cone-map " +
                           flt.string() + " --cone-map-encoding float",
                       "--cone-map-encoding float");
}

TEST(Cli, BadLightsAreOneError) {
    const std::string r = "render --map builtin:shapes:32 --method relief ";
    ExpectCleanFailure(r + "--light-dir 0,0,-1", "--light-dir");
    ExpectCleanFailure(r + "--light-dir 1,0,0", "--light-dir");
    ExpectCleanFailure(r + "--light-dir 1,2", "--light-dir");
    ExpectCleanFailure(r + "--light-dir 1,2,3,4", "--light-dir");
    ExpectCleanFailure(r + "--light-dir nan,0,1", "--light-dir");
    ExpectCleanFailure(r + "--light-dir 0,0,1 --light-angle 30", "--light-dir");
    ExpectCleanFailure(r + "--light-angle 90", "--light-angle");
    ExpectCleanFailure(r + "--light-angle -1", "--light-angle");
    ExpectCleanFailure(r + "--light-angle nan", "--light-angle");
    ExpectCleanFailure(r + "--light-azimuth inf", "--light-azimuth");
    ExpectCleanFailure(r + "--light-azimuth 1e30",
                       "--light-azimuth: must be a finite angle");
    ExpectCleanFailure(r + "--light-azimuth -2e6",
                       "--light-azimuth: must be a finite angle");
}

TEST(Cli, LightAnglesAreTheLightDirection) {
    // --light-angle 0 is the light along the normal: the same image as --light-dir 0,0,1.
    fs::path d = Scratch();
    const std::string r = "render --map builtin:shapes:32 --method relief --size 40x30 ";
    ASSERT_EQ(RunCli(r + "--light-angle 0 --out " + (d / "a").string(), d).exitCode, 0);
    ASSERT_EQ(RunCli(r + "--light-dir 0,0,2 --out " + (d / "b").string(), d).exitCode, 0);
    ASSERT_EQ(RunCli(r + "--out " + (d / "c").string(), d).exitCode, 0);
    auto read = [](const fs::path& p) {
        std::ifstream in(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    EXPECT_EQ(read(d / "a" / "color.png"), read(d / "b" / "color.png"));
    EXPECT_NE(read(d / "a" / "color.png"), read(d / "c" / "color.png"));
    EXPECT_NE(read(d / "b" / "metrics.json").find("\"light_dir\""), std::string::npos)
        << read(d / "b" / "metrics.json");
}

TEST(Cli, BadShadowsAreOneError) {
    const std::string r = "render --map builtin:shapes:32 --method relief ";
    ExpectCleanFailure(r + "--shadow penumbra", "--shadow");
    ExpectCleanFailure(r + "--shadow hard --shadow-steps 0", "--shadow-steps");
    ExpectCleanFailure(r + "--shadow hard --shadow-steps 5000", "--shadow-steps");
    ExpectCleanFailure(r + "--shadow hard --shadow-steps x", "--shadow-steps");
    ExpectCleanFailure(r + "--shadow soft --shadow-softening -1", "--shadow-softening");
    ExpectCleanFailure(r + "--shadow soft --shadow-softening nan", "--shadow-softening");
    ExpectCleanFailure(r + "--shadow soft --shadow-softening inf", "--shadow-softening");
    ExpectCleanFailure(r + "--shadow cone", "--shadow cone");  // relief has no cone map
    ExpectCleanFailure("render --map builtin:shapes:32 --method csm --shadow cone",
                       "--shadow cone");  // csm's cones are ratios, not normals
    ExpectCleanFailure(r + "--shadow hard --shadow-penumbra -2", "--shadow-penumbra");
}

TEST(Cli, ShadowsWriteTheirFetchesApart) {
    fs::path d = Scratch();
    const std::string r = "render --map builtin:shapes:64 --size 64x48 ";
    Result hard =
        RunCli(r + "--shadow hard --shadow-steps 12 --out " + (d / "h").string(), d);
    ASSERT_EQ(hard.exitCode, 0) << hard.err;
    EXPECT_NE(hard.out.find("shadow_fetches.png"), std::string::npos) << hard.out;
    EXPECT_TRUE(fs::exists(d / "h" / "shadow_fetches.png"));
    std::ifstream in(d / "h" / "metrics.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["shadow"], "hard");
    EXPECT_EQ(j["shadow_steps"], 12);
    EXPECT_GT(j["avg_shadow_fetches"].get<double>(), 1.0);
    EXPECT_LE(j["max_shadow_fetches"].get<int>(), 12);
    EXPECT_LT(j["avg_light_visibility"].get<double>(), 1.0);  // shapes casts shadows
    // Without --shadow: no light ray, no file, and the key says 0.
    Result none = RunCli(r + "--out " + (d / "n").string(), d);
    ASSERT_EQ(none.exitCode, 0) << none.err;
    EXPECT_FALSE(fs::exists(d / "n" / "shadow_fetches.png"));
    std::ifstream in2(d / "n" / "metrics.json");
    const nlohmann::json k = nlohmann::json::parse(in2);
    EXPECT_EQ(k["shadow"], "none");
    EXPECT_EQ(k["avg_shadow_fetches"].get<double>(), 0.0);
}

TEST(Cli, AnimateRendersTheDynamicDemoAndWritesTheLastFrame) {
    // The ACM paper's dynamic demo: every frame regenerates the sinusoid map, makes its
    // adaptive ACM map and renders it; per-frame times are printed and the last frame's
    // outputs written as `render` writes them, the same on every run.
    fs::path d = Scratch();
    const std::string args = "render --animate 3 --animate-size 32 --size 64x48 --out ";
    Result a = RunCli(args + (d / "a").string(), d);
    ASSERT_EQ(a.exitCode, 0) << a.err;
    for (const char* s : {"frame 0:", "frame 2:", "adaptive acm4", "frame loop",
                          "animate: 3 frames of acm4 on the 32x32 sinusoid map at 64x48"})
        EXPECT_NE(a.out.find(s), std::string::npos) << s << "\n" << a.out;
    for (const char* f :
         {"color.png", "record.exr", "metrics.json", "missed_geometry.png"})
        EXPECT_TRUE(fs::exists(d / "a" / f)) << f;
    Result b = RunCli(args + (d / "b").string() + " --quiet", d);
    ASSERT_EQ(b.exitCode, 0) << b.err;
    EXPECT_TRUE(b.out.empty()) << b.out;
    std::ifstream ra(d / "a" / "record.exr", std::ios::binary),
        rb(d / "b" / "record.exr", std::ios::binary);
    const std::string sa((std::istreambuf_iterator<char>(ra)), {}),
        sb((std::istreambuf_iterator<char>(rb)), {});
    EXPECT_FALSE(sa.empty());
    EXPECT_EQ(sa, sb);
    // The last frame moved: a one-frame run renders another map (time 0).
    Result c = RunCli("render --animate 1 --animate-size 32 --size 64x48 --quiet --out " +
                          (d / "c").string(),
                      d);
    ASSERT_EQ(c.exitCode, 0) << c.err;
    std::ifstream rc(d / "c" / "record.exr", std::ios::binary);
    const std::string sc((std::istreambuf_iterator<char>(rc)), {});
    EXPECT_NE(sa, sc);
    // Every adaptive kind's kernel animates.
    for (const char* m : {"csm", "qcsm", "acm8"}) {
        Result r = RunCli(
            "render --animate 2 --animate-size 16 --size 32x32 --no-reference "
            "--quiet --method " +
                std::string(m) + " --out " + (d / m).string(),
            d);
        EXPECT_EQ(r.exitCode, 0) << m << ": " << r.err;
    }
}

TEST(Cli, BadAnimationsAreOneError) {
    ExpectCleanFailure("render --animate 2 --method relief", "--method relief");
    ExpectCleanFailure("render --animate 2 --method rcs", "adaptive ACM");
    ExpectCleanFailure("render --animate 2 --map builtin:shapes:32", "--map");
    ExpectCleanFailure("render --animate 0", "--animate");
    ExpectCleanFailure("render --animate 2 --animate-size 1", "--animate-size 1");
    ExpectCleanFailure("render --animate 2 --adaptive-threshold 2",
                       "--adaptive-threshold");
    ExpectCleanFailure("render --animate 2 --adaptive-levels 13", "--adaptive-levels 13");
    ExpectCleanFailure("render --map builtin:shapes:32 --animate-size 64",
                       "--animate-size");
    ExpectCleanFailure("render --map builtin:shapes:32 --adaptive-levels 2",
                       "--adaptive-levels");
    ExpectCleanFailure("render --animate 2 --cone-map m.png", "--cone-map");
}

// maxmip and qdm need --wrap repeat: named with clamp, one error; left to the default
// method list of `safety`, they are left out with clamp and the others run.
TEST(Cli, HierarchicalTracersNeedRepeatWrap) {
    fs::path d = Scratch();
    for (const char* method : {"maxmip", "qdm"}) {
        Result r =
            RunCli(std::string("render --map builtin:shapes:32 --size 16x16 --method ") +
                       method + " --wrap clamp --out " + (d / method).string(),
                   d);
        EXPECT_NE(r.exitCode, 0) << method;
        EXPECT_EQ(CountLines(r.err), 1) << r.err;
        EXPECT_NE(r.err.find("--wrap repeat"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(d / method));
    }
    Result r = RunCli(
        "safety --map builtin:shapes:32 --size 16x16 --wrap clamp --angles 30 "
        "--methods linear,relief",
        d);
    EXPECT_EQ(r.exitCode, 0) << r.err;
    r = RunCli("safety --map builtin:shapes:32 --size 16x16 --wrap clamp --angles 30", d);
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.out.find("maxmip"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("relief"), std::string::npos) << r.out;
}

TEST(Cli, NumbersAreDecimal) {
    // The rules of --set and --size for every numeric option: CLI11 alone reads 0x10 as
    // 16, 010 as 8 (octal), 0x1p3 as 8 and +3 as 3.
    const std::string r = "render --map builtin:shapes:32 --method relief --size 24x16 ";
    ExpectCleanFailure(r + "--threads 0x10",
                       "--threads: \"0x10\" is not a decimal integer");
    ExpectCleanFailure(r + "--threads 0b11",
                       "--threads: \"0b11\" is not a decimal integer");
    ExpectCleanFailure(r + "--threads 1e1",
                       "--threads: \"1e1\" is not a decimal integer");
    ExpectCleanFailure(r + "--threads +3", "--threads: \"+3\" is not a decimal integer");
    ExpectCleanFailure(r + "--threads 99999999999999999999", "--threads");
    ExpectCleanFailure(r + "--azimuth 0x1p3",
                       "--azimuth: \"0x1p3\" is not a decimal number");
    ExpectCleanFailure(r + "--azimuth 1_0", "--azimuth: \"1_0\" is not a decimal number");
    ExpectCleanFailure(r + "--azimuth +30", "--azimuth: \"+30\" is not a decimal number");
    ExpectCleanFailure(r + "--azimuth -", "--azimuth");
    ExpectCleanFailure(r + "--azimuth nan", "--azimuth nan: must be a finite angle");
    ExpectCleanFailure(r + "--size +8x8", "--size");  // the same rule in its own parser
    ExpectCleanFailure("maps --map builtin:noise:16 --kind relaxed --search-steps 0x10",
                       "--search-steps: \"0x10\" is not a decimal integer");
    ExpectCleanFailure("safety --map builtin:shapes:32 --methods relief --angles 30,0x5",
                       "--angles: \"0x5\" is not a decimal number");
    // Leading zeros are decimal; exponents and points are numbers.
    fs::path d = Scratch();
    const auto run = [&](const std::string& opts, const std::string& name) {
        EXPECT_EQ(RunCli(r + opts + " --out " + (d / name).string(), d).exitCode, 0)
            << opts;
        return nlohmann::json::parse(Slurp(d / name / "metrics.json"));
    };
    EXPECT_EQ(run("--threads 010", "a")["timing"]["threads"], 10);
    EXPECT_EQ(run("--threads -0", "b")["timing"]["threads"],
              run("--threads 0", "c")["timing"]["threads"]);
    run("--azimuth 30", "e");
    run("--azimuth 30.0e0", "f");
    EXPECT_EQ(Slurp(d / "f" / "color.png"), Slurp(d / "e" / "color.png"));
    run("--azimuth 0", "g");
    EXPECT_NE(Slurp(d / "g" / "color.png"), Slurp(d / "e" / "color.png"));
}
