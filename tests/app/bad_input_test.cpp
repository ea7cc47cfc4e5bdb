// Bad input across the commands, by class: every case gets one error line naming the
// culprit, a non-zero exit, and leaves the output location exactly as it was (issue #8
// §2).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/app/cli_util.h"
#include "texture/image_io.h"

namespace fs = std::filesystem;
using reliefsim::testing::CliResult;
using reliefsim::testing::CountLines;
using reliefsim::testing::RunCli;
using reliefsim::testing::Slurp;
using reliefsim::testing::WriteBytes;

namespace {

fs::path Scratch() { return reliefsim::testing::Scratch("rs_bad_"); }

std::string Q(const fs::path& p) { return "'" + p.string() + "'"; }

/// Runs a failing command and checks the contract: non-zero exit, exactly one line on
/// stderr that contains every culprit string, nothing at `out` (when given), and no
/// temporary or staging files left in the scratch folder.
void ExpectFailure(const std::string& args, const std::vector<std::string>& culprits,
                   const fs::path& scratch, const fs::path& out = {}) {
    CliResult r = RunCli(args, scratch);
    EXPECT_NE(r.exitCode, 0) << args;
    EXPECT_EQ(CountLines(r.err), 1) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("reliefsim: error: ", 0), 0u) << args << "\n" << r.err;
    for (const std::string& c : culprits)
        EXPECT_NE(r.err.find(c), std::string::npos)
            << args << "\nexpected \"" << c << "\" in\n"
            << r.err;
    for (const char* internal : {"staging", ".tmp", "std::", "basic_string"})
        EXPECT_EQ(r.err.find(internal), std::string::npos) << args << "\n" << r.err;
    std::error_code ec;
    if (!out.empty()) {
        EXPECT_FALSE(fs::exists(out, ec)) << args;
    }
    for (const auto& e : fs::directory_iterator(scratch)) {
        const std::string name = e.path().filename().string();
        EXPECT_EQ(name.find("staging"), std::string::npos) << args << ": left " << name;
        EXPECT_EQ(name.find(".tmp"), std::string::npos) << args << ": left " << name;
    }
}

/// Render with `args` into scratch/out, expected to fail naming `culprits`.
void ExpectRenderFailure(const std::string& args,
                         const std::vector<std::string>& culprits) {
    fs::path d = reliefsim::testing::Scratch("rs_badrun_");
    fs::path out = d / "out";
    ExpectFailure("render " + args + " --size 32x32 --out " + Q(out), culprits, d, out);
}

// ---- Files that are not valid maps
// -------------------------------------------------------

