// The lane search: exact conservative-family cone maps (cone, cone-normal, quad, acm4,
// acm8, stacked, relaxed-exact) by one traversal of a min-depth pyramid per 4x4 tile of
// apexes, the 16 apexes tested together as vector lanes. Not part of the public API.
#pragma once

#include <cstdint>
#include <vector>

#include "maps/cone_map.h"
#include "maps/cone_map_detail.h"

namespace reliefsim::detail {

/// The side of a tile of apexes searched together (its texels are the vector lanes).
inline constexpr int kLaneTile = 4;

/// How a search's minimum q is stored.
enum class ConeSearchOutput {
    Ratio,       ///< RatioFromQ: the ratio rounded down (the cap without a blocker)
    ConeNormal,  ///< ConeNormalFromRatio of sqrt(q) / scale (1 without a blocker)
};

/// One search: for every texel p and channel c, the minimum over blockers q (texels of
/// the wrap window with depth b < apex(p), in channel c's sector; with `limiting`, only
/// texels limiting for the offset's direction, as IsLimiting) of CandidateQ(S, apex, b),
/// converted by `output` and written to out[(j * W + i) * outStride + outBase + c].
struct ConeSearchJob {
    const DepthField* field = nullptr;
    const float* apex = nullptr;        ///< W * H apex depths (the depths, or stacked)
    ConeKind sectors = ConeKind::Cone;  ///< Cone (1 channel), Quad, Acm4, Acm8
    bool limiting = false;              ///< relaxed-exact's blockers
    ConeSearchOutput output = ConeSearchOutput::Ratio;
    float* out = nullptr;
    int outStride = 1, outBase = 0;
};

/// Runs the search (oneTBB over bands of tile rows; exact, so bit-identical for any
/// thread count and ISA, and equal to BruteSearch with the same definition). The fast
/// path of GenerateConeMap; proof and measurements: docs/cone_maps.md, "The lane search".
void RunConeSearch(const ConeSearchJob& job, ProgressCounter* progress = nullptr);

/// How many passes RunConeSearch makes over the tile rows (its progress counts each
/// pass's rows): one per rip-map (acm8 on square maps: four), else one.
int ConeSearchPasses(ConeKind sectors, int W, int H);

/// Which instruction set the lane search runs with on this CPU ("avx512", "avx2",
/// "sse4.1"); RS_CONE_SEARCH_ISA=avx512|avx2|sse4.1 forces one (tests compare them).
const char* ConeSearchIsa();

}  // namespace reliefsim::detail
