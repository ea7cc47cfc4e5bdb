// The height texture laid out for the lane sampler (texture/lane_sampler.h).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "texture/depth_field.h"
#include "texture/sampler.h"

namespace reliefsim {

/// A copy of a DepthField's depths with one extra column and one extra row that hold the
/// texel the wrap mode reads past the last one (repeat: the first column / row; clamp:
/// the last). For every uv the bilinear footprint whose first texel is (i0, j0) is then
/// the texels base, base + 1, base + stride and base + stride + 1 with base = j0 * stride
/// + i0 (research/llvmpipe.md §2.1 gives i1 = i0 + 1, or the wrapped / clamped index that
/// the extra column holds), so a footprint is two 64-bit loads and one address.
struct PaddedTexels {
    int width = 0, height = 0;  ///< of the field
    int stride = 0;             ///< width + 1
    WrapMode wrap = WrapMode::Repeat;
    std::vector<float> texels;  ///< stride * (height + 1)

    int64_t Count() const { return int64_t(texels.size()); }
};

/// The padded copy of `field` for `wrap`.
PaddedTexels PadTexels(const DepthField& field, WrapMode wrap);

}  // namespace reliefsim
