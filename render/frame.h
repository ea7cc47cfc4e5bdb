// The frame driver: renders the scene (render/scene.h) with the lane driver
// (render/batch.h) behind the rasterizer, into a per-pixel record and a colour buffer.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/record.h"
#include "kernels/registry.h"
#include "metrics/reference_metrics.h"
#include "metrics/summary.h"
#include "render/scene.h"
#include "texture/depth_field.h"

namespace reliefsim {

/// Bytes per pixel of one Render() plus WriteRenderOutputs(): the record, the colour
/// buffer and the output conversions (measured: about 107 bytes per pixel at 1024² and
/// 2048², `/usr/bin/time -v reliefsim render --size 2048x2048`). glcompare, which keeps
/// two records and llvmpipe's targets and their read-back, needs kGlCompareBytesPerPixel.
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
    /// With settings.shadow (else empty), per pixel (row-major, 0 where not covered): the
    /// light ray's fetches, counted apart from the view ray's (record.exr
    /// shadow_fetches), and the light's visibility at the hit in [0, 1].
    std::vector<uint32_t> shadowFetches;
    std::vector<float> visibility;
    /// With settings.ao (else empty), per pixel: the ambient occlusion factor at the hit
    /// in [0, 1] (record.exr ambient_occlusion; its fetch is in shadowFetches).
    std::vector<float> ambient;
    bool hasReference = false;  ///< settings.reference: the two below are set
    ReferenceRecord reference;
    ReferenceSummary referenceSummary;
};

/// Renders one frame of the textured plane with the settings' method.
RenderOutput Render(const DepthField& field, const RenderSettings& settings);

}  // namespace reliefsim
