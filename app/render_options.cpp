// The options of `reliefsim render`, shared by render, glcompare and the llvmpipe
// benchmark.
#include "app/render_options.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "app/enum_option.h"
#include "core/error.h"
#include "core/output_set.h"
#include "core/param_name.h"
#include "core/parse.h"
#include "raster/rasterizer.h"

namespace reliefsim {

void ParseSize(const std::string& text, int& w, int& h) {
    const size_t x = text.find_first_of("xX");
    if (text.empty() || x == std::string::npos || x == 0 || x + 1 == text.size())
        throw Error("--size \"" + text + "\": expected WxH, e.g. 512x512");
    w = int(ParseIntInRange(std::string_view(text).substr(0, x), 1, kMaxImageSize,
                            "--size \"" + text + "\": width"));
    h = int(ParseIntInRange(std::string_view(text).substr(x + 1), 1, kMaxImageSize,
                            "--size \"" + text + "\": height"));
}

namespace {

constexpr double kPi = 3.14159265358979323846;

void ParseScale(const std::string& opt, const std::string& text, float& lo, float& hi) {
    if (text.empty()) return;
    const size_t c = text.find(':');
    std::optional<float> a, b;
    if (c != std::string::npos) {
        a = ParseFiniteFloat(std::string_view(text).substr(0, c));
        b = ParseFiniteFloat(std::string_view(text).substr(c + 1));
    }
    if (!a || !b)
        throw Error(opt + " \"" + text +
                    "\": expected MIN:MAX with finite numbers, e.g. 0:64");
    if (!(*b > *a)) throw Error(opt + " \"" + text + "\": MAX must be greater than MIN");
    lo = *a;
    hi = *b;
}

/// "X,Y,Z": three finite numbers, as --view-dir and --light-dir take them.
glm::vec3 ParseVec3(const std::string& opt, const std::string& text) {
    std::vector<float> c;
    size_t start = 0;
    for (;;) {
        const size_t comma = text.find(',', start);
        const auto part = std::string_view(text).substr(
            start, comma == std::string::npos ? std::string::npos : comma - start);
        const std::optional<float> f = ParseFiniteFloat(part);
        if (!f || c.size() == 3)
            throw Error(opt + " \"" + text + "\": expected X,Y,Z, three numbers");
        c.push_back(*f);
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    if (c.size() != 3)
        throw Error(opt + " \"" + text + "\": expected X,Y,Z, three numbers");
    return {c[0], c[1], c[2]};
}

/// "0:64": a heatmap scale as --iterations-scale takes it.
std::string ScaleText(float lo, float hi) {
    char text[64];
    std::snprintf(text, sizeof text, "%g:%g", double(lo), double(hi));
    return text;
}

}  // namespace

void AddRenderOptions(CLI::App* cmd, RenderOptions& o, bool withHeatmapScales) {
    AddMapOptions(cmd, o.map);
    cmd->add_option("--method", o.settings.method,
                    "method name (see `reliefsim methods`)")
        ->capture_default_str();
    cmd->add_option("--set", o.settings.set, "kernel parameter key=value (repeatable)");
    cmd->add_option("--size", o.size, "framebuffer WxH")->capture_default_str();
    o.command = cmd;
    cmd->add_option("--view-angle", o.settings.viewAngle,
                    "orbit camera: degrees between the view direction and the plane "
                    "normal, [0, 90)")
        ->capture_default_str();
    cmd->add_option("--azimuth", o.settings.azimuth,
                    "orbit camera: azimuth around the normal, degrees")
        ->capture_default_str();
    cmd->add_option("--distance", o.settings.distance,
                    "orbit camera: distance, plane widths")
        ->capture_default_str();
    cmd->add_option("--fov", o.settings.fovY,
                    "orbit camera: vertical field of view, degrees")
        ->capture_default_str();
    cmd->add_option("--depth-scale", o.settings.depthScale,
                    "relief depth in plane widths (depth 1 = this), > 0")
        ->capture_default_str();
    cmd->add_option("--tiling", o.settings.tiling, "texture repeats across the plane")
        ->capture_default_str();
    AddEnumOption(cmd, "--camera", o.settings.camera, kCameraNames,
                  "orbit (--view-angle, --azimuth, --distance, --fov) or ortho: the "
                  "texture-space view of one tile, pixel (x, y) at uv ((x+0.5)/W, "
                  "(y+0.5)/H), one ray direction (--view-dir)");
    cmd->add_option("--view-dir", o.viewDir,
                    "ortho camera: tangent-space direction from the eye towards the "
                    "surface, X,Y,Z with Z < 0")
        ->type_name("X,Y,Z")
        ->default_str("0,0,-1");
    cmd->add_option(
           "--light-dir", o.lightDir,
           "directional light of the shading: tangent-space direction from the "
           "surface towards the light, X,Y,Z with Z > 0 (x along +u, y along +v)")
        ->type_name("X,Y,Z")
        ->default_str("-0.4,-0.5,0.77");
    cmd->add_option("--light-angle", o.lightAngle,
                    "the light as angles: degrees from the plane normal, [0, 90) "
                    "(default 45 when --light-azimuth is given)")
        ->check(CLI::Range(0.0f, 89.99f));
    cmd->add_option("--light-azimuth", o.lightAzimuth,
                    "the light's azimuth, degrees counter-clockwise from +u (default 0 "
                    "when --light-angle is given)");
    AddEnumOption(cmd, "--shadow", o.settings.shadow, kShadowNames,
                  "self-shadowing of every hit by a light ray (docs/methods/shadows.md): "
                  "none, hard (linear search towards the light, --shadow-steps), cone "
                  "(with --method cns: the cone-normal soft shadow, --shadow-steps, "
                  "--shadow-penumbra) or soft "
                  "(Tatarchuk's seven weighted samples, --shadow-softening)");
    cmd->add_option("--shadow-steps", o.settings.shadowSteps,
                    "hard and cone shadows: steps of the light ray from the surface to "
                    "the top")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxShadowSteps));
    cmd->add_option("--shadow-softening", o.settings.shadowSoftening,
                    "soft shadows: Tatarchuk's softening (the DirectX SDK sample's 0.58)")
        ->capture_default_str()
        ->check(CLI::Range(0.0f, kMaxShadowSoftening));
    cmd->add_option("--shadow-penumbra", o.settings.shadowPenumbra,
                    "cone shadows: the distance-field penumbra factor k (larger: harder)")
        ->capture_default_str()
        ->check(CLI::Range(0.0f, kMaxShadowPenumbra));
    AddEnumOption(
        cmd, "--ao", o.settings.ao, kAoNames,
        "ambient occlusion of every hit (docs/methods/shadows.md): none, or cone "
        "(with --method csm or cns: the cone at the hit scales the ambient term "
        "by sin² of its half angle; one fetch, counted in shadow_fetches)");
    AddEnumOption(cmd, "--filter", o.settings.sampler.filter, kFilterNames,
                  "height sampler filter");
    AddEnumOption(cmd, "--wrap", o.settings.sampler.wrap, kWrapModeNames,
                  "height sampler wrap");
    AddEnumOption(cmd, "--texture-format", o.settings.sampler.precision,
                  kTextureFormatNames,
                  "height texture: r32f (float) or r8 (8-bit unorm, filtered in "
                  "llvmpipe's 8.8 fixed point; the map is quantised)");
    cmd->add_option("--threads", o.settings.threads, "worker threads (0 = all cores)")
        ->capture_default_str()
        ->check(CLI::Range(0, kMaxThreads));
    cmd->add_option(
           "--lanes", o.settings.lanes,
           "fragment-driver lane width: 0 = the widest this CPU runs, or 1, 4, 8 "
           "(AVX2), 16 (AVX-512); results are identical for every width")
        ->capture_default_str()
        ->check(CLI::IsMember({0, 1, 4, 8, 16}));
    cmd->add_option("--cone-encoding", o.coneEncoding,
                    "cone kernels: how the cone map is stored, " + ConeEncodingList() +
                        " (default: as the kernel's paper stores it; csm u8sqrt, rcs u8)")
        ->type_name("ENC");
    cmd->add_option("--cache-dir", o.settings.maps.cacheDir,
                    "disk cache of the cone kernels' generated maps (default "
                    "$XDG_CACHE_HOME/reliefsim or ~/.cache/reliefsim)")
        ->type_name("DIR");
    cmd->add_flag("!--no-cache", o.settings.maps.useCache,
                  "cone kernels: generate their maps without the disk cache");
    cmd->add_option("--cone-map", o.settings.maps.coneMap,
                    "cone kernels: use this map (EXR, PNG, TGA, ... of the height map's "
                    "size) instead of generating one, e.g. GPU Gems 3's "
                    "tile1_relaxedcone.tga with --cone-map-channel B")
        ->type_name("FILE");
    cmd->add_option("--cone-map-channel", o.coneMapChannel,
                    "with --cone-map: the ratio's channel, R|G|B|A (default R); "
                    "directional kernels (qcsm, acm4) read RGBA")
        ->type_name("C");
    AddEnumOption(
        cmd, "--cone-bounds", o.settings.maps.bounds, kConeBoundsNames,
        "cone kernels (csm, qcsm, acm4, acm8, cns): the surface their generated "
        "map bounds, the texel centres (as the papers) or the bilinear surface "
        "between them (conservative for it with any cone_filter)");
    cmd->add_option("--cone-map-encoding", o.coneMapEncoding,
                    "with --cone-map: how its values store the ratio, " +
                        ConeEncodingList() +
                        " (default: the kernel's, as --cone-encoding)")
        ->type_name("ENC");
    if (!withHeatmapScales) return;
    cmd->add_flag("--reference,!--no-reference", o.settings.reference,
                  "also compute the exact reference of every pixel and the metrics "
                  "against it (on by default)");
    const RenderSettings& s = o.settings;
    cmd->add_option("--iterations-scale", o.iterScale,
                    "fixed MIN:MAX of the iterations heatmap")
        ->type_name("MIN:MAX")
        ->default_str(ScaleText(s.iterScaleMin, s.iterScaleMax));
    cmd->add_option("--fetches-scale", o.fetchScale,
                    "fixed MIN:MAX of the fetches heatmap")
        ->type_name("MIN:MAX")
        ->default_str(ScaleText(s.fetchScaleMin, s.fetchScaleMax));
}