uint32_t Crc32(const std::string& bytes) {
    uint32_t c = 0xffffffffu;
    for (unsigned char b : bytes) {
        c ^= b;
        for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return ~c;
}

std::string Be32(uint32_t v) {
    return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

std::string PngChunk(const std::string& type, const std::string& data) {
    return Be32(uint32_t(data.size())) + type + data + Be32(Crc32(type + data));
}

/// A PNG of ~100 bytes whose header claims width x height (8-bit grey).
std::string PngClaiming(uint32_t width, uint32_t height) {
    std::string ihdr =
        Be32(width) + Be32(height) + std::string("\x08\x00\x00\x00\x00", 5);
    // IDAT: a stored zlib block of a few zero bytes.
    std::string idat("\x78\x01\x01\x05\x00\xfa\xff\x00\x00\x00\x00\x00\x00\x05\x00\x01",
                     16);
    return std::string("\x89PNG\r\n\x1a\n", 8) + PngChunk("IHDR", ihdr) +
           PngChunk("IDAT", idat) + PngChunk("IEND", "");
}

std::string Le16(uint16_t v) { return {char(v), char(v >> 8)}; }
std::string Le32(uint32_t v) {
    return {char(v), char(v >> 8), char(v >> 16), char(v >> 24)};
}

/// A baseline little-endian TIFF, 8-bit grey, one uncompressed strip of `data`, with the
/// strip offset and byte count as given (defaults: right after the IFD, data's size).
std::string Tiff(uint32_t w, uint32_t h, const std::string& data, int64_t offset = -1,
                 int64_t count = -1) {
    struct Entry {
        uint16_t tag, type;
        uint32_t value;
    };
    const uint32_t nEntries = 10, ifdSize = 2 + nEntries * 12 + 4;
    const uint32_t dataOffset = offset < 0 ? 8 + ifdSize : uint32_t(offset);
    const Entry entries[] = {
        {256, 4, w},
        {257, 4, h},
        {258, 3, 8},
        {259, 3, 1},
        {262, 3, 1},
        {273, 4, dataOffset},
        {277, 3, 1},
        {278, 4, h},
        {279, 4, count < 0 ? uint32_t(data.size()) : uint32_t(count)},
        {284, 3, 1}};
    std::string s = std::string("II*\0", 4) + Le32(8) + Le16(uint16_t(nEntries));
    for (const Entry& e : entries)
        s += Le16(e.tag) + Le16(e.type) + Le32(1) + Le32(e.value);
    return s + Le32(0) + data;
}

std::string Ramp(size_t n) {
    std::string d(n, '\0');
    for (size_t i = 0; i < n; ++i) d[i] = char((i * 7) & 255);
    return d;
}

void WriteFloatMap(const fs::path& p, std::vector<float> values) {
    reliefsim::WriteFloatImage(p.string(), int(values.size()), 1, 1, values.data());
}

}  // namespace

TEST(BadInput, MissingDirectoryDeviceFifoAndEmptyFilesAreRefused) {
    fs::path d = Scratch();
    fs::create_directories(d / "adir.png");
    WriteBytes(d / "empty.png", "");
    ASSERT_EQ(::mkfifo((d / "pipe.png").c_str(), 0600), 0);
    fs::create_symlink("/dev/zero", d / "zero.png");
    const auto t0 = std::chrono::steady_clock::now();
    ExpectRenderFailure("--map " + Q(d / "missing.png"),
                        {"missing.png", "does not exist"});
    ExpectRenderFailure("--map " + Q(d / "adir.png"), {"adir.png", "is a directory"});
    ExpectRenderFailure("--map " + Q(d / "empty.png"), {"empty.png", "is empty"});
    ExpectRenderFailure("--map " + Q(d / "pipe.png"), {"pipe.png", "named pipe"});
    ExpectRenderFailure("--map /dev/zero", {"/dev/zero", "character device"});
    ExpectRenderFailure("--map " + Q(d / "zero.png"), {"zero.png", "character device"});
    // None of them may block or spin: all together well under a minute.
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(60));
}

TEST(BadInput, FilesThatAreNotImagesAreRefused) {
    fs::path d = Scratch();
    WriteBytes(d / "blank.null", "anything");
    WriteBytes(d / "text.png", "this is not a png at all");
    WriteBytes(d / "text.exr", "not an exr either");
    WriteBytes(d / "noext", "plain text without an extension");
    ExpectRenderFailure("--map " + Q(d / "blank.null"), {"blank.null"});
    ExpectRenderFailure("--map " + Q(d / "text.png"), {"text.png"});
    ExpectRenderFailure("--map " + Q(d / "text.exr"), {"text.exr"});
    ExpectRenderFailure("--map " + Q(d / "noext"), {"noext"});
}

TEST(BadInput, HeadersClaimingHugeSizesAreRefusedBeforeReading) {
    fs::path d = Scratch();
    WriteBytes(d / "huge.png", PngClaiming(100000, 100000));
    WriteBytes(d / "wide.png", PngClaiming(20000, 16));
    WriteBytes(d / "tall.png", PngClaiming(16, 16385));
    WriteBytes(d / "huge.tif", Tiff(70000, 70000, Ramp(64)));
    const auto t0 = std::chrono::steady_clock::now();
    ExpectRenderFailure("--map " + Q(d / "huge.png"),
                        {"huge.png", "100000x100000", "16384"});
    ExpectRenderFailure("--map " + Q(d / "wide.png"), {"wide.png", "20000x16"});
    ExpectRenderFailure("--map " + Q(d / "tall.png"), {"tall.png", "16x16385"});
    ExpectRenderFailure("--map " + Q(d / "huge.tif"), {"huge.tif", "70000x70000"});
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(30));
}

