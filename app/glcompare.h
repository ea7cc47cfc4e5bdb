// `reliefsim glcompare`'s report (the runner is glref/glcompare.h). Only built when
// rs_glref exists (EGL and GL found).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/render_options.h"
#include "glref/glcompare.h"

namespace reliefsim {

/// The JSON report: pixels, identical{hit_uv, hit_depth, iterations, fetches, with
/// --shadow shadow_fetches and light_visibility}, max_diff,
/// coverage, first_differences (with trace commands), lane_cost.
nlohmann::json GlCompareJson(const GlCompareResult& r, const RenderOptions& options,
                             const DepthField& field);

/// The command line that re-runs glcompare for one pixel with a two-path fetch trace.
std::string TraceCommand(const RenderOptions& options, int x, int y);

}  // namespace reliefsim
