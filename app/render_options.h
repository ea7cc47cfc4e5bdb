// The options of `reliefsim render`, shared by every command that renders the same scene
// (render, glcompare, bench/frame_vs_llvmpipe), so they stay identical.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "app/commands.h"
#include "app/pipeline.h"

namespace reliefsim {

/// The render options as parsed text and values; Resolve() turns them into settings.
struct RenderOptions {
    MapOptions map;
    RenderSettings settings;
    std::string size = "512x512";
    std::string filter = "bilinear", wrap = "repeat";
    std::string textureFormat = "r32f";  ///< r32f | r8 (8-bit unorm, llvmpipe fixed point)
    std::string iterScale, fetchScale;
};

/// Most worker threads --threads accepts.
constexpr int kMaxThreads = 1024;

/// Adds render's scene options (map, method, set, size, camera, sampler, texture format,
/// threads and, when asked, the heatmap scales) to cmd. Output options (--out, --quiet) are
/// the command's own. Commands that write no heatmap leave the scales out, so giving them
/// is an error rather than silently ignored.
void AddRenderOptions(CLI::App* cmd, RenderOptions& options, bool withHeatmapScales = true);

/// Parses the text options into options.settings and validates them (throws Error).
void ResolveRenderSettings(RenderOptions& options);

/// Parses "X,Y" (row 0 at the top) for `option` and checks it lies inside width x height;
/// throws Error naming the option otherwise.
std::pair<int, int> ParsePixel(const std::string& option, const std::string& text, int width,
                               int height);

/// Checks, before any work, that `path` can receive an output file: nothing but a regular
/// file stands at the path, the name is not too long, and its folder exists (or, when
/// `folderIsCreated`, its nearest existing ancestor is a directory). Throws Error naming
/// the option.
void CheckOutputFile(const std::string& option, const std::string& path,
                     bool folderIsCreated = true);

/// The files `render --out DIR` writes.
inline const std::vector<std::string>& RenderOutputNames() {
    static const std::vector<std::string> kNames = {"color.png", "iterations.png", "fetches.png",
                                                    "record.exr", "metrics.json"};
    return kNames;
}

/// Checks, before any work, that `dir` can receive the outputs: not empty, no path
/// component too long, it is a directory if it exists (and no output name in it is held by
/// a directory or other non-regular entry), else its nearest existing ancestor is a
/// directory. Throws Error naming the option.
void CheckOutputDirectory(const std::string& option, const std::string& dir,
                          const std::vector<std::string>& outputs = RenderOutputNames());

/// Loads the map; with --texture-format r8 quantises it to 8 bits (keeping depth8) unless it
/// already came from 8-bit data.
HeightField LoadRenderMap(const RenderOptions& options);

}  // namespace reliefsim
