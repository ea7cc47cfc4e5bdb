// Lane batches: the fragment driver's unit of work, and the choice of lane width and ISA.
//
// A batch is n rays in structure-of-arrays form. The driver runs them in packs of its
// lane width (1, 4, 8 or 16), each pack until its last lane finishes, and writes per-lane
// results. Each width lives in its own translation unit compiled for its ISA
// (batch_w*.cpp); one binary picks the widest the CPU runs (PickLaneWidth). Results are
// bit-identical for every width (tests/render/lane_width_test.cpp).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <glm/vec3.hpp>
#include <memory>
#include <span>
#include <string>

#include "kernels/registry.h"
#include "kernels/shadow.h"
#include "render/view_ray.h"
#include "texture/lane_sampler.h"

namespace reliefsim {

/// n rays in, n results out (structure of arrays; the caller owns the memory). The rays
/// are given either directly (uEntry, vEntry, du, dv) or as pixels (px, py) of the view
/// BatchJob::view, turned into rays on the lanes exactly as PixelToRay does.
struct LaneBatch {
    int n = 0;
    const float *uEntry = nullptr, *vEntry = nullptr;  ///< MarchInput::uvEntry
    const float *du = nullptr, *dv = nullptr;          ///< MarchInput::dirUv
    const float* viewZ = nullptr;  ///< MarchInput::viewZ; null: 1 for every ray
    const int32_t *px = nullptr, *py = nullptr;  ///< or pixels (row 0 at the top)
    float* rgb = nullptr;  ///< when set, 3 floats per lane: the shaded hit (ShadeHit)
    float *u = nullptr, *v = nullptr, *depth = nullptr;  ///< returned point
    uint16_t *nCoarse = nullptr, *nRefine = nullptr;
    uint32_t *fetches = nullptr, *texelReads = nullptr;
    uint8_t* flags = nullptr;  ///< kFlagNoHit | kFlagBudgetExhausted (core/record.h)
    /// With BatchJob::shadow on: per lane, the light-ray fetches and the light's
    /// visibility at the hit (kernels/shadow.h); both may be null.
    uint32_t* shadowFetches = nullptr;
    float* visibility = nullptr;
    /// With BatchJob::shadow's ambient occlusion on: per lane, the AO factor (may be
    /// null).
    float* ambient = nullptr;
};

/// One fetch of a traced lane: where, at which ray depth, what came back.
struct TracedFetch {
    float u, v, t, sampled;
};
using TraceSink = std::function<void(const TracedFetch&)>;

/// `d` scaled to unit length in float (the shading's light direction).
inline glm::vec3 UnitLight(glm::vec3 d) {
    const float inv = 1.0f / std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    return {d.x * inv, d.y * inv, d.z * inv};
}

/// What every width's entry point receives: the kernel (its index in KernelTypes and its
/// Params, built by MakeKernelParams), the fetch budget and the textures.
struct BatchJob {
    int kernelIndex = 0;
    const void* params = nullptr;
    uint32_t budget = 0;
    Textures textures;
    const ViewUniforms* view = nullptr;  ///< for batches given as pixels
    float slopeScale = 1.0f;             ///< depth scale x tiling, for shading
    /// Unit tangent-space direction towards the light, for shading (SceneLight).
    glm::vec3 light = UnitLight({-0.4f, -0.5f, 0.77f});
    ShadowJob shadow;  ///< the light-ray kernel of every hit (none: no shadows)
};

using BatchFn = void (*)(const BatchJob& job, LaneBatch& batch);

/// The sampler microbenchmark's loop: n lanes each make `chain` dependent counted fetches
/// (the next uv moves by the sampled value, so fetches cannot overlap within a lane, as
/// in a kernel); returns a checksum and adds the texels read to *texelReads (null: the
/// same loop without counting, the benchmark's baseline).
using SampleChainFn = float (*)(const Textures& textures, const float* u, const float* v,
                                int n, int chain, uint64_t* texelReads);

/// n fetches, one per lane of consecutive packs (the last pack padded with inactive
/// lanes): out[i] = the height sampler at (u[i], v[i]); texels[i] = the texels it read.
/// The lane sampler's test entry point.
using SampleLanesFn = void (*)(const Textures& textures, const float* u, const float* v,
                               int n, float* out, uint32_t* texels);

/// The lane widths this binary has, in increasing order, and whether this CPU runs each.
struct LaneWidthInfo {
    int width;
    const char* isa;  ///< "baseline" (x86-64 SSE2), "avx2" (with FMA), "avx512"
    bool supported;
    BatchFn fn;
    SampleChainFn sampleChain;
    SampleLanesFn sampleLanes;
};
std::span<const LaneWidthInfo> LaneWidths();

/// The batch function of `width` lanes; 0 = the widest this CPU supports. Throws Error
/// (naming --lanes) for a width the binary lacks or the CPU cannot run.
const LaneWidthInfo& PickLaneWidth(int width);

/// Kernel parameters as the kernel's Params, type-erased for BatchJob::params.
std::shared_ptr<const void> MakeKernelParams(int kernelIndex, const ParamValues& values);

/// One ray through the single-lane reference, with its result and counts; every fetch is
/// reported to `trace` when set.
struct RayRun {
    MarchResult result;
    FetchCounts counts;
};
RayRun MarchRay(const BatchJob& job, const MarchInput& in, const TraceSink& trace = {});

/// One ray through a given lane width's batch function (as lane 0 of a pack).
RayRun MarchRayAt(const LaneWidthInfo& width, const BatchJob& job, const MarchInput& in);

/// A BatchJob for a configured kernel; `params` keeps its Params alive. Binds the padded
/// texels (BindTextures) when `textures` has none.
BatchJob MakeBatchJob(const Kernel& kernel, const Textures& textures,
                      std::shared_ptr<const void>& params);

}  // namespace reliefsim
