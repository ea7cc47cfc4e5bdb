// The scene: settings validation, the plane, the camera, its view uniforms and the
// kernel.
#include "render/scene.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/param_name.h"
#include "core/parse.h"
#include "render/batch.h"

namespace reliefsim {

void ValidateSettings(const RenderSettings& s) {
    auto bad = [](const std::string& what) { throw Error(what); };
    if (s.width < 1 || s.height < 1 || s.width > 16384 || s.height > 16384)
        bad(ParamName("size") + " " + std::to_string(s.width) + "x" +
            std::to_string(s.height) + ": each side must be in [1, 16384]");
    if (!(s.viewAngle >= 0.0f && s.viewAngle < 90.0f))
        bad(ParamName("view_angle") + " " + FloatText(s.viewAngle) +
            ": must be in [0, 90) degrees");
    if (!(std::fabs(s.azimuth) <= 1e6f))
        bad(ParamName("azimuth") + " " + FloatText(s.azimuth) +
            ": must be a finite angle in [-1e6, 1e6] degrees");
    if (!(s.depthScale > 0.0f && s.depthScale <= kMaxDepthScale))
        bad(ParamName("depth_scale") + " " + FloatText(s.depthScale) +
            ": must be in (0, " + FloatText(kMaxDepthScale) + "] plane widths");
    if (!(s.tiling > 0.0f && s.tiling <= kMaxTiling))
        bad(ParamName("tiling") + " " + FloatText(s.tiling) + ": must be in (0, " +
            FloatText(kMaxTiling) + "]");
    if (!(s.distance >= kMinDistance && s.distance <= kMaxDistance))
        bad(ParamName("distance") + " " + FloatText(s.distance) + ": must be in [" +
            FloatText(kMinDistance) + ", " + FloatText(kMaxDistance) + "] plane widths");
    if (!(s.fovY > 0.0f && s.fovY < 180.0f))
        bad(ParamName("fov") + " " + FloatText(s.fovY) + ": must be in (0, 180) degrees");
    if (s.threads < 0 || s.threads > kMaxThreads)
        bad(ParamName("threads") + " " + std::to_string(s.threads) + ": must be in [0, " +
            std::to_string(kMaxThreads) + "]");
    if (!std::isfinite(s.iterScaleMin) || !std::isfinite(s.iterScaleMax) ||
        !(s.iterScaleMax > s.iterScaleMin))
        bad(ParamName("iterations_scale") +
            ": MIN and MAX must be finite with MAX > MIN");
    if (!std::isfinite(s.fetchScaleMin) || !std::isfinite(s.fetchScaleMax) ||
        !(s.fetchScaleMax > s.fetchScaleMin))
        bad(ParamName("fetches_scale") + ": MIN and MAX must be finite with MAX > MIN");
    if (s.shadowSteps < 1 || s.shadowSteps > kMaxShadowSteps)
        bad(ParamName("shadow_steps") + " " + std::to_string(s.shadowSteps) +
            ": must be in [1, " + std::to_string(kMaxShadowSteps) + "]");
    if (!(s.shadowSoftening >= 0.0f && s.shadowSoftening <= kMaxShadowSoftening))
        bad(ParamName("shadow_softening") + " " + FloatText(s.shadowSoftening) +
            ": must be in [0, " + FloatText(kMaxShadowSoftening) + "]");
    if (!(s.shadowPenumbra >= 0.0f && s.shadowPenumbra <= kMaxShadowPenumbra))
        bad(ParamName("shadow_penumbra") + " " + FloatText(s.shadowPenumbra) +
            ": must be in [0, " + FloatText(kMaxShadowPenumbra) + "]");
    if (s.ao == AoKind::Cone) {
        // The AO term reads the cone of csm's or cns's map at the hit (004 §4.5: the
        // relaxed cones of rcs and rcns "did not allow generating good approximations").
        const auto maps = s.method == kExactMethod ? decltype(FindMethod(s.method).maps){}
                                                   : FindMethod(s.method).maps;
        if (maps.size() != 1 || (maps[0] != "cone" && maps[0] != "cone-normal"))
            bad(ParamName("ao") +
                " cone: reads the cone map of method csm or cns (dissertation §4.5: "
                "CSM's "
                "ratio or CNS's cone normal); " +
                ParamName("method") + " " + s.method + " binds " +
                (maps.empty() ? std::string("no derived map")
                              : "the \"" + std::string(maps[0]) + "\" map") +
                "; use " + ParamName("method") + " csm or cns");
    }
    if (s.shadow == ShadowKind::Cone) {
        // The cone-normal soft shadow reads the cone normal of cns's map (004 §4.4).
        const auto maps = FindMethod(s.method).maps;
        if (maps.size() != 1 || maps[0] != "cone-normal")
            bad(ParamName("shadow") +
                " cone: reads the cone-normal map of method cns (dissertation "
                "§4.4); " +
                ParamName("method") + " " + s.method + " binds " +
                (maps.empty() ? std::string("no derived map")
                              : "the \"" + std::string(maps[0]) + "\" map") +
                "; use " + ParamName("method") + " cns, or " + ParamName("shadow") +
                " hard|soft");
    }
    if (s.camera == CameraKind::Ortho) {
        const glm::vec3 d = s.viewDir;
        const std::string text =
            FloatText(d.x) + "," + FloatText(d.y) + "," + FloatText(d.z);
        if (!(std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z)))
            bad(ParamName("view_dir") + " " + text + ": must be finite");
        if (!(d.z < 0.0f))
            bad(ParamName("view_dir") + " " + text +
                ": Z must be < 0 (the direction from the eye towards the surface)");
        if (!(std::hypot(double(d.x), double(d.y)) <= 1000.0 * -double(d.z)))
            bad(ParamName("view_dir") + " " + text +
                ": within 89.94 degrees of the normal (|XY| <= 1000 |Z|)");
        if (s.tiling != 1.0f)
            bad(ParamName("tiling") + " " + FloatText(s.tiling) +
                ": the ortho camera frames exactly one tile; leave " +
                ParamName("tiling") + " at 1");
    }
    {
        const glm::vec3 l = s.lightDir;
        const std::string text =
            FloatText(l.x) + "," + FloatText(l.y) + "," + FloatText(l.z);
        if (!(std::isfinite(l.x) && std::isfinite(l.y) && std::isfinite(l.z)))
            bad(ParamName("light_dir") + " " + text + ": must be finite");
        if (!(l.z > 0.0f))
            bad(ParamName("light_dir") + " " + text +
                ": Z must be > 0 (the light is above the surface)");
        if (!(std::hypot(double(l.x), double(l.y)) <= 1e6 * double(l.z)))
            bad(ParamName("light_dir") + " " + text + ": |XY| must be <= 1e6 Z");
    }
    if (s.reference && !s.shade)
        bad(ParamName("shade") +
            ": off, but the reference's metrics compare the shaded colours; turn the "
            "reference off too");
    if (s.method == kExactMethod) {
        if (!s.set.empty())
            bad(ParamName("set") + " " + s.set.front() +
                ": method exact takes no parameters");
        if (s.sampler.filter != Filter::Bilinear)
            bad(ParamName("filter") + " " +
                std::string(kFilterNames.Name(s.sampler.filter)) +
                ": method exact intersects the bilinear surface; use " +
                ParamName("filter") + " bilinear");
    } else {
        const KernelInfo& info = FindMethod(s.method);
        const Kernel kernel = MakeKernel(info, ResolveParams(info, s.set));
        ValidateKernelMaps(kernel, s.sampler, s.maps);
    }
    if (!s.maps.coneMap.empty()) {
        if (s.method == kExactMethod || FindMethod(s.method).maps.empty())
            bad(ParamName("cone_map") + ": method " + s.method + " reads no cone map");
        const KernelInfo& info = FindMethod(s.method);
        const auto spec = ParseKernelMap(info.maps[0]);
        if (spec && ChannelCount(spec->kind) != 1 && s.maps.coneMapChannel >= 0)
            bad(ParamName("cone_map_channel") + ": method " + s.method + " reads all " +
                (ChannelCount(spec->kind) == 8
                     ? std::string("eight channels (acm8 map: 8 channels, or two RGBA "
                                   "halves side by side)")
                     : std::string("four channels (") + std::string(info.maps[0]) +
                           " map: RGBA)"));
    }
    if (s.maps.coneMapChannel > 3)
        bad(ParamName("cone_map_channel") + ": must be R, G, B or A");
    if (s.maps.encoding &&
        (s.method == kExactMethod || FindMethod(s.method).maps.empty()))
        bad(ParamName("cone_encoding") + ": method " + s.method + " reads no cone map");
    if (s.maps.bounds == ConeBounds::Bilinear) {
        const std::string opt = ParamName("cone_bounds") + " bilinear";
        if (s.method == kExactMethod || FindMethod(s.method).maps.empty())
            bad(opt + ": method " + s.method + " reads no cone map");
        const std::string_view name = FindMethod(s.method).maps[0];
        const auto spec = ParseKernelMap(name);
        if (!spec || !HasBilinearBounds(spec->kind) || spec->params.relaxed ||
            spec->params.normal)
            bad(opt + ": method " + s.method + " reads a \"" + std::string(name) +
                "\" map, which has no bilinear-bound variant (csm, qcsm, acm4, acm8 and "
                "cns read one that has)");
        if (!s.maps.coneMap.empty())
            bad(opt + ": applies to generated maps, not to " + ParamName("cone_map"));
        if (s.maps.generator)
            bad(opt + ": the map generator given (adaptive ACM) makes texel-bound maps");
    }
    PickLaneWidth(s.lanes);
}

