// `reliefsim trace`: one pixel's kernel, fetch by fetch (CPU only).
#include <cstdio>
#include <iostream>

#include "app/commands.h"
#include "app/render_options.h"
#include "core/error.h"
#include "render/trace.h"

namespace reliefsim {

void RegisterTraceCommand(CLI::App& root) {
    struct TraceArgs {
        RenderOptions options;
        std::string pixel;
        bool json = false;
    };
    auto a = std::make_shared<TraceArgs>();
    auto* cmd = root.add_subcommand(
        "trace",
        "run one pixel's kernel of the scene `render` would draw and print every fetch "
        "(uv, ray depth, sampled depth) and the result, next to the exact first hit");
    AddRenderOptions(cmd, a->options, /*withHeatmapScales=*/false);
    cmd->add_option("--pixel", a->pixel, "pixel X,Y (row 0 at the top)")
        ->type_name("X,Y")
        ->required();
    cmd->add_flag("--json", a->json, "print the trace as JSON");
    cmd->callback([a] {
        ResolveRenderSettings(a->options);
        const auto [x, y] = ParsePixel("--pixel", a->pixel, a->options.settings.width,
                                       a->options.settings.height);
        DepthField field = LoadRenderMap(a->options);
        const PixelTrace t = TracePixel(field, a->options.settings, x, y);
        std::cout << (a->json ? TraceJson(t) : FormatTrace(t));
    });
}

}  // namespace reliefsim
