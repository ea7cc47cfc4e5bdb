// `reliefsim sweep` / `merge` (app/sweep.h): the cross product, resumption, shards.
#include "app/sweep.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "tests/app/cli_util.h"

namespace fs = std::filesystem;
using namespace reliefsim;

namespace {

const char* kConfig = R"({
  "size": "48x32", "threads": 1,
  "maps": ["builtin:shapes:32", {"map": "builtin:noise:32"}],
  "views": [{"view_angle": 45}, {"view_angle": 70, "azimuth": 30}],
  "methods": [{"method": "relief", "set": {"linear_steps": [8, 16], "refine_steps": [0, 2]}},
              {"method": "secant"}]
})";

std::string Read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// results.csv without its timing columns (their values differ run to run).
std::string WithoutTiming(const std::string& csv) {
    std::vector<std::vector<std::string>> rows;
    std::stringstream in(csv);
    std::string line;
    while (std::getline(in, line)) {
        std::vector<std::string> cells;
        std::stringstream l(line);
        std::string c;
        while (std::getline(l, c, ',')) cells.push_back(c);
        rows.push_back(cells);
    }
    std::string out;
    for (const auto& r : rows) {
        for (size_t i = 0; i < r.size(); ++i)
            if (rows[0][i].rfind("timing.", 0) != 0) out += r[i] + ",";
        out += "\n";
    }
    return out;
}

fs::path Scratch() { return reliefsim::testing::Scratch("rs_sweep_"); }

void ExpectConfigError(const std::string& text, const std::string& culprit) {
    try {
        ParseSweepConfig(text, "cfg");
        ADD_FAILURE() << "accepted: " << text;
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(culprit), std::string::npos) << e.what();
    }
}

}  // namespace

TEST(Sweep, NamedParameterValuesCrossAsNames) {
    const auto configs = ParseSweepConfig(R"({
      "maps": ["builtin:shapes:32"],
      "methods": [{"method": "csm", "set": {"refine": ["none", "binary", "interval"],
                                            "refine_steps": [3, 5]}}]})",
                                          "cfg");
    ASSERT_EQ(configs.size(), 6u);
    EXPECT_EQ(configs[3].settings.set,
              (std::vector<std::string>{"refine=binary", "refine_steps=5"}));
    EXPECT_EQ(configs[3].columns["set.refine"], "binary");
    EXPECT_EQ(configs[3].columns["set.refine_steps"], 5);
    // A view may set the light.
    const auto lit = ParseSweepConfig(R"({"maps": ["builtin:shapes:32"],
      "views": [{"light_dir": [1, 0, 1]}], "methods": [{"method": "relief"}]})",
                                      "cfg");
    ASSERT_EQ(lit.size(), 1u);
    EXPECT_EQ(lit[0].settings.lightDir.x, 1.0f);
    EXPECT_EQ(lit[0].settings.lightDir.z, 1.0f);
    ExpectConfigError(R"({"maps": ["builtin:shapes:32"],
      "views": [{"light_dir": [1, 0, -1]}], "methods": [{"method": "relief"}]})",
                      "light_dir");
    // A name the parameter does not have is the configuration's error, with the choices.
    ExpectConfigError(R"({"maps": ["builtin:shapes:32"],
      "methods": [{"method": "csm", "set": {"refine": ["bisect"]}}]})",
                      "none, binary, interval, secant, pom");
    ExpectConfigError(R"({"maps": ["builtin:shapes:32"],
      "methods": [{"method": "csm", "set": {"refine": [true]}}]})",
                      "refine");
}

TEST(Sweep, CrossesMapsViewsMethodsAndSetLists) {
    const auto configs = ParseSweepConfig(kConfig, "cfg");
    ASSERT_EQ(configs.size(), 2u * 2u * (4u + 1u));
    EXPECT_EQ(configs[0].settings.set,
              (std::vector<std::string>{"linear_steps=8", "refine_steps=0"}));
    EXPECT_EQ(configs[1].settings.set,
              (std::vector<std::string>{"linear_steps=8", "refine_steps=2"}));
    EXPECT_EQ(configs[3].settings.set,
              (std::vector<std::string>{"linear_steps=16", "refine_steps=2"}));
    EXPECT_EQ(configs[4].settings.method, "secant");
    EXPECT_EQ(configs[5].settings.viewAngle, 70.0f);
    EXPECT_EQ(configs[5].settings.azimuth, 30.0f);
    EXPECT_EQ(configs[10].map, "builtin:noise:32");
    EXPECT_EQ(configs[19].index, 19);
    EXPECT_EQ(configs[0].settings.width, 48);
}