TEST(BadInput, TruncatedAndDamagedFilesAreRefusedOnOneLine) {
    fs::path d = Scratch();
    const int n = 64;
    std::vector<uint8_t> px(size_t(n) * n);
    for (size_t i = 0; i < px.size(); ++i) px[i] = uint8_t((i * 37 + i / 7) & 255);
    for (const char* ext : {"png", "tga", "exr", "tif"}) {
        const fs::path ok = d / (std::string("ok.") + ext);
        if (std::string(ext) == "exr") {
            std::vector<float> f(px.begin(), px.end());
            for (float& v : f) v /= 255.0f;
            reliefsim::WriteFloatImage(ok.string(), n, n, 1, f.data());
        } else {
            reliefsim::WriteRgb8Image(ok.string(), n, n, 1, px.data());
        }
        const std::string bytes = Slurp(ok);
        const fs::path cut = d / (std::string("cut.") + ext);
        WriteBytes(cut, bytes.substr(0, bytes.size() * 2 / 3));
        ExpectRenderFailure("--map " + Q(cut), {cut.filename().string()});
    }
    // A JPEG cut off in the middle of its scan decodes "successfully" with grey fill.
    const int big = 256;
    std::vector<uint8_t> noise(size_t(big) * big);
    uint64_t x = 88172645463325252ull;
    for (auto& v : noise) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        v = uint8_t(x);
    }
    reliefsim::WriteRgb8Image((d / "ok.jpg").string(), big, big, 1, noise.data());
    const std::string jpg = Slurp(d / "ok.jpg");
    WriteBytes(d / "cutscan.jpg", jpg.substr(0, jpg.size() * 2 / 3));
    ExpectRenderFailure("--map " + Q(d / "cutscan.jpg"), {"cutscan.jpg", "truncated"});
    // TIFFs whose strip is short, or whose data offset lies past the end of the file.
    const std::string data = Ramp(size_t(n) * n);
    WriteBytes(d / "good.tif", Tiff(n, n, data));
    WriteBytes(d / "short.tif",
               Tiff(n, n, data.substr(0, data.size() - 100), -1, int64_t(data.size())));
    WriteBytes(d / "offset.tif", Tiff(n, n, data, 100000));
    ExpectRenderFailure("--map " + Q(d / "short.tif"), {"short.tif", "truncated"});
    ExpectRenderFailure("--map " + Q(d / "offset.tif"), {"offset.tif", "truncated"});
    // The hand-made TIFF itself is fine (the cases above fail for the damage alone).
    fs::path out = d / "good_out";
    CliResult r = RunCli(
        "render --map " + Q(d / "good.tif") + " --size 16x16 --quiet --out " + Q(out), d);
    EXPECT_EQ(r.exitCode, 0) << r.err;
}

TEST(BadInput, OutOfRangeHeightsAreReportedAsStoredInTheFile) {
    fs::path d = Scratch();
    WriteFloatMap(d / "neg.exr", {0.25f, -0.5f});
    WriteFloatMap(d / "big.exr", {1.5f, 0.5f});
    WriteFloatMap(d / "nan.exr", {0.5f, std::nanf("")});
    WriteFloatMap(d / "inf.exr", {INFINITY, 0.5f});
    ExpectRenderFailure("--map " + Q(d / "neg.exr"), {"neg.exr", "-0.5", "(1, 0)"});
    ExpectRenderFailure("--map " + Q(d / "neg.exr") + " --map-stores depth", {"-0.5"});
    ExpectRenderFailure("--map " + Q(d / "big.exr"), {"big.exr", "1.5", "(0, 0)"});
    ExpectRenderFailure("--map " + Q(d / "nan.exr"), {"nan.exr", "NaN"});
    ExpectRenderFailure("--map " + Q(d / "inf.exr"), {"inf.exr", "+Inf"});
}

TEST(BadInput, MapOptionsThatDoNotApplyAreRefused) {
    fs::path d = Scratch();
    std::vector<uint8_t> grey(16, 100);
    reliefsim::WriteRgb8Image((d / "g.png").string(), 4, 4, 1, grey.data());
    ExpectRenderFailure("--map " + Q(d / "g.png") + " --map-channel B",
                        {"g.png", "channel"});
    ExpectRenderFailure("--map builtin:shapes --map-channel A", {"--map-channel"});
    ExpectRenderFailure("--map builtin:shapes --map-stores depth", {"--map-stores"});
    ExpectRenderFailure("--map " + Q(d / "g.png") + " --map-channel X",
                        {"--map-channel: \"X\" is unknown", "\"A\", \"auto\""});
    ExpectRenderFailure("--map builtin:nope", {"nope", "shapes"});
    ExpectRenderFailure("--map builtin:shapes:0", {"builtin:shapes:0"});
    ExpectRenderFailure("--map builtin:shapes:99999999999",
                        {"99999999999", "out of range"});
    ExpectRenderFailure("--map builtin:shapes:12abc", {"12abc"});
}

