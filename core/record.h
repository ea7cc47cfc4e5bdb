// The per-pixel record shared by kernels (producer), the frame loop and metrics
// (consumers).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace reliefsim {

/// Per-pixel flags (bit set).
enum PixelFlags : uint8_t {
    kFlagCovered = 1u << 0,  ///< a triangle covers the pixel centre and passed depth
    kFlagHelper =
        1u << 1,  ///< reserved: helper lanes write nothing, so never set in a frame
    kFlagBudgetExhausted =
        1u << 2,  ///< the kernel stopped because its fetch budget ran out
    /// the search ended outside the surface: the linear family left the relief without
    /// a hit; a cone march stopped above the surface (its last point is still its
    /// answer, shaded and lit: kernels/kernel.h KernelAnswersAtStop)
    kFlagNoHit = 1u << 3,
};

/// One frame's per-pixel record, structure of arrays, row-major, row 0 at the top of the
/// image. Uncovered pixels hold zeros. Filled by tiles that each own their pixels.
struct FrameRecord {
    int width = 0, height = 0;
    std::vector<float> hitU,
        hitV;                     ///< texture uv of the hit (tiling included, unwrapped)
    std::vector<float> hitDepth;  ///< ray depth at the hit, in [0,1] (0 = top surface)
    std::vector<uint16_t> nCoarse;  ///< coarse-search iterations (linear / cone)
    std::vector<uint16_t>
        nRefine;  ///< refinement iterations (binary / secant / interval)
    std::vector<uint32_t> nFetches;     ///< sampler calls by the pixel's own lane
    std::vector<uint32_t> nTexelReads;  ///< texels read by those calls
    std::vector<uint8_t> flags;         ///< PixelFlags

    // Per-frame totals of helper lanes (they execute, are counted, and write nothing).
    uint64_t nHelperLanes = 0;
    uint64_t nHelperFetches = 0;
    uint64_t nHelperTexelReads = 0;

    void Resize(int w, int h) {
        width = w;
        height = h;
        size_t n = size_t(w) * size_t(h);
        hitU.assign(n, 0.0f);
        hitV.assign(n, 0.0f);
        hitDepth.assign(n, 0.0f);
        nCoarse.assign(n, 0);
        nRefine.assign(n, 0);
        nFetches.assign(n, 0);
        nTexelReads.assign(n, 0);
        flags.assign(n, 0);
        nHelperLanes = nHelperFetches = nHelperTexelReads = 0;
    }
    size_t Index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
    bool Covered(size_t i) const { return (flags[i] & kFlagCovered) != 0; }
};

}  // namespace reliefsim
