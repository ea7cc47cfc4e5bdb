// `reliefsim sweep` and `reliefsim merge`: algorithm studies over methods x parameter
// ranges x maps x views (docs/studies.md).
//
// A sweep folder holds sweep.json (the configuration, canonical), rows/NNNNNN.json (one
// finished configuration each, written atomically: the unit of resumption and of
// sharding), results.csv and tables.md (both rebuilt from the rows, atomically, after
// every run and by merge, so they are never half-written).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "render/scene.h"

namespace reliefsim {

/// One configuration of a sweep: its index in the cross product and what it renders.
struct SweepConfig {
    int index = 0;
    nlohmann::ordered_json
        columns;      ///< the configuration's keys, as results.csv shows them
    std::string map;  ///< file path or builtin:NAME[:SIZE]
    std::string mapChannel = "auto", mapStores = "height";
    RenderSettings settings;
};

/// Parses and validates a sweep configuration (the text of FILE.json; `subject` names it
/// in errors) into its configurations, in order: maps x views x methods x the crossed
/// `set` lists of each method. Every setting is validated (ValidateSettings) before any
/// work; unknown keys are listed with the valid ones. Throws Error.
std::vector<SweepConfig> ParseSweepConfig(const std::string& text,
                                          const std::string& subject);

struct SweepRunOptions {
    int taskIndex = 0, taskCount = 1;  ///< this shard: configurations with index % count
    int maxRows = -1;                  ///< stop after this many new rows (tests), -1: all
    bool progress = false;             ///< a progress bar on stderr
};

/// Runs the configurations of this shard that `outDir` does not hold yet, writing one
/// row file each, then rebuilds results.csv and tables.md from every row present.
/// `configText` is stored as sweep.json; a folder holding another configuration is
/// refused. Returns the number of rows computed now.
int RunSweep(const std::string& configText, const std::string& subject,
             const std::string& outDir, const SweepRunOptions& options);

/// Draws `dir`/mse_vs_steps.png and `dir`/mse_vs_time.png from `dir`/results.csv with
/// scripts/sweep_charts.py (compiled in) run by $RELIEFSIM_PYTHON when it is set, else
/// by the first of python3 on the PATH and /usr/bin/python3 that has matplotlib. Returns
/// false, drawing nothing, when none has it; throws Error when the script fails. Each
/// chart is written to a temporary and renamed: whole or absent.
bool DrawSweepCharts(const std::string& dir);

/// Joins the rows of sweep folders (shards, in any order) of one configuration into
/// outDir, which then equals the unsharded sweep's folder outside timing columns.
/// Throws Error when the parts hold different configurations, a configuration twice with
/// different results, or not every configuration.
void MergeSweeps(const std::vector<std::string>& partDirs, const std::string& outDir);

/// results.csv of a set of rows (ordered by index): the configuration columns, then every
/// metrics.json field (nested keys joined with dots), timing columns last.
std::string SweepCsv(const std::vector<nlohmann::ordered_json>& rows);

/// tables.md: per map and view, per method, steps | avg steps per pixel | MSE | time.
std::string SweepTables(const std::vector<nlohmann::ordered_json>& rows);

}  // namespace reliefsim
