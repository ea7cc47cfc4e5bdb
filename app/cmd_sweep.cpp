// `reliefsim sweep` and `reliefsim merge` (app/sweep.h, docs/studies.md).
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "app/commands.h"
#include "app/sweep.h"
#include "core/error.h"

namespace reliefsim {

namespace {

struct SweepArgs {
    std::string config, out;
    int taskIndex = -1, taskCount = -1, maxRows = -1;
    bool quiet = false, noCharts = false;
};

/// Whether the folder's results.csv holds a configuration (a shard of more shards than
/// configurations, or --max-rows 0, holds none).
bool HasResults(const std::string& dir) {
    std::ifstream in(std::filesystem::path(dir) / "results.csv");
    std::string header, row;
    return std::getline(in, header) && std::getline(in, row) && !row.empty();
}

/// The charts of a finished run, unless --no-charts or it holds no configuration; a note
/// when matplotlib is missing or there is nothing to draw.
std::string Charts(const std::string& dir, bool noCharts, bool quiet) {
    if (noCharts) return "";
    if (!HasResults(dir)) {
        if (!quiet)
            std::cerr << "reliefsim: charts not drawn: " << dir
                      << " holds no configuration yet\n";
        return "";
    }
    if (DrawSweepCharts(dir)) return ",mse_vs_steps.png,mse_vs_time.png";
    if (!quiet)
        std::cerr << "reliefsim: charts not drawn: no python3 with matplotlib "
                     "(Debian: python3-matplotlib; --no-charts silences this)\n";
    return "";
}

/// An environment variable as a non-negative integer, or `fallback`.
int EnvInt(const char* name, int fallback) {
    const char* v = std::getenv(name);
    if (!v || !*v) return fallback;
    char* end = nullptr;
    const long n = std::strtol(v, &end, 10);
    if (*end != '\0' || n < 0 || n > 1000000)
        throw Error(std::string(name) + "=\"" + v + "\": not a task number");
    return int(n);
}

std::string ReadConfig(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        throw Error("--config \"" + path + "\": " +
                    (fs::exists(path, ec) ? "not a regular file" : "no such file"));
    if (fs::file_size(path, ec) > (16u << 20))
        throw Error("--config \"" + path + "\": larger than 16 MiB");
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    if (!in && !in.eof()) throw Error("--config \"" + path + "\": cannot be read");
    return ss.str();
}

void RunSweepCommand(const SweepArgs& a) {
    SweepRunOptions o;
    o.taskIndex = a.taskIndex >= 0 ? a.taskIndex : EnvInt("SLURM_ARRAY_TASK_ID", 0);
    o.taskCount = a.taskCount >= 0 ? a.taskCount : EnvInt("SLURM_ARRAY_TASK_COUNT", 1);
    o.maxRows = a.maxRows;
    o.progress = !a.quiet && isatty(2);
    const int n =
        RunSweep(ReadConfig(a.config), "--config \"" + a.config + "\"", a.out, o);
    const std::string charts = Charts(a.out, a.noCharts, a.quiet);
    if (!a.quiet)
        std::cout << "reliefsim sweep: " << n << " configurations computed (task "
                  << o.taskIndex << " of " << o.taskCount << "); wrote " << a.out
                  << "/{results.csv,tables.md" << charts << "}\n";
}

}  // namespace

void RegisterSweepCommand(CLI::App& root) {
    auto a = std::make_shared<SweepArgs>();
    auto* cmd = root.add_subcommand(
        "sweep",
        "run a study: methods x parameter ranges x maps x views from a JSON config into "
        "--out (results.csv, tables.md, charts, one row file per configuration; "
        "resumable)");
    cmd->add_option("--config", a->config,
                    "the study's JSON configuration (docs/studies.md)")
        ->required();
    cmd->add_option("--out", a->out, "output folder (created; a rerun resumes it)")
        ->required();
    cmd->add_option("--task-index", a->taskIndex,
                    "this shard's index (default: $SLURM_ARRAY_TASK_ID, else 0)")
        ->check(CLI::Range(0, 1000000));
    cmd->add_option("--task-count", a->taskCount,
                    "number of shards (default: $SLURM_ARRAY_TASK_COUNT, else 1)")
        ->check(CLI::Range(1, 1000000));
    cmd->add_option("--max-rows", a->maxRows,
                    "stop after computing this many configurations (a partial run)")
        ->check(CLI::Range(0, 100000000));
    cmd->add_flag("--quiet", a->quiet, "print nothing on success, no progress bar");
    cmd->add_flag("--no-charts", a->noCharts,
                  "do not draw mse_vs_steps.png and mse_vs_time.png (matplotlib)");
    cmd->callback([a] { RunSweepCommand(*a); });

    auto parts = std::make_shared<std::vector<std::string>>();
    auto out = std::make_shared<std::string>();
    auto noCharts = std::make_shared<bool>(false);
    auto* merge = root.add_subcommand(
        "merge", "join the folders of a sharded sweep (any order) into one sweep folder");
    merge->add_option("--out", *out, "output folder")->required();
    merge->add_option("parts", *parts, "the shards' --out folders")->required();
    merge->add_flag("--no-charts", *noCharts,
                    "do not draw mse_vs_steps.png and mse_vs_time.png (matplotlib)");
    merge->callback([parts, out, noCharts] {
        MergeSweeps(*parts, *out);
        Charts(*out, *noCharts, false);
    });
}

}  // namespace reliefsim