namespace {

/// The settings that only some cameras or shadow kinds read (RefuseIgnoredSettings,
/// SettingRead).
/// The setting whose value decides whether a key is read.
enum class Decider { Camera, Shadow };

struct SettingRule {
    const char* key;
    bool (*read)(const RenderSettings&);
    Decider decider;
    const char* appliesTo;  ///< its values that read the key
    const char* instead;    ///< what the other values read instead, or null
};

bool Orbit(const RenderSettings& s) { return s.camera == CameraKind::Orbit; }
bool Ortho(const RenderSettings& s) { return s.camera == CameraKind::Ortho; }
bool HardOrCone(const RenderSettings& s) {
    return s.shadow == ShadowKind::Hard || s.shadow == ShadowKind::Cone;
}
bool Soft(const RenderSettings& s) { return s.shadow == ShadowKind::Soft; }
bool ConeShadow(const RenderSettings& s) { return s.shadow == ShadowKind::Cone; }

constexpr SettingRule kSettingRules[] = {
    {"view_angle", Orbit, Decider::Camera, "orbit", "view_dir"},
    {"azimuth", Orbit, Decider::Camera, "orbit", "view_dir"},
    {"distance", Orbit, Decider::Camera, "orbit", "view_dir"},
    {"fov", Orbit, Decider::Camera, "orbit", "view_dir"},
    {"view_dir", Ortho, Decider::Camera, "ortho", nullptr},
    {"shadow_steps", HardOrCone, Decider::Shadow, "hard or cone", nullptr},
    {"shadow_softening", Soft, Decider::Shadow, "soft", nullptr},
    {"shadow_penumbra", ConeShadow, Decider::Shadow, "cone", nullptr},
};

}  // namespace

