// The options of `reliefsim render`, shared by every command that renders the same scene
// (render, glcompare, bench/frame_vs_llvmpipe), so they stay identical.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/commands.h"
#include "render/scene.h"
#include "texture/depth_field.h"

namespace reliefsim {

/// "WxH", as --size takes it.
inline std::string SizeText(int width, int height) {
    return std::to_string(width) + "x" + std::to_string(height);
}

/// The render options: values bound straight into settings (the sampler's enums among
/// them), and the text of the options that ResolveRenderSettings() parses. The defaults
/// are RenderSettings' own.
struct RenderOptions {
    MapOptions map;
    RenderSettings settings;
    std::string size = SizeText(settings.width, settings.height);  ///< WxH
    std::string iterScale, fetchScale;  ///< MIN:MAX; empty: the settings' scale
    std::string viewDir;                ///< X,Y,Z (--view-dir); empty: the settings'
    /// The command the options were added to: which were given (RefuseIgnoredSettings);
    /// null where code filled the options in (nothing counts as given then).
    const CLI::App* command = nullptr;
    /// The methods rendered with these settings when a command renders several
    /// (safety's --methods); empty: settings.method.
    std::vector<std::string> methods;
    std::string lightDir;  ///< X,Y,Z (--light-dir); empty: the settings'
    std::optional<float> lightAngle, lightAzimuth;  ///< --light-angle, --light-azimuth
    std::string coneEncoding;     ///< --cone-encoding; empty: the kernel's own
    std::string coneMapChannel;   ///< --cone-map-channel R|G|B|A
    std::string coneMapEncoding;  ///< --cone-map-encoding
};

/// Adds render's scene options (map, method, set, size, camera, sampler, texture format,
/// threads and, when asked, the heatmap scales) to cmd. Output options (--out, --quiet)
/// are the command's own. Commands that write no heatmap leave the scales out, so giving
/// them is an error rather than silently ignored.
void AddRenderOptions(CLI::App* cmd, RenderOptions& options,
                      bool withHeatmapScales = true);

/// Parses "WxH" (--size) into w and h; throws Error naming --size.
void ParseSize(const std::string& text, int& w, int& h);

/// Parses the text options into options.settings and validates them (throws Error).
void ResolveRenderSettings(RenderOptions& options);

/// Parses "X,Y" (row 0 at the top) for `option` and checks it lies inside width x height;
/// throws Error naming the option otherwise.
std::pair<int, int> ParsePixel(const std::string& option, const std::string& text,
                               int width, int height);

/// Checks, before any work, that `path` can receive an output file (the checks of
/// core/output_set.h CheckOutputDestination; with !folderIsCreated its folder must also
/// exist already). Throws Error naming the option.
void CheckOutputFile(const std::string& option, const std::string& path,
                     bool folderIsCreated = true);

/// The files `render --out DIR` writes (missed_geometry.png only with the reference, the
/// default).
inline const std::vector<std::string>& RenderOutputNames() {
    static const std::vector<std::string> kNames = {
        "color.png",    "iterations.png", "fetches.png",          "record.exr",
        "metrics.json", "warp_trips.png", "warp_utilisation.png", "missed_geometry.png"};
    return kNames;
}

/// Checks, before any work, that `dir` can receive the outputs: not empty, a directory if
/// it exists, and each output in it passes CheckOutputDestination (no directory or other
/// non-regular entry where an output goes, names within the limits, parents that are
/// folders). Throws Error naming the option.
void CheckOutputDirectory(const std::string& option, const std::string& dir,
                          const std::vector<std::string>& outputs = RenderOutputNames());

/// Loads the map; with --texture-format r8 quantises it to 8 bits (keeping depth8) unless
/// it already came from 8-bit data.
DepthField LoadRenderMap(const RenderOptions& options);

}  // namespace reliefsim
