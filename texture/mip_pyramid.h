// Min and max mip pyramids with wrap-aware 2x2 reductions, for any size (odd sizes included).
#pragma once

#include <cstddef>
#include <vector>

namespace reliefsim {

enum class MipReduce { Min, Max };

/// One level: width x height texels of `channels` interleaved floats.
struct MipLevel {
    int width = 0, height = 0, channels = 1;
    std::vector<float> values;
    float At(int i, int j, int c = 0) const {
        return values[(size_t(j) * size_t(width) + size_t(i)) * size_t(channels) + size_t(c)];
    }
};

/// Level 0 is the input; level l+1 has ceil(w/2) x ceil(h/2) texels, texel (i, j) reducing the
/// children (2i + a, 2j + b), a, b in {0, 1}, indices wrapped (repeat): for an odd width the last
/// parent also covers child 0, so each parent bounds every child it overlaps. Stops at 1x1.
/// Min of cone ratios is the conservative mip of a cone map (001, "Mipmapping"); Max of
/// heights (= Min of depths) is the maximum mipmap of Tevs et al.
std::vector<MipLevel> BuildMipPyramid(const std::vector<float>& values, int width, int height,
                                      int channels, MipReduce op);

}  // namespace reliefsim
