// `reliefsim render`: one frame of one method, with heatmaps, record and metrics.
#include <cstdio>
#include <iostream>

#include "app/commands.h"
#include "app/pipeline.h"
#include "core/error.h"

namespace reliefsim {

namespace {

struct RenderArgs {
    MapOptions map;
    RenderSettings settings;
    std::string size = "512x512";
    std::string filter = "bilinear", wrap = "repeat";
    std::string iterScale, fetchScale;
    std::string out;
    bool quiet = false;
};

void ParseSize(const std::string& text, int& w, int& h) {
    unsigned a = 0, b = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%u%c%u%c", &a, &x, &b, &extra) != 3 || (x != 'x' && x != 'X'))
        throw Error("--size \"" + text + "\": expected WxH, e.g. 512x512");
    w = int(a);
    h = int(b);
}

void ParseScale(const std::string& opt, const std::string& text, float& lo, float& hi) {
    if (text.empty()) return;
    float a = 0, b = 0;
    char c = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%f%c%f%c", &a, &c, &b, &extra) != 3 || c != ':')
        throw Error(opt + " \"" + text + "\": expected MIN:MAX, e.g. 0:64");
    lo = a;
    hi = b;
}

void RunRender(RenderArgs& a) {
    RenderSettings& s = a.settings;
    ParseSize(a.size, s.width, s.height);
    auto filter = ParseFilter(a.filter);
    if (!filter) throw Error("--filter \"" + a.filter + "\": must be nearest, bilinear or min4");
    auto wrap = ParseWrapMode(a.wrap);
    if (!wrap) throw Error("--wrap \"" + a.wrap + "\": must be repeat or clamp");
    s.sampler = {*filter, *wrap};
    ParseScale("--iterations-scale", a.iterScale, s.iterScaleMin, s.iterScaleMax);
    ParseScale("--fetches-scale", a.fetchScale, s.fetchScaleMin, s.fetchScaleMax);
    ValidateSettings(s);  // before any file is read or written
    HeightField field = LoadMapFromOptions(a.map);
    RenderOutput out = Render(field, s);
    WriteRenderOutputs(a.out, out, s, field);
    if (!a.quiet) {
        const FrameSummary& m = out.summary;
        std::cout << "reliefsim render: " << s.method << " on " << field.name << " at " << s.width
                  << "x" << s.height << ": " << m.coveredPixels << " covered pixels, "
                  << m.avgIterations << " iterations/px, " << m.avgFetches
                  << " fetches/px (max " << m.maxFetches << "), mse_paper " << m.msePaper
                  << ", " << out.frameSeconds * 1e3 << " ms\n"
                  << "wrote " << a.out
                  << "/{color.png,iterations.png,fetches.png,record.exr,metrics.json}\n";
    }
}

}  // namespace

void RegisterRenderCommand(CLI::App& root) {
    auto a = std::make_shared<RenderArgs>();
    auto* cmd = root.add_subcommand(
        "render", "render the textured plane with one method; write color.png, iterations.png, "
                  "fetches.png, record.exr and metrics.json into --out");
    AddMapOptions(cmd, a->map);
    cmd->add_option("--method", a->settings.method, "method name (see `reliefsim methods`)")
        ->capture_default_str();
    cmd->add_option("--set", a->settings.set, "kernel parameter key=value (repeatable)");
    cmd->add_option("--size", a->size, "framebuffer WxH")->capture_default_str();
    cmd->add_option("--view-angle", a->settings.viewAngle,
                    "degrees between the view direction and the plane normal, [0, 90)")
        ->capture_default_str();
    cmd->add_option("--azimuth", a->settings.azimuth, "camera azimuth around the normal, degrees")
        ->capture_default_str();
    cmd->add_option("--distance", a->settings.distance, "camera distance, plane widths")
        ->capture_default_str();
    cmd->add_option("--fov", a->settings.fovY, "vertical field of view, degrees")
        ->capture_default_str();
    cmd->add_option("--depth-scale", a->settings.depthScale,
                    "relief depth in plane widths (depth 1 = this), > 0")
        ->capture_default_str();
    cmd->add_option("--tiling", a->settings.tiling, "texture repeats across the plane")
        ->capture_default_str();
    cmd->add_option("--filter", a->filter, "height sampler filter: nearest|bilinear|min4")
        ->capture_default_str();
    cmd->add_option("--wrap", a->wrap, "height sampler wrap: repeat|clamp")->capture_default_str();
    cmd->add_option("--threads", a->settings.threads, "worker threads (0 = all cores)")
        ->capture_default_str();
    cmd->add_option("--iterations-scale", a->iterScale,
                    "fixed MIN:MAX of the iterations heatmap (default 0:64)");
    cmd->add_option("--fetches-scale", a->fetchScale,
                    "fixed MIN:MAX of the fetches heatmap (default 0:64)");
    cmd->add_option("--out", a->out, "output directory (created; files replaced)")->required();
    cmd->add_flag("--quiet", a->quiet, "print nothing on success");
    cmd->callback([a] { RunRender(*a); });
}

}  // namespace reliefsim
