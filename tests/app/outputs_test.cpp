// Outputs of `render` and `maps`: all or nothing (a failed run leaves the output location
// exactly as it was), folders as the umask says, byte-identical reruns and thread counts.
#include "render/outputs.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "core/error.h"
#include "maps/mip_pyramid.h"
#include "tests/app/cli_util.h"
#include "tests/common/test_files.h"
#include "texture/procedural.h"

using namespace reliefsim;
namespace fs = std::filesystem;
using reliefsim::testing::ExpectNoLeftovers;
using reliefsim::testing::Snapshot;

namespace {

using reliefsim::testing::CountLines;
using reliefsim::testing::RunCli;
using reliefsim::testing::Slurp;
using Result = reliefsim::testing::CliResult;

const char* const kRenderFiles[] = {"color.png", "iterations.png", "fetches.png",
                                    "record.exr", "metrics.json"};
const std::string kScene = "--map builtin:shapes:64 --size 40x28 --quiet ";

fs::path Scratch() { return reliefsim::testing::Scratch("rs_outputs_"); }

std::string Bytes(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

/// Runs `PREFIX; reliefsim ARGS` in a shell (for umask and taskset), capturing the output
/// like RunCli.
Result RunShell(const std::string& prefix, const std::string& args,
                const fs::path& scratch) {
    const std::string bin = std::string(RS_BINARY_DIR) + "/app/reliefsim";
    const auto out = scratch / "stdout.txt", err = scratch / "stderr.txt";
    const std::string cmd =
        prefix + " " + bin + " " + args + " >" + out.string() + " 2>" + err.string();
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, Slurp(out), Slurp(err)};
}

/// A failed run: non-zero exit, one error line that names `culprit`.
void ExpectOneLineFailure(const Result& r, const std::string& culprit) {
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(CountLines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(culprit), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find(".rs-"), std::string::npos) << r.err;  // never a temporary
}

mode_t ModeOf(const fs::path& p) {
    struct stat st;
    EXPECT_EQ(::stat(p.c_str(), &st), 0) << p;
    return st.st_mode & 07777;
}

RenderSettings SmallSettings(const std::string& method) {
    RenderSettings s;
    s.method = method;
    s.width = 40;
    s.height = 28;
    return s;
}

nlohmann::json WithoutTiming(const std::string& text) {
    nlohmann::json j = nlohmann::json::parse(text);
    j.erase("timing");
    return j;
}

}  // namespace

TEST(RenderOutputs, FolderInPlaceOfEachOutputChangesNothing) {
    for (const char* blocked : kRenderFiles) {
        const fs::path d = Scratch();
        const fs::path out = d / "o";
        ASSERT_EQ(RunCli("render " + kScene + "--method linear --out " + out.string(), d)
                      .exitCode,
                  0);
        std::ofstream(out / "notes.txt") << "the user's own file";
        fs::remove(out / blocked);
        fs::create_directory(out / blocked);
        std::ofstream(out / blocked / "inside.txt") << "kept";
        const auto before = Snapshot(out);
        const Result r =
            RunCli("render " + kScene + "--method relief --out " + out.string(), d);
        ExpectOneLineFailure(r, blocked);
        EXPECT_EQ(Snapshot(out), before) << blocked;
        ExpectNoLeftovers(d);
    }
}

TEST(RenderOutputs, LibraryRefusesAFolderInPlaceOfEachOutput) {
    // The same through WriteRenderOutputs, below the command line's early checks: the
    // all-or-nothing commit itself refuses, before the first file is replaced.
    const DepthField field = MakeBuiltinMap("builtin:shapes:32");
    const RenderSettings a = SmallSettings("linear"), b = SmallSettings("relief");
    const RenderOutput outA = Render(field, a), outB = Render(field, b);
    for (const char* blocked : kRenderFiles) {
        const fs::path d = Scratch();
        const fs::path out = d / "o";
        WriteRenderOutputs(out.string(), outA, a, field);
        std::ofstream(out / "notes.txt") << "mine";
        fs::remove(out / blocked);
        fs::create_directory(out / blocked);
        const auto before = Snapshot(out);
        try {
            WriteRenderOutputs(out.string(), outB, b, field);
            ADD_FAILURE() << "expected Error for " << blocked;
        } catch (const Error& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find((out / blocked).string() + "\": is a folder"),
                      std::string::npos)
                << msg;
            EXPECT_EQ(msg.find(".rs-"), std::string::npos) << msg;
        }
        EXPECT_EQ(Snapshot(out), before) << blocked;
        ExpectNoLeftovers(d);
    }
}

