// The options of `reliefsim render`, shared by every command that renders the same scene
// (render, glcompare, bench/frame_vs_llvmpipe), so they stay identical.
#pragma once

#include <string>

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

/// Adds render's scene options (map, method, set, size, camera, sampler, texture format,
/// threads, heatmap scales) to cmd. Output options (--out, --quiet) are the command's own.
void AddRenderOptions(CLI::App* cmd, RenderOptions& options);

/// Parses the text options into options.settings and validates them (throws Error).
void ResolveRenderSettings(RenderOptions& options);

/// Loads the map; with --texture-format r8 quantises it to 8 bits (keeping depth8) unless it
/// already came from 8-bit data.
HeightField LoadRenderMap(const RenderOptions& options);

}  // namespace reliefsim