void RefuseIgnoredSettings(const RenderSettings& s,
                           const std::function<bool(std::string_view)>& given,
                           std::span<const std::string> methods) {
    const std::span<const std::string> rendered =
        methods.empty() ? std::span<const std::string>(&s.method, 1) : methods;
    for (const char* key : {"cache_dir", "no_cache"}) {
        if (!given(key)) continue;
        if (!s.maps.coneMap.empty())
            throw Error(ParamName(key) + ": applies to generated cone maps; " +
                        ParamName("cone_map") + " gives the map");
        const auto generates = [](const std::string& m) {
            return m != kExactMethod && !FindMethod(m).maps.empty();
        };
        if (std::none_of(rendered.begin(), rendered.end(), generates)) {
            std::string names;
            for (const std::string& m : rendered) names += (names.empty() ? "" : ",") + m;
            throw Error(
                ParamName(key) + ": applies to the cone kernels' generated maps; " +
                (rendered.size() > 1
                     ? "none of " + ParamName("method") + " " + names + " reads one"
                     : ParamName("method") + " " + names + " reads none"));
        }
    }
    for (const SettingRule& r : kSettingRules) {
        if (!given(r.key) || r.read(s)) continue;
        const bool camera = r.decider == Decider::Camera;
        const std::string setting = ParamName(camera ? "camera" : "shadow");
        const std::string current(camera ? kCameraNames.Name(s.camera)
                                         : kShadowNames.Name(s.shadow));
        throw Error(ParamName(r.key) + ": applies to " + setting + " " + r.appliesTo +
                    ", not " + setting + " " + current +
                    (r.instead ? std::string(", which reads ") + ParamName(r.instead)
                               : std::string()));
    }
}