TEST(Sweep, BadConfigurationsNameTheCulprit) {
    // {configuration, what its error names}
    const std::pair<std::string, std::string> kBad[] = {
        {"{", "not valid JSON"},
        // Camera keys that the view's camera would ignore, as render refuses them.
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief"}], "views": [{"camera": "ortho", "view_angle": 30}]})",
         "\"views\" [0]: view_angle: applies to camera orbit"},
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief"}], "fov": 40, "views": [{"camera": "ortho"}]})",
         "\"views\" [0]: fov: applies to camera orbit"},
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief"}], "views": [{"view_dir": [0, 0, -1]}]})",
         "view_dir: applies to camera ortho, not camera orbit"},
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief"}], "shadow_steps": 8})",
         "shadow_steps: applies to shadow hard or cone, not shadow none"},
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief"}], "views": [{"shadow": "hard", "shadow_softening": 0.5}]})",
         "shadow_softening: applies to shadow soft, not shadow hard"},
        // A number beyond double's range is a parse error of its own kind in the JSON
        // library.
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief", "set": {"linear_steps": 1e400}}]})",
         "not valid JSON"},
        {"[1]", "expected a JSON object"},
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief"}], "colour": 1})",
         "\"colour\": unknown key; valid: size, maps"},
        {R"({"methods": [{"method": "relief"}]})", "no \"maps\""},
        {R"({"maps": ["builtin:shapes"]})", "no \"methods\""},
        {R"({"maps": [], "methods": [{"method": "relief"}]})", "non-empty list"},
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "cheese"}]})", "cheese"},
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief", "set": {"steps": 3}}]})",
         "steps"},
        {R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief", "set": {"linear_steps": []}}]})",
         "empty list"},
        {R"({"maps": ["builtin:shapes"], "views": [{"view_angle": 95}], "methods": [{"method": "relief"}]})",
         "view_angle 95"},
        {R"({"maps": ["builtin:shapes"], "views": [{"filter": "bicubic"}], "methods": [{"method": "relief"}]})",
         "\"bicubic\" is unknown"},
        {R"({"maps": ["builtin:shapes"], "views": [{"camera": "ortho", "view_dir": [0, 0, 1]}], "methods": [{"method": "relief"}]})",
         "Z must be < 0"},
        {R"({"maps": ["builtin:shapes"], "views": [{"camera": "fisheye"}], "methods": [{"method": "relief"}]})",
         "\"fisheye\" is unknown"},
        {R"({"maps": [{"map": "x.png", "map_channel": "Q"}], "methods": [{"method": "relief"}]})",
         "\"Q\" is unknown"},
        {R"({"size": "0x3", "maps": ["builtin:shapes"], "methods": [{"method": "relief"}]})",
         "size"},
        {R"({"maps": ["builtin:shapes"], "cone_bounds": "exact", "methods": [{"method": "csm"}]})",
         "\"exact\" is unknown"},
        {R"({"maps": ["builtin:shapes"], "cone_bounds": "bilinear", "methods": [{"method": "rcs"}]})",
         "no bilinear-bound variant"},
    };
    for (const auto& [config, culprit] : kBad) {
        SCOPED_TRACE(config);
        ExpectConfigError(config, culprit);
    }
    EXPECT_NO_THROW(ParseSweepConfig(
        R"({"maps": ["builtin:shapes"], "views": [{"cone_bounds": "bilinear"}, {}], "methods": [{"method": "acm4"}]})",
        "cfg"));
}

TEST(Sweep, RefusesHugeCrossProductsAndOutOfRangeIntegers) {
    std::string budgets;  // 10 x 10 x 2 x 5001 crossed values: over the cap
    for (int b = 1; b <= 5001; ++b) budgets += (b > 1 ? "," : "") + std::to_string(b);
    ExpectConfigError(
        R"({"maps": ["builtin:shapes"], "methods": [{"method": "relief", )"
        R"("set": {"linear_steps": [1,2,3,4,5,6,7,8,9,10], "refine_steps": )"
        R"([0,1,2,3,4,5,6,7,8,9], "early_exit": [0,1], "budget": [)" +
            budgets + "]}}]}",
        "more than 1000000 configurations");
    ExpectConfigError(
        R"({"threads": 1e20, "maps": ["builtin:shapes"], "methods": [{"method": "relief"}]})",
        "expected an integer");
}