// ---- Numbers -------------------------------------------------------------------------

TEST(BadInput, SizesAreParsedWithRangeChecks) {
    for (const char* size :
         {"4294967808x64", "64x4294967808", "0x64", "64x0", "-5x5", "64x", "x64", "x",
          "64x64x2", "1e3x5", "16385x16", " 64x64", "64X-1", "99999999999999999999x1"}) {
        fs::path d = Scratch();
        fs::path out = d / "out";
        ExpectFailure(std::string("render --size '") + size + "' --out " + Q(out),
                      {"--size"}, d, out);
    }
}

TEST(BadInput, FramesThatDoNotFitInMemoryAreRefusedBeforeWork) {
    fs::path d = Scratch();
    fs::path out = d / "out";
    // Under a 4 GiB address-space limit an 8192x8192 frame (about 7 GiB) is refused up
    // front, naming the option, what it needs and what is available.
    const std::string bin = std::string(RS_BINARY_DIR) + "/app/reliefsim";
    const std::string cmd = "ulimit -v 4000000; exec " + bin +
                            " render --size 8192x8192 --out " + Q(out) + " >" +
                            Q(d / "o.txt") + " 2>" + Q(d / "e.txt");
    const int status = std::system(("bash -c \"" + cmd + "\"").c_str());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) != 0);
    const std::string err = Slurp(d / "e.txt");
    EXPECT_EQ(CountLines(err), 1) << err;
    for (const char* c : {"--size 8192x8192", "needs about", "available"})
        EXPECT_NE(err.find(c), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(out));
}

TEST(BadInput, PixelsAreParsedWithRangeChecks) {
    for (const char* pixel : {"99999999999,1", "1,99999999999", "64,0", "0,64", "-1,0",
                              "1", "a,b", "1,2,3", ",", "1,", ",1", "1.5,2"}) {
        fs::path d = Scratch();
        ExpectFailure(std::string("trace --size 64x64 --pixel '") + pixel + "'",
                      {"--pixel"}, d);
    }
}

TEST(BadInput, ScalesAreValidatedBeforeAnyWork) {
    for (const char* scale : {"0:inf", "nan:1", "0:nan", "5:1", "1:1", "0:", ":", ":5",
                              "a:b", "0:1e39", "-inf:0", "1:2:3"}) {
        ExpectRenderFailure(std::string("--iterations-scale '") + scale + "'",
                            {"--iterations-scale"});
        ExpectRenderFailure(std::string("--fetches-scale '") + scale + "'",
                            {"--fetches-scale"});
    }
}

TEST(BadInput, NumericOptionsOutOfRangeAreRefused) {
    ExpectRenderFailure("--threads 99999999999", {"--threads"});
    ExpectRenderFailure("--threads -1", {"--threads"});
    ExpectRenderFailure("--view-angle 90", {"--view-angle"});
    ExpectRenderFailure("--view-angle nan", {"--view-angle"});
    ExpectRenderFailure("--depth-scale 0", {"--depth-scale"});
    ExpectRenderFailure("--depth-scale inf", {"--depth-scale"});
    ExpectRenderFailure("--depth-scale 1e39", {"--depth-scale"});
    ExpectRenderFailure("--fov 180", {"--fov"});
    ExpectRenderFailure("--tiling 0", {"--tiling"});
    ExpectRenderFailure("--distance -1", {"--distance"});
    ExpectRenderFailure("--azimuth inf", {"--azimuth"});
    ExpectRenderFailure("--filter bicubic", {"--filter: \"bicubic\" is unknown",
                                             "\"nearest\", \"bilinear\", \"min4\""});
    ExpectRenderFailure("--wrap mirror",
                        {"--wrap: \"mirror\" is unknown", "\"repeat\", \"clamp\""});
    ExpectRenderFailure("--texture-format r16",
                        {"--texture-format: \"r16\" is unknown", "\"r32f\", \"r8\""});
    ExpectRenderFailure("--method frob", {"--method", "frob", "relief"});
}