void ResolveRenderSettings(RenderOptions& o) {
    RenderSettings& s = o.settings;
    ParseSize(o.size, s.width, s.height);
    ParseScale("--iterations-scale", o.iterScale, s.iterScaleMin, s.iterScaleMax);
    ParseScale("--fetches-scale", o.fetchScale, s.fetchScaleMin, s.fetchScaleMax);
    RefuseIgnoredSettings(
        s,
        [&](std::string_view key) {
            const CLI::Option* opt =
                o.command ? o.command->get_option_no_throw(FlagName(key)) : nullptr;
            return opt && opt->count() > 0;
        },
        o.methods);
    if (!o.viewDir.empty()) s.viewDir = ParseVec3("--view-dir", o.viewDir);
    if (!o.lightDir.empty()) {
        if (o.lightAngle || o.lightAzimuth)
            throw Error("--light-dir " + o.lightDir +
                        ": give the light either as --light-dir or as --light-angle / "
                        "--light-azimuth, not both");
        s.lightDir = ParseVec3("--light-dir", o.lightDir);
    } else if (o.lightAngle || o.lightAzimuth) {
        if (o.lightAngle && !std::isfinite(*o.lightAngle))
            throw Error("--light-angle: must be a finite number in [0, 90)");
        if (o.lightAzimuth && !(std::fabs(*o.lightAzimuth) <= 1e6f))  // as --azimuth
            throw Error("--light-azimuth: must be a finite angle in [-1e6, 1e6] degrees");
        const double a = double(o.lightAngle.value_or(45.0f)) * kPi / 180.0,
                     b = double(o.lightAzimuth.value_or(0.0f)) * kPi / 180.0;
        s.lightDir = glm::vec3(float(std::sin(a) * std::cos(b)),
                               float(std::sin(a) * std::sin(b)), float(std::cos(a)));
    }
    if (!o.coneEncoding.empty()) {
        const auto e = ParseConeEncoding(o.coneEncoding);
        if (!e)
            throw Error("--cone-encoding \"" + o.coneEncoding +
                        "\": unknown; must be one of: " + ConeEncodingList());
        s.maps.encoding = *e;
    }
    if (s.maps.coneMap.empty()) {
        if (!o.coneMapChannel.empty())
            throw Error("--cone-map-channel: applies with --cone-map");
        if (!o.coneMapEncoding.empty())
            throw Error("--cone-map-encoding: applies with --cone-map");
    } else {
        if (!o.coneEncoding.empty())
            throw Error(
                "--cone-encoding: applies to generated maps; give the encoding of "
                "--cone-map's values with --cone-map-encoding");
        if (!o.coneMapEncoding.empty()) {
            const auto e = ParseConeEncoding(o.coneMapEncoding);
            if (!e)
                throw Error("--cone-map-encoding \"" + o.coneMapEncoding +
                            "\": unknown; must be one of: " + ConeEncodingList());
            s.maps.encoding = *e;
        }
        if (!o.coneMapChannel.empty()) {
            static constexpr std::string_view kChannels = "RGBA";
            const std::string& c = o.coneMapChannel;
            const size_t at =
                c.size() == 1
                    ? kChannels.find(char(std::toupper(static_cast<unsigned char>(c[0]))))
                    : std::string_view::npos;
            if (at == std::string_view::npos)
                throw Error("--cone-map-channel \"" + c + "\": must be R, G, B or A");
            s.maps.coneMapChannel = int(at);
        }
    }
    if (!s.maps.cacheDir.empty()) {
        std::error_code ec;
        const auto st = std::filesystem::status(s.maps.cacheDir, ec);
        if (std::filesystem::exists(st) && !std::filesystem::is_directory(st))
            throw Error("--cache-dir \"" + s.maps.cacheDir +
                        "\": exists and is not a directory");
    }
    ValidateSettings(s);
}