TEST(Sweep, ResumedRunEqualsAnUninterruptedOne) {
    const fs::path d = Scratch();
    SweepRunOptions partial;
    partial.maxRows = 7;
    EXPECT_EQ(RunSweep(kConfig, "cfg", (d / "a").string(), partial), 7);
    EXPECT_TRUE(fs::exists(d / "a" / "results.csv"));  // the rows so far
    EXPECT_EQ(RunSweep(kConfig, "cfg", (d / "a").string(), {}), 13);
    EXPECT_EQ(RunSweep(kConfig, "cfg", (d / "a").string(), {}), 0);  // nothing left
    EXPECT_EQ(RunSweep(kConfig, "cfg", (d / "b").string(), {}), 20);
    const std::string a = Read(d / "a" / "results.csv"),
                      b = Read(d / "b" / "results.csv");
    EXPECT_EQ(WithoutTiming(a), WithoutTiming(b));
    EXPECT_NE(a.find("index,map,map_channel,map_stores,view,method,set.linear_steps,"
                     "set.refine_steps,"),
              std::string::npos)
        << a.substr(0, 200);
    EXPECT_NE(a.find("mse_exact_depth"), std::string::npos);
    EXPECT_EQ(std::count(a.begin(), a.end(), '\n'), 21);
    EXPECT_NE(Read(d / "b" / "tables.md").find("| steps | avg steps per pixel | MSE |"),
              std::string::npos);
    // Folders that cannot hold a sweep: one Error, nothing written.
    { std::ofstream(d / "file") << "x"; }
    EXPECT_THROW(RunSweep(kConfig, "cfg", (d / "file" / "sub").string(), {}), Error);
    EXPECT_THROW(RunSweep(kConfig, "cfg", (d / "file").string(), {}), Error);
    EXPECT_THROW(RunSweep(kConfig, "cfg", "", {}), Error);
    EXPECT_THROW(MergeSweeps({(d / "a").string()}, (d / "file").string()), Error);
    EXPECT_EQ(Read(d / "file"), "x");
    // Another configuration in the same folder is refused.
    EXPECT_THROW(
        RunSweep(R"({"maps": ["builtin:flat:16"], "methods": [{"method": "linear"}]})",
                 "cfg", (d / "a").string(), {}),
        Error);
}

TEST(Sweep, ShardsMergedInAnyOrderEqualTheUnshardedRun) {
    const fs::path d = Scratch();
    RunSweep(kConfig, "cfg", (d / "whole").string(), {});
    std::vector<std::string> parts;
    for (int i = 0; i < 3; ++i) {
        SweepRunOptions o;
        o.taskIndex = i;
        o.taskCount = 3;
        const std::string dir = (d / ("part" + std::to_string(i))).string();
        RunSweep(kConfig, "cfg", dir, o);
        parts.push_back(dir);
    }
    MergeSweeps({parts[2], parts[0], parts[1]}, (d / "merged").string());
    EXPECT_EQ(WithoutTiming(Read(d / "merged" / "results.csv")),
              WithoutTiming(Read(d / "whole" / "results.csv")));
    EXPECT_EQ(Read(d / "merged" / "sweep.json"), Read(d / "whole" / "sweep.json"));
    // A missing shard is an error, not a silently shorter table.
    EXPECT_THROW(MergeSweeps({parts[0], parts[1]}, (d / "short").string()), Error);
}