TEST(BadInput, KernelSettingsAreValidated) {
    for (const char* set :
         {"linear_steps=99999999999", "linear_steps=1e400", "linear_steps=nan",
          "linear_steps=0", "linear_steps=2.5", "linear_steps=", "=5", "linear_steps",
          "frob=1", "linear_steps=0x10", "budget=-1"})
        ExpectRenderFailure(std::string("--method relief --set '") + set + "'",
                            {"--set"});
    // The orbit camera's options with the ortho camera would be ignored: refused.
    for (const char* opt :
         {"--view-angle 30", "--azimuth 10", "--distance 2", "--fov 40"})
        ExpectRenderFailure(std::string("--camera ortho ") + opt,
                            {std::string(opt).substr(0, std::string(opt).find(' ')),
                             "applies to --camera orbit"});
    // Shadow options the --shadow given does not read, and a kernel parameter given
    // twice.
    ExpectRenderFailure("--shadow-steps 5", {"--shadow-steps", "--shadow none"});
    ExpectRenderFailure("--shadow hard --shadow-softening 0.5",
                        {"--shadow-softening", "--shadow hard"});
    ExpectRenderFailure("--shadow soft --shadow-penumbra 3",
                        {"--shadow-penumbra", "--shadow soft"});
    ExpectRenderFailure("--method relief --set budget=3 --set budget=4",
                        {"--set budget", "given twice"});
    // The map cache of a method that generates no cone map, or with the map given.
    ExpectRenderFailure("--method relief --no-cache", {"--no-cache", "--method relief"});
    ExpectRenderFailure("--method exact --cache-dir c",
                        {"--cache-dir", "--method exact"});
    ExpectRenderFailure("--method maxmip --no-cache", {"--no-cache", "--method maxmip"});
    ExpectRenderFailure("--method csm --cone-map m.png --no-cache",
                        {"--no-cache", "--cone-map gives the map"});
    // safety varies the orbit camera's view angle: the ortho camera would repeat one
    // view.
    ExpectFailure("safety --map builtin:shapes:16 --size 8x8 --camera ortho",
                  {"--camera ortho", "view angle"}, Scratch());
    // safety takes its methods as --methods: the error names that option.
    const fs::path d = Scratch();
    ExpectFailure("safety --map builtin:shapes:16 --size 8x8 --methods relief,frob",
                  {"--methods \"frob\"", "unknown"}, d);
    // ... and its angles as --angles; --method and --view-angle would be ignored.
    for (const auto& [args, culprits] :
         std::vector<std::pair<std::string, std::vector<std::string>>>{
             {"--methods relief --method csm", {"--method:", "--methods"}},
             {"--view-angle 10", {"--view-angle", "--angles"}},
             {"--angles 20,95", {"--angles 95"}},
             {"--methods relief --ao cone", {"--ao cone", "--methods relief"}}})
        ExpectFailure("safety --map builtin:shapes:16 --size 8x8 " + args, culprits, d);
    // The map cache where no method profiled generates a cone map would be ignored.
    ExpectFailure(
        "safety --map builtin:shapes:16 --size 8x8 --methods relief,linear "
        "--no-cache",
        {"--no-cache", "none of --methods relief,linear"}, d);
    // Its settings are checked with the methods profiled, not render's default method:
    // cns reads the cone-normal map that the cone shadow and AO need.
    const CliResult ok = RunCli(
        "safety --map builtin:shapes:16 --size 8x8 --angles 30 --methods cns --shadow "
        "cone --ao cone --no-cache",
        d);
    EXPECT_EQ(ok.exitCode, 0) << ok.err;
    EXPECT_NE(ok.out.find("| cns |"), std::string::npos) << ok.out;
}