std::pair<int, int> ParsePixel(const std::string& option, const std::string& text,
                               int width, int height) {
    const size_t comma = text.find(',');
    if (text.empty() || comma == std::string::npos || comma == 0 ||
        comma + 1 == text.size())
        throw Error(option + " \"" + text +
                    "\": expected X,Y, e.g. 10,20 (row 0 at the top)");
    const std::string subject = option + " \"" + text + "\":";
    const int x =
        int(ParseIntInRange(std::string_view(text).substr(0, comma), 0, width - 1,
                            subject + " X (the image is " + std::to_string(width) + "x" +
                                std::to_string(height) + ")"));
    const int y =
        int(ParseIntInRange(std::string_view(text).substr(comma + 1), 0, height - 1,
                            subject + " Y (the image is " + std::to_string(width) + "x" +
                                std::to_string(height) + ")"));
    return {x, y};
}

void CheckOutputFile(const std::string& option, const std::string& path,
                     bool folderIsCreated) {
    if (!folderIsCreated) {
        std::error_code ec;
        const std::filesystem::path folder =
            std::filesystem::absolute(path, ec).lexically_normal().parent_path();
        if (!std::filesystem::is_directory(folder, ec))
            throw Error(option + " \"" + path + "\": folder \"" + folder.string() +
                        "\" does not exist or is not a directory");
    }
    CheckOutputDestination(path, option);
}

void CheckOutputDirectory(const std::string& option, const std::string& dir,
                          const std::vector<std::string>& outputs) {
    namespace fs = std::filesystem;
    if (dir.empty()) throw Error(option + ": empty; give a directory");
    std::error_code ec;
    const fs::file_status st = fs::status(dir, ec);
    if (fs::exists(st) && !fs::is_directory(st))
        throw Error(option + " \"" + dir + "\": exists and is not a directory");
    for (const std::string& name : outputs)
        CheckOutputDestination((fs::path(dir) / name).string(), option);
}

DepthField LoadRenderMap(const RenderOptions& o) {
    DepthField field = LoadMapFromOptions(o.map);
    if (o.settings.sampler.precision == Precision::Llvmpipe8 &&
        field.depth8.size() != field.depth.size())
        field = QuantizeToUnorm8(field);
    return field;
}

}  // namespace reliefsim
