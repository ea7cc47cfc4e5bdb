// The output files of a frame: metrics.json and the images and record of
// WriteRenderOutputs.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "render/frame.h"

namespace reliefsim {

/// metrics.json content: the contract keys plus extras; timing fields only under
/// "timing".
nlohmann::json MetricsJson(const RenderOutput& out, const RenderSettings& settings,
                           const DepthField& field);

/// Writes color.png, iterations.png, fetches.png, record.exr and metrics.json into
/// outDir, all or nothing (core/output_set.h): every destination is checked first (a
/// folder or other non-file standing where an output goes, a name too long: Error,
/// nothing written), the files are written to temporaries and replace the previous
/// outputs together; any failure restores what was there and removes the folders this
/// call created. Files in outDir that are not outputs are never touched. Missing folders
/// are created as mkdir does (mode 0777 & ~umask). Every file but metrics.json's "timing"
/// is byte-identical for equal inputs and any thread count.
/// With allLaneGroups, also the trips and lane-utilisation heatmaps of the other lane
/// groups (kLaneGroupHeatmaps), beside warp_trips.png and warp_utilisation.png.
void WriteRenderOutputs(const std::string& outDir, const RenderOutput& out,
                        const RenderSettings& settings, const DepthField& field,
                        bool allLaneGroups = false);

/// The lane groups whose heatmaps `render --group-heatmaps` adds: file prefix, width and
/// height in pixels (docs/exact.md "Lane groups"). The 8x4 warp's are always written.
struct LaneGroupHeatmap {
    const char* prefix;
    int width, height;
    const char* what;
};
inline constexpr LaneGroupHeatmap kLaneGroupHeatmaps[] = {
    {"quad", 2, 2, "2x2 quad"},
    {"group4x2", 4, 2, "llvmpipe 4x2 group"},
    {"wave", 8, 8, "8x8 64-lane wave"}};

}  // namespace reliefsim
