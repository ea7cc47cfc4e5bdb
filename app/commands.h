// The reliefsim subcommands: each registers itself on the root CLI11 app.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "texture/depth_field.h"
#include "texture/image_io.h"

namespace reliefsim {

/// The height-map options shared by every command that reads a map.
struct MapOptions {
    std::string map = "builtin:shapes";  ///< file path or builtin:NAME[:SIZE]
    Channel channel = Channel::Auto;
    Stores stores = Stores::Height;
    /// Set by AddMapOptions: tells whether --map-channel / --map-stores were given (they
    /// do not apply to a builtin map, and are refused there).
    const CLI::Option* channelOption = nullptr;
    const CLI::Option* storesOption = nullptr;
};

/// Adds --map, --map-channel, --map-stores to a subcommand.
void AddMapOptions(CLI::App* cmd, MapOptions& options);

/// Loads the map the options name; throws Error on any problem.
DepthField LoadMapFromOptions(const MapOptions& options);

// Each Register*Command adds one subcommand whose callback does the work and throws
// reliefsim::Error on bad input (main() prints it and exits non-zero).
void RegisterMethodsCommand(CLI::App& root);
void RegisterRenderCommand(CLI::App& root);
void RegisterSummaryCommand(CLI::App& root);
void RegisterTraceCommand(CLI::App& root);
void RegisterMapsCommand(CLI::App& root);
void RegisterSweepCommand(CLI::App& root);
void RegisterSafetyCommand(
    CLI::App& root);  // app/safety.cpp  // app/cmd_sweep.cpp: sweep and merge       //
                      // app/cmd_maps.cpp (issue #3)
void RegisterGlCompareCommand(CLI::App& root);  // app/cmd_glcompare.cpp (issue #4)

}  // namespace reliefsim