TEST(RenderOutputs, RerunReplacesOutputsAndKeepsOtherFiles) {
    const fs::path d = Scratch();
    const fs::path out = d / "o";
    ASSERT_EQ(
        RunCli("render " + kScene + "--method linear --out " + out.string(), d).exitCode,
        0);
    std::ofstream(out / "notes.txt") << "mine";
    const std::string oldMetrics = Bytes(out / "metrics.json");
    const Result r =
        RunCli("render " + kScene + "--method relief --out " + out.string(), d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(Bytes(out / "metrics.json"), oldMetrics);
    EXPECT_NE(Bytes(out / "metrics.json").find("\"relief\""), std::string::npos);
    EXPECT_EQ(Bytes(out / "notes.txt"), "mine");
    size_t n = 0;
    for (const auto& e : fs::directory_iterator(out)) n += e.is_regular_file() ? 1 : 0;
    EXPECT_EQ(n,
              9u);  // eight outputs (missed_geometry.png with the reference) and the
                    // user's file
    ExpectNoLeftovers(d);
}

TEST(RenderOutputs, ParentThatIsAFileLeavesNothing) {
    const fs::path d = Scratch();
    std::ofstream(d / "file") << "x";
    fs::create_directory(d / "user");
    const auto before = Snapshot(d / "user");
    const Result r =
        RunCli("render " + kScene + "--out " + (d / "file" / "sub").string(), d);
    ExpectOneLineFailure(r, (d / "file").string());
    EXPECT_EQ(Bytes(d / "file"), "x");
    EXPECT_EQ(Snapshot(d / "user"), before);
    ExpectNoLeftovers(d);
}

TEST(RenderOutputs, TooLongNameLeavesNoFolder) {
    const fs::path d = Scratch();
    const std::string longName(300, 'n');
    const Result r =
        RunCli("render " + kScene + "--out " + (d / "new" / longName).string(), d);
    ExpectOneLineFailure(r, "300");
    EXPECT_FALSE(fs::exists(d / "new"));
    // The library refuses it as well, before creating anything.
    const DepthField field = MakeBuiltinMap("builtin:flat:8");
    const RenderSettings s = SmallSettings("linear");
    const RenderOutput out = Render(field, s);
    EXPECT_THROW(WriteRenderOutputs((d / "new" / longName).string(), out, s, field),
                 Error);
    EXPECT_THROW(
        WriteRenderOutputs((d / "new" / "a" / longName / "b").string(), out, s, field),
        Error);
    EXPECT_FALSE(fs::exists(d / "new"));
    ExpectNoLeftovers(d);
}

TEST(RenderOutputs, FoldersAndFilesFollowTheUmask) {
    const fs::path d = Scratch();
    for (const auto& [mask, dirMode, fileMode] :
         {std::tuple{"022", 0755, 0644}, std::tuple{"077", 0700, 0600}}) {
        const fs::path top = d / ("u" + std::string(mask));
        const Result r =
            RunShell(std::string("umask ") + mask + ";",
                     "render " + kScene + "--out " + (top / "a" / "b").string(), d);
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_EQ(ModeOf(top), mode_t(dirMode)) << mask;
        EXPECT_EQ(ModeOf(top / "a"), mode_t(dirMode)) << mask;
        EXPECT_EQ(ModeOf(top / "a" / "b"), mode_t(dirMode)) << mask;
        for (const char* name : kRenderFiles)
            EXPECT_EQ(ModeOf(top / "a" / "b" / name), mode_t(fileMode))
                << mask << " " << name;
    }
    ExpectNoLeftovers(d);
}

TEST(RenderOutputs, ByteIdenticalForOneAndTwoThreadsAndReruns) {
    const fs::path d = Scratch();
    const std::string scene =
        "render --map builtin:shapes:128 --size 75x49 --method secant "
        "--view-angle 55 --azimuth 20 --quiet ";
    ASSERT_EQ(RunCli(scene + "--threads 1 --out " + (d / "t1").string(), d).exitCode, 0);
    // EXR time stamps have one-second resolution: make sure a second passes.
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    ASSERT_EQ(RunCli(scene + "--threads 2 --out " + (d / "t2").string(), d).exitCode, 0);
    ASSERT_EQ(RunCli(scene + "--threads 2 --out " + (d / "t2again").string(), d).exitCode,
              0);
    for (const char* again : {"t2", "t2again"}) {
        for (const char* name :
             {"color.png", "iterations.png", "fetches.png", "record.exr"})
            EXPECT_EQ(Bytes(d / "t1" / name), Bytes(d / again / name))
                << again << " " << name;
        EXPECT_EQ(WithoutTiming(Bytes(d / "t1" / "metrics.json")),
                  WithoutTiming(Bytes(d / again / "metrics.json")))
            << again;
    }
}

TEST(MapsOutputs, StatisticsBlockedByAFolderKeepTheMap) {
    const fs::path d = Scratch();
    const fs::path out = d / "o";
    fs::create_directory(out);
    const std::string m = (out / "m.exr").string();
    ASSERT_EQ(RunCli("maps --map builtin:shapes:16 --kind cone --out " + m, d).exitCode,
              0);
    fs::remove(out / "m.stats.json");
    fs::create_directory(out / "m.stats.json");
    std::ofstream(out / "notes.txt") << "mine";
    const auto before = Snapshot(out);
    const Result r = RunCli("maps --map builtin:shapes:16 --kind acm4 --out " + m, d);
    ExpectOneLineFailure(r, "m.stats.json");
    EXPECT_EQ(Snapshot(out), before);
    ExpectNoLeftovers(d);
}

TEST(MapsOutputs, MapBlockedByAFolderKeepsTheStatistics) {
    const fs::path d = Scratch();
    const fs::path out = d / "o";
    fs::create_directory(out);
    fs::create_directory(out / "m.png");
    std::ofstream(out / "m.stats.json") << "{}";
    const auto before = Snapshot(out);
    const Result r = RunCli(
        "maps --map builtin:shapes:16 --kind cone --out " + (out / "m.png").string(), d);
    ExpectOneLineFailure(r, "m.png");
    EXPECT_EQ(Snapshot(out), before);
    ExpectNoLeftovers(d);
}

TEST(MapsOutputs, MipPyramidIsOneFileWithEveryLevel) {
    const fs::path d = Scratch();
    for (const char* kind : {"minmip", "maxmip"}) {
        const fs::path m = d / (std::string(kind) + ".exr");
        const Result r = RunCli(std::string("maps --map builtin:bumps:13 --kind ") +
                                    kind + " --out " + m.string(),
                                d);
        ASSERT_EQ(r.exitCode, 0) << r.err;
        const DepthField hf = MakeBuiltinMap("builtin:bumps:13");
        const auto want = BuildMipPyramid(
            hf.depth, hf.width, hf.height, 1,
            std::string(kind) == "maxmip" ? MipReduce::Min : MipReduce::Max);
        const auto got = ReadMipPyramidFile(m.string());
        ASSERT_EQ(got.size(), want.size()) << kind;  // 13, 7, 4, 2, 1
        for (size_t l = 0; l < want.size(); ++l) {
            EXPECT_EQ(got[l].width, want[l].width);
            EXPECT_EQ(got[l].height, want[l].height);
            EXPECT_EQ(got[l].values, want[l].values) << kind << " level " << l;
        }
    }
    for (const auto& e : fs::directory_iterator(d)) {  // no per-level files
        const std::string name = e.path().filename().string();
        EXPECT_EQ(name.find("_L"), std::string::npos) << name;
    }
}

TEST(MapsOutputs, MipPyramidToPngIsRefused) {
    const fs::path d = Scratch();
    const Result r = RunCli(
        "maps --map builtin:shapes:16 --kind minmip --out " + (d / "m.png").string(), d);
    ExpectOneLineFailure(r, "MIP");
    EXPECT_FALSE(fs::exists(d / "m.png"));
    ExpectNoLeftovers(d);
}

TEST(MapsOutputs, BlockedMipPyramidLeavesNothing) {
    const fs::path d = Scratch();
    fs::create_directory(d / "o");
    fs::create_directory(d / "o" / "m.exr");
    std::ofstream(d / "file") << "x";
    const auto before = Snapshot(d / "o");
    ExpectOneLineFailure(RunCli("maps --map builtin:shapes:16 --kind maxmip --out " +
                                    (d / "o" / "m.exr").string(),
                                d),
                         "m.exr");
    ExpectOneLineFailure(RunCli("maps --map builtin:shapes:16 --kind maxmip --out " +
                                    (d / "file" / "m.exr").string(),
                                d),
                         "file");
    EXPECT_EQ(Snapshot(d / "o"), before);
    EXPECT_EQ(Bytes(d / "file"), "x");
    ExpectNoLeftovers(d);
}

TEST(MapsOutputs, ByteIdenticalAcrossThreadCountsAndReruns) {
    const fs::path d = Scratch();
    const std::vector<std::string> runs = {"--kind acm4 --encoding u8 --out {}/acm4.png",
                                           "--kind relaxed --search-steps 32 "
                                           "--out {}/relaxed.exr",
                                           "--kind minmip --out {}/minmip.exr"};
    // One core (TBB follows the affinity mask) and all of them, a second apart.
    for (const char* where : {"one", "all"}) fs::create_directory(d / where);
    for (const auto& run : runs) {
        auto args = [&](const char* where) {
            std::string a = run;
            a.replace(a.find("{}"), 2, (d / where).string());
            return "maps --map builtin:shapes:24 " + a;
        };
        ASSERT_EQ(RunShell("taskset -c 0", args("one"), d).exitCode, 0) << run;
        std::this_thread::sleep_for(std::chrono::milliseconds(1100));
        ASSERT_EQ(RunShell("", args("all"), d).exitCode, 0) << run;
    }
    size_t compared = 0;
    for (const auto& e : fs::directory_iterator(d / "one")) {
        const fs::path name = e.path().filename();
        EXPECT_EQ(Bytes(e.path()), Bytes(d / "all" / name)) << name;
        ++compared;
    }
    EXPECT_EQ(compared, 5u);  // two maps with their statistics, one pyramid
}
