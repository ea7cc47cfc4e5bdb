// Cone maps conservative for the bilinear surface: cones that bound the surface the
// kernels sample (and the exact reference intersects) between texel centres, not only its
// texel centres. docs/cone_maps.md, "Bilinear bounds".
#pragma once

#include <optional>
#include <string_view>

#include "core/enum_names.h"
#include "maps/cone_map.h"

namespace reliefsim {

/// Which surface a conservative cone map bounds (`--cone-bounds` of render, trace,
/// glcompare and sweep; `maps --bilinear`).
enum class ConeBounds {
    Texel,     ///< the texel centres (Dummer; the papers' maps, GenerateConeMap)
    Bilinear,  ///< the bilinear surface between them (GenerateBilinearConeMap)
};
inline constexpr auto kConeBoundsNames = MakeEnumNames<ConeBounds>({
    {"texel", ConeBounds::Texel},
    {"bilinear", ConeBounds::Bilinear},
});

/// Whether a kind has a bilinear-bound variant: cone, cone-normal, quad, acm4, acm8.
bool HasBilinearBounds(ConeKind kind);

/// The map of `kind` whose cones bound the bilinear surface of `hf` (wrap-around): for
/// any point p of the surface and any sampling of the map at p that returns a convex
/// combination of the four texels around p (nearest, bilinear, min-of-4), every point q
/// of the surface (in the channel's sector of p, for quad, acm4 and acm8) satisfies
/// |q - p|_uv >= r (D(p) - D(q)). Per cell C (the square between four texel centres):
///   R(C) = min(1 / L(C), min over cells C' at least two cells away, in the sector:
///          dist(C, C') / (max depth of C's corners - min depth of C''s corners)),
/// L(C) the largest gradient norm of the bilinear surface over the 3x3 cells around C
/// (it bounds the near cells, whose segments to C stay inside them); a texel stores the
/// least R of the four cells it is a corner of, rounded down. Exact: equal to
/// GenerateBilinearConeMapBruteForce bit for bit. Params: only the defaults (no
/// relaxed, normal or adaptive); throws Error otherwise, for other kinds and for invalid
/// fields.
ConeMap GenerateBilinearConeMap(const DepthField& hf, ConeKind kind,
                                const ConeMapParams& params = {});
/// The same, every cell pair evaluated (the oracle of the tests).
ConeMap GenerateBilinearConeMapBruteForce(const DepthField& hf, ConeKind kind,
                                          const ConeMapParams& params = {});

}  // namespace reliefsim
