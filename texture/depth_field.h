// DepthField: an immutable single-channel depth texture, the input of every kernel.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace reliefsim {

/// A depth texture: depth in [0,1], 0 = the polygon's surface (top), 1 = deepest.
/// Texel (i, j) is stored at depth[j * width + i] and has its centre at uv ((i+0.5)/W,
/// (j+0.5)/H). Row j = 0 is the first row of the source image (its top row) and sits at v
/// in [0, 1/H): exactly what an OpenGL upload of the same array gives, so both paths see
/// the same texels.
struct DepthField {
    int width = 0, height = 0;
    std::vector<float> depth;  ///< W*H depths in [0,1]
    /// Set when the source had 8-bit channels: the depth as 8-bit unorm (depth = d8 / 255
    /// computed as float(d8) * float(1.0/255.0), the GPU's unorm conversion). Empty
    /// otherwise.
    std::vector<uint8_t> depth8;
    std::string name;  ///< file path or "builtin:NAME:SIZE", for messages and reports

    float At(int i, int j) const { return depth[size_t(j) * size_t(width) + size_t(i)]; }
    bool Empty() const { return width <= 0 || height <= 0; }
};

/// The GPU's unorm8 -> float conversion: a multiply by the rounded reciprocal (not v /
/// 255.0f, which differs by 1 ulp for some v; research/llvmpipe.md §2.1).
inline float Unorm8ToFloat(uint8_t v) { return float(v) * float(1.0 / 255.0); }

/// Builds a DepthField from 8-bit depths (keeps depth8 and derives depth).
DepthField DepthFieldFromUnorm8(int width, int height, std::vector<uint8_t> depth8,
                                std::string name);

/// Quantises a float field to 8 bits (round to nearest), keeping depth8.
DepthField QuantizeToUnorm8(const DepthField& hf);

/// `hf` resampled bilinearly to width x height floats (repeat addressing, texel centres
/// at (i + 0.5) / width): a smooth map with as many distinct depths as a float map. The
/// name is hf's with "@WxH" appended.
DepthField UpsampleBilinear(const DepthField& hf, int width, int height);

/// Throws Error naming hf.name when the field is empty or holds NaN/Inf or values outside
/// [0,1].
void ValidateDepthField(const DepthField& hf);

}  // namespace reliefsim