bool SettingRead(const RenderSettings& s, std::string_view key) {
    for (const SettingRule& r : kSettingRules)
        if (r.key == key) return r.read(s);
    return true;
}

Mesh MakePlane(float tiling) {
    Mesh mesh;
    const glm::vec2 corners[4] = {
        {-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
    for (const glm::vec2& c : corners) {
        Vertex v;
        v.position = glm::vec3(c, 0.0f);
        v.uv = glm::vec2((c.x + 0.5f) * tiling, (0.5f - c.y) * tiling);
        v.tangent = glm::vec3(1.0f, 0.0f, 0.0f);
        v.bitangent = glm::vec3(0.0f, -1.0f, 0.0f);
        v.normal = glm::vec3(0.0f, 0.0f, 1.0f);
        mesh.vertices.push_back(v);
    }
    mesh.indices = {0, 1, 2, 0, 2, 3};  // counter-clockwise seen from +z
    return mesh;
}

glm::vec3 SceneLight(const RenderSettings& s) { return UnitLight(s.lightDir); }

float SceneSlopeScale(const RenderSettings& s) {
    return s.camera == CameraKind::Ortho ? s.depthScale : s.depthScale * s.tiling;
}

ShadowJob SceneShadow(const RenderSettings& s) {
    ShadowJob j;
    j.kind = s.shadow;
    j.steps = s.shadowSteps;
    j.stepInv = 1.0f / float(s.shadowSteps);
    j.softening = s.shadowSoftening;
    j.penumbra = s.shadowPenumbra;
    const glm::vec3 l = SceneLight(s);
    const float k = SceneSlopeScale(s);
    j.lu = (l.x / l.z) * k;
    j.lv = (l.y / l.z) * k;
    j.rayLength = std::sqrt((j.lu * j.lu + j.lv * j.lv) + 1.0f);
    j.ao = s.ao;
    if (s.ao != AoKind::None && s.method != kExactMethod) {
        const auto maps = FindMethod(s.method).maps;
        j.aoFromNz = maps.size() == 1 && maps[0] == "cone-normal";
    }
    return j;
}

Kernel SettingsKernel(const RenderSettings& s) {
    const KernelInfo& method = FindMethod(s.method);
    return MakeKernel(method, ResolveParams(method, s.set));
}

Camera SceneCamera(const RenderSettings& s) {
    if (s.camera == CameraKind::Ortho) return MakeTileOrthoCamera();
    return MakeOrbitCamera(s.viewAngle, s.azimuth, s.distance, s.fovY,
                           float(s.width) / float(s.height));
}

ViewUniforms MakeViewUniforms(const RenderSettings& s) {
    Camera cam = SceneCamera(s);
    const glm::mat4& v = cam.viewFromWorld;
    const double tanY = std::tan(double(s.fovY) * 0.5 * 3.14159265358979323846 / 180.0);
    const double tanX = tanY * double(s.width) / double(s.height);
    ViewUniforms u;
    u.eye = cam.eye;
    u.right = glm::vec3(float(double(v[0][0]) * tanX), float(double(v[1][0]) * tanX),
                        float(double(v[2][0]) * tanX));
    u.up = glm::vec3(float(double(v[0][1]) * tanY), float(double(v[1][1]) * tanY),
                     float(double(v[2][1]) * tanY));
    u.forward = glm::vec3(-v[0][2], -v[1][2], -v[2][2]);
    u.width = float(s.width);
    u.height = float(s.height);
    u.tiling = s.tiling;
    u.depthScale = s.depthScale;
    if (s.camera == CameraKind::Ortho) {
        // DESIGN.md conventions: dirUv = -view_ts.xy / view_ts.z * depth scale, in float.
        u.ortho = 1;
        u.orthoDu = -(s.viewDir.x / s.viewDir.z) * s.depthScale;
        u.orthoDv = -(s.viewDir.y / s.viewDir.z) * s.depthScale;
        const glm::vec3 d = s.viewDir;
        u.orthoViewZ = -d.z / std::sqrt((d.x * d.x + d.y * d.y) + d.z * d.z);
    }
    return u;
}

}  // namespace reliefsim
