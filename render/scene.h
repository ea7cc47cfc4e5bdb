// The scene, defined once: the textured plane, the orbit camera and its view uniforms,
// and the kernel, all from RenderSettings. Render, trace, glcompare and the benchmarks
// take their scene from here.
#pragma once

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/enum_names.h"
#include "kernels/registry.h"
#include "kernels/shadow_job.h"
#include "raster/camera.h"
#include "raster/mesh.h"
#include "render/kernel_maps.h"
#include "render/view_ray.h"
#include "texture/sampler.h"

namespace reliefsim {

/// Most worker threads a run accepts (--threads).
constexpr int kMaxThreads = 1024;

/// Valid ranges of the scene settings beyond their natural bounds (so float arithmetic in
/// the camera and rasterizer stays finite).
constexpr float kMaxDepthScale = 100.0f;  ///< plane widths
constexpr float kMaxTiling = 4096.0f;
constexpr float kMinDistance = 0.01f, kMaxDistance = 1000.0f;  ///< plane widths

/// The scene's camera: the orbit camera (--view-angle, --azimuth, --distance, --fov) or
/// the orthographic texture-space view of one tile (--view-dir).
enum class CameraKind { Orbit, Ortho };
inline constexpr auto kCameraNames = MakeEnumNames<CameraKind>({
    {"orbit", CameraKind::Orbit},
    {"ortho", CameraKind::Ortho},
});

/// Everything `reliefsim render` takes besides the map. Defaults are the documented ones.
struct RenderSettings {
    std::string method = "relief";
    std::vector<std::string> set;  ///< "key=value" kernel parameters
    int width = 512, height = 512;
    float viewAngle = 45.0f;  ///< degrees from the plane normal, [0, 90)
    float azimuth = 0.0f;     ///< degrees around the normal
    float distance = 1.0f;    ///< camera distance from the plane centre, plane units
    float fovY = 45.0f;       ///< vertical field of view, degrees
    float depthScale = 0.1f;  ///< relief depth in plane units; > 0
    float tiling = 1.0f;      ///< texture repeats across the plane; > 0
    CameraKind camera = CameraKind::Orbit;
    /// The ortho view's tangent-space direction from the eye towards the surface (Z < 0;
    /// any length).
    glm::vec3 viewDir{0.0f, 0.0f, -1.0f};
    /// The directional light of the shading: tangent-space direction (x along +u, y along
    /// +v, z the plane normal) from the surface towards the light, Z > 0, any length.
    glm::vec3 lightDir{-0.4f, -0.5f, 0.77f};
    /// The light-ray kernel of every hit (kernels/shadow.h): none, hard or soft shadows,
    /// with its parameters (--shadow, --shadow-steps, --shadow-softening).
    ShadowKind shadow = ShadowKind::None;
    int shadowSteps = 16;  ///< hard: steps from the surface to the top, [1, 1024]
    float shadowSoftening = 0.58f;  ///< soft: Tatarchuk's softening, [0, 1000]
    float shadowPenumbra = 8.0f;    ///< cone: the penumbra factor k, [0, 1000]
    /// Ambient occlusion of every hit from the kernel's cone map (--ao; csm and cns,
    /// dissertation §4.5; kernels/shadow.h AmbientOcclusion).
    AoKind ao = AoKind::None;
    SamplerState sampler;    ///< height-map filter and wrap
    KernelMapSettings maps;  ///< the kernel's derived maps (cone kernels)
    int threads = 0;         ///< worker threads; 0 = all cores
    int lanes = 0;           ///< fragment-driver lane width; 0 = the widest the CPU runs
    float iterScaleMin = 0.0f, iterScaleMax = 64.0f;    ///< iterations heatmap scale
    float fetchScaleMin = 0.0f, fetchScaleMax = 64.0f;  ///< fetches heatmap scale
    /// Also compute the exact reference of every covered pixel and the metrics against it
    /// (render/reference.h; --no-reference turns it off).
    bool reference = true;
    /// Shade every hit into RenderOutput::color (color.png). Off: the record only, as
    /// llvmpipe's twin writes it (bench/frame_vs_llvmpipe times both sides without
    /// shading); RenderOutput::color is then empty.
    bool shade = true;
};

/// Throws Error naming the first bad setting (size, angles, depth scale, tiling, threads,
/// scales, method, parameters).
void ValidateSettings(const RenderSettings& settings);

/// Refuses a setting that was given but that the others make the render ignore: the
/// orbit camera's view_angle, azimuth, distance and fov with the ortho camera, view_dir
/// with the orbit camera, and the shadow_steps, shadow_softening and shadow_penumbra
/// that the shadow kind does not read. `given(key)` says whether the setting of that key
/// ("view_angle") was given: render asks its options, sweep its configuration's keys.
/// The map cache (cache_dir, no_cache) is refused where none of `methods` (empty: the
/// settings' method) generates a cone map: it reads none, or reads cone_map's file.
/// Throws Error naming the setting (ParamName) and what it applies to.
void RefuseIgnoredSettings(const RenderSettings& settings,
                           const std::function<bool(std::string_view)>& given,
                           std::span<const std::string> methods = {});

/// Whether a render with these settings reads the setting of `key` ("view_angle"): false
/// for the orbit camera's view_angle, azimuth, distance and fov with the ortho camera,
/// view_dir with the orbit camera, and the shadow settings the shadow kind does not read
/// (the rules RefuseIgnoredSettings applies); true for every other key.
bool SettingRead(const RenderSettings& settings, std::string_view key);

/// The scene's plane: the world square [-0.5,0.5]^2 in the z = 0 plane, two triangles,
/// normal +z, tangent +x (u), bitangent -y (v), uv = (x + 0.5, 0.5 - y) * tiling, so
/// texel row 0 (the image's top row) lies on the far edge (+y) for azimuth 0. PixelToRay
/// (render/view_ray.h) intersects exactly this plane.
Mesh MakePlane(float tiling);

/// The unit direction towards the light (settings.lightDir normalised in float).
glm::vec3 SceneLight(const RenderSettings& settings);

/// uv per plane unit times the depth scale: what one unit of depth is in uv along a
/// tangent direction (the view ray's dirUv scale; the shading's slope scale). The orbit
/// camera's plane repeats the texture `tiling` times; the ortho view frames one tile.
float SceneSlopeScale(const RenderSettings& settings);

/// The light-ray kernel of the settings (kernels/shadow.h): kind, parameters and the uv
/// step per unit of rise towards SceneLight.
ShadowJob SceneShadow(const RenderSettings& settings);

/// The settings' method with its --set parameters resolved (defaults filled in): the one
/// place render, trace and glcompare configure their kernel.
Kernel SettingsKernel(const RenderSettings& settings);

/// The settings' orbit camera, looking at the plane's centre.
Camera SceneCamera(const RenderSettings& settings);

/// The view uniforms of the settings' camera (shared by the C++ and GLSL paths).
ViewUniforms MakeViewUniforms(const RenderSettings& settings);

}  // namespace reliefsim