TEST(BadInput, MapsOptionsThatDoNotApplyAreRefused) {
    struct Case {
        const char* args;
        const char* culprit;
    };
    const Case cases[] = {
        {"--kind relaxed --adaptive", "--adaptive"},
        {"--kind stacked --adaptive", "--adaptive"},
        {"--kind minmip --external x.png", "--external"},
        {"--kind maxmip --encoding u8", "--encoding"},
        {"--kind minmip --safety", "--safety"},
        {"--animate 3 --out m.exr", "--out"},
        {"--animate 3 --kind relaxed", "--animate"},
        {"--animate 3 --cache-dir c", "--cache-dir"},
        {"--kind cone --search-steps 64", "--search-steps"},
        {"--kind cone-normal --search-steps 64", "--search-steps"},
        {"--kind cone --stacked-count 3", "--stacked-count"},
        {"--kind cone --threshold 0.3", "--threshold"},
        {"--kind acm4 --levels 2", "--levels"},
        {"--external-channel B", "--external-channel"},
        {"--kind acm8 --external x.png", "acm8 has eight channels"},
        {"--kind quad --external x.png --external-channel B", "--external-channel"},
        {"--kind cone --external x.png --external-channel all", "--external-channel"},
        {"--kind cone --external x.png --cache-dir c", "--cache-dir"},
        {"--kind relaxed --relaxed", "--relaxed"},
        {"--kind frob", "--kind: \"frob\""},
        {"--encoding u12", "--encoding: \"u12\""},
        {"--external-channel X", "--external-channel: \"X\""},
        {"--search-steps 0 --kind relaxed", "--search-steps"},
        {"--search-steps 99999999999 --kind relaxed", "--search-steps"},
        {"--animate -1", "--animate"},
        {"--out m.jpg", "--out"},
        {"--encoding u16 --out m.png", "--encoding u16"},
        {"--encoding float --out m.png", "--encoding float"},
    };
    for (const Case& c : cases) {
        fs::path d = Scratch();
        ExpectFailure(std::string("maps --map builtin:shapes:16 ") + c.args, {c.culprit},
                      d);
        EXPECT_FALSE(fs::exists(d / "m.exr")) << c.args;
        EXPECT_FALSE(fs::exists(d / "m.png")) << c.args;
        EXPECT_FALSE(fs::exists(d / "c")) << c.args;
    }
    // Without --encoding a PNG stores u8 codes, and its statistics say so.
    const fs::path d = Scratch();
    ASSERT_EQ(RunCli("maps --map builtin:shapes:16 --out " + Q(d / "m.png"), d).exitCode,
              0);
    EXPECT_NE(Slurp(d / "m.stats.json").find("\"encoding\": \"u8\""), std::string::npos)
        << Slurp(d / "m.stats.json");
}

TEST(BadInput, OptionsOfOtherCommandsAreNotAccepted) {
    fs::path d = Scratch();
    // trace writes no heatmap, so it takes no heatmap scale.
    ExpectFailure("trace --pixel 1,1 --iterations-scale 0:10", {"--iterations-scale"}, d);
    ExpectFailure("summary", {"metrics"}, d);
}

