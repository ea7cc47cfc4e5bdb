// The options of `reliefsim render`, shared by render, glcompare and the llvmpipe benchmark.
#include "app/render_options.h"

#include <cstdio>

#include "core/error.h"

namespace reliefsim {

namespace {

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

}  // namespace

void AddRenderOptions(CLI::App* cmd, RenderOptions& o) {
    AddMapOptions(cmd, o.map);
    cmd->add_option("--method", o.settings.method, "method name (see `reliefsim methods`)")
        ->capture_default_str();
    cmd->add_option("--set", o.settings.set, "kernel parameter key=value (repeatable)");
    cmd->add_option("--size", o.size, "framebuffer WxH")->capture_default_str();
    cmd->add_option("--view-angle", o.settings.viewAngle,
                    "degrees between the view direction and the plane normal, [0, 90)")
        ->capture_default_str();
    cmd->add_option("--azimuth", o.settings.azimuth, "camera azimuth around the normal, degrees")
        ->capture_default_str();
    cmd->add_option("--distance", o.settings.distance, "camera distance, plane widths")
        ->capture_default_str();
    cmd->add_option("--fov", o.settings.fovY, "vertical field of view, degrees")
        ->capture_default_str();
    cmd->add_option("--depth-scale", o.settings.depthScale,
                    "relief depth in plane widths (depth 1 = this), > 0")
        ->capture_default_str();
    cmd->add_option("--tiling", o.settings.tiling, "texture repeats across the plane")
        ->capture_default_str();
    cmd->add_option("--filter", o.filter, "height sampler filter: nearest|bilinear|min4")
        ->capture_default_str();
    cmd->add_option("--wrap", o.wrap, "height sampler wrap: repeat|clamp")->capture_default_str();
    cmd->add_option("--texture-format", o.textureFormat,
                    "height texture: r32f (float) or r8 (8-bit unorm, filtered in llvmpipe's "
                    "8.8 fixed point; the map is quantised)")
        ->capture_default_str();
    cmd->add_option("--threads", o.settings.threads, "worker threads (0 = all cores)")
        ->capture_default_str();
    cmd->add_option("--iterations-scale", o.iterScale,
                    "fixed MIN:MAX of the iterations heatmap (default 0:64)");
    cmd->add_option("--fetches-scale", o.fetchScale,
                    "fixed MIN:MAX of the fetches heatmap (default 0:64)");
}

void ResolveRenderSettings(RenderOptions& o) {
    RenderSettings& s = o.settings;
    ParseSize(o.size, s.width, s.height);
    auto filter = ParseFilter(o.filter);
    if (!filter) throw Error("--filter \"" + o.filter + "\": must be nearest, bilinear or min4");
    auto wrap = ParseWrapMode(o.wrap);
    if (!wrap) throw Error("--wrap \"" + o.wrap + "\": must be repeat or clamp");
    s.sampler.filter = *filter;
    s.sampler.wrap = *wrap;
    if (o.textureFormat == "r32f") {
        s.sampler.precision = Precision::Float;
    } else if (o.textureFormat == "r8") {
        s.sampler.precision = Precision::Llvmpipe8;
    } else {
        throw Error("--texture-format \"" + o.textureFormat + "\": must be r32f or r8");
    }
    ParseScale("--iterations-scale", o.iterScale, s.iterScaleMin, s.iterScaleMax);
    ParseScale("--fetches-scale", o.fetchScale, s.fetchScaleMin, s.fetchScaleMax);
    ValidateSettings(s);
}

HeightField LoadRenderMap(const RenderOptions& o) {
    HeightField field = LoadMapFromOptions(o.map);
    if (o.settings.sampler.precision == Precision::Llvmpipe8 &&
        field.depth8.size() != field.depth.size())
        field = QuantizeToUnorm8(field);
    return field;
}

}  // namespace reliefsim
