// `reliefsim render`: one frame of one method, with heatmaps, record and metrics.
#include <iostream>

#include "app/commands.h"
#include "app/render_options.h"
#include "core/error.h"
#include "render/outputs.h"

namespace reliefsim {

namespace {

struct RenderArgs {
    RenderOptions options;
    std::string out;
    bool quiet = false, groupHeatmaps = false;
};

void RunRender(RenderArgs& a) {
    ResolveRenderSettings(a.options);  // before any file is read or written
    const RenderSettings& s = a.options.settings;
    std::vector<std::string> outputs = RenderOutputNames();
    if (!s.reference) std::erase(outputs, std::string("missed_geometry.png"));
    if (s.shadow != ShadowKind::None) outputs.push_back("shadow_fetches.png");
    std::string groupFiles;
    if (a.groupHeatmaps)
        for (const LaneGroupHeatmap& g : kLaneGroupHeatmaps)
            for (const char* kind : {"_trips.png", "_utilisation.png"}) {
                outputs.push_back(g.prefix + std::string(kind));
                groupFiles += "," + outputs.back();
            }
    CheckOutputDirectory("--out", a.out, outputs);
    RequireFrameMemory(s.width, s.height);
    DepthField field = LoadRenderMap(a.options);
    RequireFrameMemory(s.width, s.height);  // what is left once the map is in memory
    RenderOutput out = Render(field, s);
    WriteRenderOutputs(a.out, out, s, field, a.groupHeatmaps);
    if (!a.quiet) {
        const FrameSummary& m = out.summary;
        std::cout << "reliefsim render: " << s.method << " on " << field.name << " at "
                  << s.width << "x" << s.height << ": " << m.coveredPixels
                  << " covered pixels, " << m.avgIterations << " iterations/px, "
                  << m.avgFetches << " fetches/px (max " << m.maxFetches
                  << "), mse_paper " << m.msePaper << ", " << out.frameSeconds * 1e3
                  << " ms\n"
                  << "wrote " << a.out
                  << "/{color.png,iterations.png,fetches.png,record.exr,metrics.json,"
                     "warp_trips.png,warp_utilisation.png"
                  << (s.reference ? ",missed_geometry.png" : "")
                  << (s.shadow != ShadowKind::None ? ",shadow_fetches.png" : "")
                  << groupFiles << "}\n";
    }
}

}  // namespace

void RegisterRenderCommand(CLI::App& root) {
    auto a = std::make_shared<RenderArgs>();
    auto* cmd = root.add_subcommand(
        "render",
        "render the textured plane with one method; write color.png, iterations.png, "
        "fetches.png, record.exr, metrics.json, warp_trips.png, warp_utilisation.png and "
        "missed_geometry.png into --out");
    AddRenderOptions(cmd, a->options);
    cmd->add_option("--out", a->out,
                    "output directory (created with its parents; the outputs replaced)")
        ->required();
    cmd->add_flag("--quiet", a->quiet, "print nothing on success");
    cmd->add_flag(
        "--group-heatmaps", a->groupHeatmaps,
        "also write {quad,group4x2,wave}_{trips,utilisation}.png: the heatmaps of "
        "the 2x2 quads, llvmpipe's 4x2 groups and 64-lane 8x8 waves");
    cmd->callback([a] { RunRender(*a); });
}

}  // namespace reliefsim