TEST(BadInput, OutputLocationsThatCannotHoldTheOutputsAreRefusedBeforeWork) {
    fs::path d = Scratch();
    WriteBytes(d / "file", "x");
    ExpectFailure("render --size 8x8 --out " + Q(d / "file"),
                  {"--out", "not a directory"}, d);
    ExpectFailure("render --size 8x8 --out " + Q(d / "file" / "sub"), {"--out"}, d);
    ExpectFailure("render --size 8x8 --out " + Q(d / std::string(300, 'n')), {"--out"}, d,
                  d / std::string(300, 'n'));
    fs::create_directories(d / "res" / "metrics.json");
    WriteBytes(d / "res" / "mine.txt", "user data");
    ExpectFailure("render --size 8x8 --out " + Q(d / "res"), {"--out", "metrics.json"},
                  d);
    EXPECT_EQ(Slurp(d / "res" / "mine.txt"), "user data");
    EXPECT_FALSE(fs::exists(d / "res" / "color.png"));
    ExpectFailure("maps --map builtin:shapes:16 --out " + Q(d / "file" / "m.exr"),
                  {"--out"}, d);
    ExpectFailure("maps --map builtin:shapes:16 --out " + Q(d / "res"), {"--out"}, d);
    // An empty path given explicitly (an unset shell variable) is refused, not taken as
    // "no output", for every output or input path option of maps and render.
    ExpectFailure("render --size 8x8 --out ''", {"--out", "empty"}, d);
    ExpectFailure("maps --map builtin:shapes:16 --out ''", {"--out", "empty"}, d);
    ExpectFailure("maps --map builtin:shapes:16 --kind minmip --out ''",
                  {"--out", "empty"}, d);
    ExpectFailure(
        "maps --map builtin:shapes:16 --out " + Q(d / "e.exr") + " --cache-dir ''",
        {"--cache-dir", "empty"}, d, d / "e.exr");
    ExpectFailure(
        "maps --map builtin:shapes:16 --out " + Q(d / "e.exr") + " --external ''",
        {"--external", "empty"}, d, d / "e.exr");
    ExpectFailure("maps --map '' --out " + Q(d / "e.exr"), {"--map", "empty"}, d,
                  d / "e.exr");
    for (const char* opt : {"--cone-map", "--view-dir", "--light-dir", "--cone-encoding",
                            "--cache-dir", "--method", "--size"})
        ExpectFailure("render --out " + Q(d / "r") + " " + opt + " ''", {opt, "empty"}, d,
                      d / "r");
    ExpectFailure("maps --map builtin:shapes:16 --out=", {"--out", "empty"}, d);
    ExpectFailure("render --out " + Q(d / "r") + " --cone-map=", {"--cone-map", "empty"},
                  d, d / "r");
    // Every option that takes a value, whatever its type and checks, in both forms, and
    // every command; a flag given "=" with nothing (CLI11 would set it).
    for (const char* opt : {"--threads", "--view-angle", "--set", "--lanes", "--out"})
        for (const char* form : {" ''", "="})
            ExpectFailure("render --size 8x8 --out " + Q(d / "r") + " " + opt + form,
                          {opt, "empty value"}, d, d / "r");
    ExpectFailure("render --size 8x8 --out " + Q(d / "r") + " --quiet=",
                  {"--quiet", "empty value"}, d, d / "r");
    ExpectFailure("safety --map builtin:shapes:8 --angles=", {"--angles", "empty value"},
                  d);
    ExpectFailure("merge --out= " + Q(d / "a"), {"--out", "empty value"}, d);
    // The joined form with a value still works.
    const CliResult ok =
        RunCli("maps --map=builtin:shapes:8 --kind=cone --out=" + Q(d / "j.exr"), d);
    EXPECT_EQ(ok.exitCode, 0) << ok.err;
    EXPECT_TRUE(fs::exists(d / "j.exr"));
}

TEST(BadInput, SummaryNamesTheFileAndRejectsWrongValues) {
    fs::path d = Scratch();
    fs::create_directories(d / "dir");
    WriteBytes(
        d / "neg.json",
        R"({"method":"relief","avg_iterations":1,"avg_fetches":1,"max_fetches":-1,"mse_paper":0})");
    WriteBytes(
        d / "str.json",
        R"({"method":"relief","avg_iterations":"x","avg_fetches":1,"max_fetches":1,"mse_paper":0})");
    WriteBytes(d / "nojson.json", "{not json");
    WriteBytes(d / "array.json", "[1,2]");
    WriteBytes(d / "partial.json", R"({"method":"relief"})");
    ExpectFailure("summary " + Q(d / "dir"), {"dir", "directory"}, d);
    ExpectFailure("summary " + Q(d / "missing.json"), {"missing.json", "does not exist"},
                  d);
    ExpectFailure("summary " + Q(d / "neg.json"), {"neg.json", "max_fetches", "-1"}, d);
    ExpectFailure("summary " + Q(d / "str.json"), {"str.json", "avg_iterations"}, d);
    ExpectFailure("summary " + Q(d / "nojson.json"), {"nojson.json", "not JSON"}, d);
    ExpectFailure("summary " + Q(d / "array.json"), {"array.json"}, d);
    ExpectFailure("summary " + Q(d / "partial.json"), {"partial.json", "avg_iterations"},
                  d);
    ExpectFailure("summary /dev/zero", {"/dev/zero", "not a regular file"}, d);
}

TEST(BadInput, UnknownCommandIsNamedWithTheCommandsThatExist) {
    fs::path d = Scratch();
    ExpectFailure("frobnicate",
                  {"\"frobnicate\"", "unknown command", "render", "maps", "trace"}, d);
    ExpectFailure("frobnicate --help", {"frobnicate"}, d);
}