namespace {

/// True when the file starts with PNG's signature and an IHDR of a non-empty image.
bool IsPng(const fs::path& p) {
    const std::string s = Read(p);
    if (s.size() < 24 || s.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 ||
        s.compare(12, 4, "IHDR") != 0)
        return false;
    auto be32 = [&](size_t at) {
        return uint32_t(uint8_t(s[at])) << 24 | uint32_t(uint8_t(s[at + 1])) << 16 |
               uint32_t(uint8_t(s[at + 2])) << 8 | uint32_t(uint8_t(s[at + 3]));
    };
    return be32(16) > 0 && be32(20) > 0;
}

bool HaveMatplotlib() {
    return std::system(
               "python3 -c 'import matplotlib' >/dev/null 2>&1 || "
               "/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0;
}

}  // namespace

TEST(Sweep, SweepAndMergeDrawChartsWithMatplotlib) {
    const fs::path d = Scratch();
    std::ofstream(d / "cfg.json") << kConfig;
    const std::string cfg = "--config " + (d / "cfg.json").string();
    const reliefsim::testing::CliResult r =
        reliefsim::testing::RunCli("sweep " + cfg + " --out " + (d / "a").string(), d);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    if (!HaveMatplotlib()) {
        EXPECT_FALSE(fs::exists(d / "a" / "mse_vs_steps.png"));
        EXPECT_NE(r.err.find("charts not drawn"), std::string::npos) << r.err;
        GTEST_SKIP() << "no python3 with matplotlib (Debian: python3-matplotlib)";
    }
    EXPECT_TRUE(r.err.empty()) << r.err;
    EXPECT_NE(r.out.find("mse_vs_time.png"), std::string::npos) << r.out;
    EXPECT_TRUE(IsPng(d / "a" / "mse_vs_steps.png"));
    EXPECT_TRUE(IsPng(d / "a" / "mse_vs_time.png"));
    EXPECT_FALSE(fs::exists(d / "a" / ".mse_vs_steps.png.tmp"));
    // merge draws the joined folder's charts; --no-charts draws none.
    ASSERT_EQ(reliefsim::testing::RunCli(
                  "merge --out " + (d / "m").string() + " " + (d / "a").string(), d)
                  .exitCode,
              0);
    EXPECT_TRUE(IsPng(d / "m" / "mse_vs_steps.png"));
    ASSERT_EQ(reliefsim::testing::RunCli(
                  "sweep " + cfg + " --no-charts --out " + (d / "b").string(), d)
                  .exitCode,
              0);
    EXPECT_FALSE(fs::exists(d / "b" / "mse_vs_steps.png"));
    EXPECT_TRUE(fs::exists(d / "b" / "results.csv"));
}

TEST(Sweep, ChartsWithoutMatplotlibAreANoteAndAFailingScriptIsAnError) {
    const fs::path d = Scratch();
    std::ofstream(d / "cfg.json") << kConfig;
    const std::string cfg = "sweep --config " + (d / "cfg.json").string() + " --out ";
    setenv("RELIEFSIM_PYTHON", (d / "no-such-python").c_str(), 1);
    const reliefsim::testing::CliResult missing =
        reliefsim::testing::RunCli(cfg + (d / "a").string(), d);
    setenv("RELIEFSIM_PYTHON", "false", 1);  // an interpreter that fails
    const reliefsim::testing::CliResult failing =
        reliefsim::testing::RunCli(cfg + (d / "b").string(), d);
    unsetenv("RELIEFSIM_PYTHON");
    EXPECT_EQ(missing.exitCode, 0) << missing.err;
    EXPECT_EQ(reliefsim::testing::CountLines(missing.err), 1) << missing.err;
    EXPECT_NE(missing.err.find("charts not drawn"), std::string::npos) << missing.err;
    EXPECT_TRUE(fs::exists(d / "a" / "results.csv"));
    EXPECT_FALSE(fs::exists(d / "a" / "mse_vs_steps.png"));
    EXPECT_NE(failing.exitCode, 0);
    EXPECT_EQ(reliefsim::testing::CountLines(failing.err), 1) << failing.err;
    EXPECT_NE(failing.err.find("sweep charts: false"), std::string::npos) << failing.err;
}

TEST(Sweep, AShardWithoutConfigurationsSucceedsWithoutCharts) {
    // More shards than configurations (and --max-rows 0) leave a shard with none: it
    // exits 0 with its results.csv and tables.md and a note instead of charts (the chart
    // script refused a results.csv without rows, failing the shard); it merges with the
    // others.
    const fs::path d = Scratch();
    std::ofstream(d / "cfg.json") << kConfig;
    const std::string cfg = "sweep --config " + (d / "cfg.json").string() + " --out ";
    const auto configs = ParseSweepConfig(kConfig, "cfg");
    const std::string count = std::to_string(configs.size() + 1);
    for (const std::string& extra :
         {" --task-count " + count + " --task-index " + std::to_string(configs.size()),
          std::string(" --max-rows 0")}) {
        const fs::path out = d / ("s" + std::to_string(extra.size()));
        const reliefsim::testing::CliResult r =
            reliefsim::testing::RunCli(cfg + out.string() + extra, d);
        EXPECT_EQ(r.exitCode, 0) << extra << "\n" << r.err;
        EXPECT_EQ(reliefsim::testing::CountLines(r.err), 1) << r.err;
        EXPECT_NE(r.err.find("holds no configuration"), std::string::npos) << r.err;
        EXPECT_NE(r.out.find("0 configurations computed"), std::string::npos) << r.out;
        EXPECT_TRUE(fs::exists(out / "results.csv")) << extra;
        EXPECT_TRUE(fs::exists(out / "tables.md")) << extra;
        EXPECT_FALSE(fs::exists(out / "mse_vs_steps.png")) << extra;
    }
}

TEST(Sweep, TheStudiesOfTheDocsAreValidConfigurations) {
    // scripts/studies runs these; docs/studies/results.md is their output.
    int n = 0;
    for (const auto& e :
         fs::directory_iterator(fs::path(RS_SOURCE_DIR) / "docs" / "studies")) {
        if (e.path().extension() != ".json") continue;
        SCOPED_TRACE(e.path().string());
        EXPECT_NO_THROW({
            const auto configs = ParseSweepConfig(Read(e.path()), e.path().string());
            EXPECT_GT(configs.size(), 10u);
        });
        ++n;
    }
    EXPECT_EQ(n, 5);
}
