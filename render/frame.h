// The frame driver: scene set-up, the fragment program running a kernel per lane,
// outputs.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/record.h"
#include "kernels/registry.h"
#include "kernels/view_ray.h"
#include "metrics/summary.h"
#include "raster/camera.h"
#include "texture/depth_field.h"
#include "texture/sampler.h"

namespace reliefsim {

/// Most worker threads a run accepts (--threads).
constexpr int kMaxThreads = 1024;

/// Valid ranges of the scene settings beyond their natural bounds (so float arithmetic in
/// the camera and rasterizer stays finite).
constexpr float kMaxDepthScale = 100.0f;  ///< plane widths
constexpr float kMaxTiling = 4096.0f;
constexpr float kMinDistance = 0.01f, kMaxDistance = 1000.0f;  ///< plane widths

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
    SamplerState sampler;     ///< height-map filter and wrap
    int threads = 0;          ///< worker threads; 0 = all cores
    int lanes = 0;            ///< fragment-driver lane width; 0 = the widest the CPU runs
    float iterScaleMin = 0.0f, iterScaleMax = 64.0f;    ///< iterations heatmap scale
    float fetchScaleMin = 0.0f, fetchScaleMax = 64.0f;  ///< fetches heatmap scale
};

/// Throws Error naming the first bad setting (size, angles, depth scale, tiling, threads,
/// scales, method, parameters).
void ValidateSettings(const RenderSettings& settings);

/// Bytes per pixel of one Render() plus WriteRenderOutputs(): the record, the colour
/// buffer and the output conversions (measured: about 107 bytes per pixel at 1024² and
/// 2048²,
/// `/usr/bin/time -v reliefsim render --size 2048x2048`). glcompare, which keeps two
/// records and llvmpipe's targets and their read-back, needs kGlCompareBytesPerPixel.
constexpr uint64_t kRenderBytesPerPixel = 112, kGlCompareBytesPerPixel = 320;

/// Peak memory of a frame of width x height at `bytesPerPixel`, plus a fixed base. The
/// height map and derived maps come on top.
uint64_t EstimateFrameBytes(int width, int height,
                            uint64_t bytesPerPixel = kRenderBytesPerPixel);

/// Throws Error naming --size when such a frame needs more memory than is available
/// (core/memory.h): "--size WxH: needs about 28.0 GiB of memory, 20.1 GiB available; use
/// a smaller --size".
void RequireFrameMemory(int width, int height,
                        uint64_t bytesPerPixel = kRenderBytesPerPixel);

/// Lane cost executed by the driver: for every (group, triangle) with a covered pixel,
/// the group's largest trip count times its lanes, summed. Groups: 2x2 quads, llvmpipe's
/// 4x2, 32-lane warps of 8x4 pixels, 64-lane waves of 8x8, aligned to the image.
struct LaneCosts {
    uint64_t quad = 0, group4x2 = 0, warp32 = 0, wave64 = 0;
};

struct RenderOutput {
    FrameRecord record;
    std::vector<float> color;  ///< RGB in [0,1], 3 floats per pixel, row 0 at the top
    ParamValues params;        ///< resolved kernel parameters
    FrameSummary summary;
    uint64_t nQuads = 0;
    double frameSeconds = 0.0;  ///< wall time of the frame loop (timing only)
    int threads = 0;            ///< threads the frame loop was allowed (timing only)
    int lanes = 0;              ///< lane width of the fragment driver (timing only)
    std::string isa;            ///< its instruction set (timing only)
    LaneCosts laneCost;
};

/// The settings' method with its --set parameters resolved (defaults filled in): the one
/// place render, trace and glcompare configure their kernel.
Kernel SettingsKernel(const RenderSettings& settings);

/// The settings' orbit camera (the scene's plane is raster/mesh.h MakePlane).
Camera SceneCamera(const RenderSettings& settings);

/// The view uniforms of the settings' camera (shared by the C++ and GLSL paths).
ViewUniforms MakeViewUniforms(const RenderSettings& settings);

/// Renders one frame of the textured plane with the settings' method.
RenderOutput Render(const DepthField& field, const RenderSettings& settings);

/// metrics.json content: the contract keys plus extras; timing fields only under
/// "timing".
nlohmann::json MetricsJson(const RenderOutput& out, const RenderSettings& settings,
                           const DepthField& field);

/// Writes color.png, iterations.png, fetches.png, record.exr and metrics.json into
/// outDir, all or nothing (core/output_set.h): every destination is checked first (a
/// folder or other non-file standing where an output goes, a name too long: Error,
/// nothing written), the files are written to temporaries and replace the previous
/// outputs together; any failure restores what was there and removes the folders this
/// call created. Files in outDir that are not outputs are never touched. Missing folders
/// are created as mkdir does (mode 0777 & ~umask). Every file but metrics.json's "timing"
/// is byte-identical for equal inputs and any thread count.
void WriteRenderOutputs(const std::string& outDir, const RenderOutput& out,
                        const RenderSettings& settings, const DepthField& field);

}  // namespace reliefsim
