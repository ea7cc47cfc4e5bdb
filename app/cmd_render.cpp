// `reliefsim render`: one frame of one method, with heatmaps, record and metrics; with
// --animate, the ACM paper's dynamic demo (a regenerated map, preprocessed every frame).
#include <chrono>
#include <cstdio>
#include <iostream>

#include "app/commands.h"
#include "app/render_options.h"
#include "core/error.h"
#include "core/memory.h"
#include "maps/cone_map.h"
#include "render/kernel_maps.h"
#include "render/outputs.h"

namespace reliefsim {

namespace {

struct RenderArgs {
    RenderOptions options;
    std::string out;
    bool quiet = false, groupHeatmaps = false;
    int animate = 0;        ///< --animate N: frames of the dynamic demo; 0: one frame
    int animateSize = 256;  ///< --animate-size: the sinusoid map's side
    float adaptiveThreshold = 0.25f;  ///< --adaptive-threshold (000 Algorithm 1)
    int adaptiveLevels = 3;           ///< --adaptive-levels
    const CLI::Option *mapOption = nullptr, *methodOption = nullptr;
    std::vector<const CLI::Option*> animateOnly;  ///< the options only --animate takes
};

/// The ACM paper's dynamic demo (000 §III): every frame regenerates the sinusoid height
/// map, preprocesses it with adaptive ACM and renders it; prints per-frame times; writes
/// the last frame's outputs as `render` does.
void RunAnimate(RenderArgs& a) {
    if (a.mapOption->count() > 0)
        throw Error(
            "--map: not with --animate, which renders the dynamic sinusoid height "
            "map of `maps --animate` (--animate-size sets its side)");
    if (!a.options.settings.maps.coneMap.empty())
        throw Error(
            "--cone-map: not with --animate, which makes every frame's map with "
            "adaptive ACM");
    if (a.animateSize < 2 || a.animateSize > 4096)
        throw Error("--animate-size " + std::to_string(a.animateSize) +
                    ": out of range; expected 2..4096");
    if (!(a.adaptiveThreshold >= 0.0f && a.adaptiveThreshold <= 1.0f))
        throw Error("--adaptive-threshold: must be a depth difference in [0, 1]");
    if (a.adaptiveLevels < 0 || a.adaptiveLevels > 12)
        throw Error("--adaptive-levels " + std::to_string(a.adaptiveLevels) +
                    ": out of range; expected 0..12");
    if (a.methodOption->count() == 0) a.options.settings.method = "acm4";
    ResolveRenderSettings(a.options);
    RenderSettings s = a.options.settings;
    const Kernel kernel = SettingsKernel(s);
    const auto spec = kernel.Info().maps.size() == 1
                          ? ParseKernelMap(kernel.Info().maps[0])
                          : std::optional<KernelMapSpec>();
    const bool adaptiveKind =
        spec && !spec->params.relaxed && !spec->params.normal &&
        (spec->kind == ConeKind::Cone || spec->kind == ConeKind::Quad ||
         spec->kind == ConeKind::Acm4 || spec->kind == ConeKind::Acm8);
    if (!adaptiveKind)
        throw Error(
            "--method " + s.method +
            ": --animate preprocesses every frame with adaptive ACM (000 Algorithm "
            "1), which makes cone, quad, acm4 and acm8 maps; use --method csm, "
            "qcsm, acm4 or acm8");
    if (s.maps.bounds == ConeBounds::Bilinear)
        throw Error(
            "--cone-bounds bilinear: --animate preprocesses every frame with adaptive "
            "ACM, whose maps bound the texel centres; leave --cone-bounds out");
    std::vector<std::string> outputs = RenderOutputNames();
    if (!s.reference) std::erase(outputs, std::string("missed_geometry.png"));
    if (s.shadow != ShadowKind::None || s.ao != AoKind::None)
        outputs.push_back("shadow_fetches.png");
    CheckOutputDirectory("--out", a.out, outputs);
    RequireFrameMemory(s.width, s.height);

    KeepFreedMemoryInHeap();  // frames allocate and free the same buffers
    // Frame f's height map is the sinusoid map of `maps --animate` at time f / 30 s, in
    // a buffer kept across frames, as are adaptive ACM's.
    DepthField field;
    double adaptiveMs = 0;
    s.maps.generator =
        AdaptiveMapGenerator(a.adaptiveThreshold, a.adaptiveLevels, &adaptiveMs);
    // The timed frames skip the exact reference (a metric of the outputs, not part of
    // the demo); the last frame is rendered again with it when it is on.
    RenderSettings timed = s;
    timed.reference = false;
    RenderOutput out;
    double sum = 0, worst = 0;
    using Clock = std::chrono::steady_clock;
    auto ms = [](Clock::time_point a0, Clock::time_point a1) {
        return std::chrono::duration<double, std::milli>(a1 - a0).count();
    };
    for (int f = 0; f < a.animate; ++f) {
        const auto t0 = Clock::now();
        FillSinusoidMap(field, a.animateSize, a.animateSize, float(f) / 30.0f);
        const auto t1 = Clock::now();
        out = Render(field, timed);
        const auto t2 = Clock::now();
        const double total = ms(t0, t2);
        if (f > 0) {
            sum += total;
            worst = std::max(worst, total);
        }
        if (!a.quiet)
            std::printf(
                "frame %d: %.3f ms (height map %.3f, adaptive %s %.3f, render "
                "%dx%d %.3f of which the frame loop %.3f)%s\n",
                f, total, ms(t0, t1), std::string(ToString(spec->kind)).c_str(),
                adaptiveMs, s.width, s.height, ms(t1, t2) - adaptiveMs,
                out.frameSeconds * 1e3, f == 0 ? " warm-up" : "");
    }
    if (!a.quiet && a.animate > 1)
        std::printf(
            "animate: %d frames of %s on the %dx%d sinusoid map at %dx%d: mean "
            "%.3f ms (%.1f frames/s), max %.3f ms after the first\n",
            a.animate, s.method.c_str(), a.animateSize, a.animateSize, s.width, s.height,
            sum / (a.animate - 1), 1000.0 * (a.animate - 1) / sum, worst);
    if (s.reference) out = Render(field, s);
    WriteRenderOutputs(a.out, out, s, field, a.groupHeatmaps);
    if (!a.quiet) std::cout << "wrote " << a.out << " (the last frame)\n";
}

void RunRender(RenderArgs& a) {
    if (a.animate > 0) return RunAnimate(a);
    for (const CLI::Option* opt : a.animateOnly)
        if (opt->count() > 0)
            throw Error(opt->get_name() + ": applies only with --animate");
    ResolveRenderSettings(a.options);  // before any file is read or written
    const RenderSettings& s = a.options.settings;
    std::vector<std::string> outputs = RenderOutputNames();
    if (!s.reference) std::erase(outputs, std::string("missed_geometry.png"));
    if (s.shadow != ShadowKind::None || s.ao != AoKind::None)
        outputs.push_back("shadow_fetches.png");
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
                  << (s.shadow != ShadowKind::None || s.ao != AoKind::None
                          ? ",shadow_fetches.png"
                          : "")
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
    cmd->add_option(
           "--animate", a->animate,
           "the ACM paper's dynamic demo: render N frames, each regenerating the "
           "sinusoid height map (as `maps --animate`), preprocessing it with "
           "adaptive ACM and rendering --method (default acm4; csm, qcsm, acm8 "
           "too); prints per-frame times and writes the last frame's outputs")
        ->check(CLI::Range(1, 100000));
    a->animateOnly = {
        cmd->add_option("--animate-size", a->animateSize,
                        "--animate: side of the sinusoid height map, [2, 4096]")
            ->capture_default_str(),
        cmd->add_option("--adaptive-threshold", a->adaptiveThreshold,
                        "--animate: adaptive ACM copies a parent block's ratios when its "
                        "depth range is at most this, [0, 1]")
            ->capture_default_str(),
        cmd->add_option("--adaptive-levels", a->adaptiveLevels,
                        "--animate: adaptive ACM's levels above the finest, [0, 12]")
            ->capture_default_str()};
    a->mapOption = cmd->get_option("--map");
    a->methodOption = cmd->get_option("--method");
    cmd->add_flag(
        "--group-heatmaps", a->groupHeatmaps,
        "also write {quad,group4x2,wave}_{trips,utilisation}.png: the heatmaps of "
        "the 2x2 quads, llvmpipe's 4x2 groups and 64-lane 8x8 waves");
    cmd->callback([a] { RunRender(*a); });
}

}  // namespace reliefsim
