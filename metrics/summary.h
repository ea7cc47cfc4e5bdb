// Frame summaries and the dissertation's error metric.
#pragma once

#include <cstdint>
#include <vector>

#include "core/record.h"
#include "texture/depth_field.h"
#include "texture/sampler.h"

namespace reliefsim {

/// Per-frame statistics over covered pixels, reduced serially in pixel order
/// (deterministic).
struct FrameSummary {
    uint64_t coveredPixels = 0;
    double avgIterations = 0.0;  ///< mean of coarse + refine iterations
    double avgCoarse = 0.0, avgRefine = 0.0;
    double avgFetches = 0.0;
    uint32_t maxFetches = 0;
    uint64_t totalFetches = 0;
    uint64_t totalTexelReads = 0;
    uint64_t budgetExhaustedPixels = 0;
    uint64_t noHitPixels = 0;
    double msePaper = 0.0;  ///< mean of e^2, e = hit depth - depth sampled at the hit uv
    double sumSqPaper = 0.0;  ///< sum of e^2 (the dissertation reports the sum)
    double maxAbsErrorPaper = 0.0;
    /// llvmpipe cost model (research/llvmpipe.md §3): for each 4x2 pixel block aligned to
    /// the framebuffer, 8 x the maximum fetches of its covered pixels, summed.
    uint64_t laneFetches4x2 = 0;
    /// the same for 8x4 warps (32 lanes)
    uint64_t laneFetches8x4 = 0;
};

/// Per-pixel error of the dissertation's metric (§4.1): hit depth - depth sampled (with
/// the same sampler state, uncounted) at the hit uv. Zero for uncovered pixels.
float PaperError(const FrameRecord& record, size_t i, const DepthField& field,
                 const SamplerState& state);

FrameSummary Summarize(const FrameRecord& record, const DepthField& field,
                       const SamplerState& state);
/// The same from each pixel's PaperError, computed elsewhere (Render computes them in
/// parallel): paperErrors[i] = PaperError(record, i, field, state). The sums run in pixel
/// order either way, so both give the same summary bit for bit.
FrameSummary Summarize(const FrameRecord& record, const std::vector<float>& paperErrors);

}  // namespace reliefsim
