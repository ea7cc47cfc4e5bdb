// Min/max mip pyramids: wrap-aware 2x2 reductions for any size.
#include "maps/mip_pyramid.h"

#include <algorithm>
#include <string>

#include "core/error.h"

namespace reliefsim {

std::vector<MipLevel> BuildMipPyramid(const std::vector<float>& values, int width,
                                      int height, int channels, MipReduce op) {
    if (width <= 0 || height <= 0 || channels <= 0 ||
        values.size() != size_t(width) * size_t(height) * size_t(channels))
        throw Error("mip pyramid: bad size " + std::to_string(width) + "x" +
                    std::to_string(height) + "x" + std::to_string(channels) +
                    "; expected positive sizes matching the data");
    std::vector<MipLevel> levels;
    levels.push_back({width, height, channels, values});
    while (levels.back().width > 1 || levels.back().height > 1) {
        const MipLevel& f = levels.back();
        MipLevel c;
        c.width = (f.width + 1) / 2;
        c.height = (f.height + 1) / 2;
        c.channels = channels;
        c.values.resize(size_t(c.width) * size_t(c.height) * size_t(channels));
        for (int j = 0; j < c.height; ++j)
            for (int i = 0; i < c.width; ++i)
                for (int k = 0; k < channels; ++k) {
                    float v = f.At(2 * i, 2 * j, k);
                    for (int d = 1; d < 4; ++d) {
                        const int x = (2 * i + (d & 1)) % f.width;
                        const int y = (2 * j + (d >> 1)) % f.height;
                        const float w = f.At(x, y, k);
                        v = op == MipReduce::Min ? std::min(v, w) : std::max(v, w);
                    }
                    c.values[(size_t(j) * size_t(c.width) + size_t(i)) *
                                 size_t(channels) +
                             size_t(k)] = v;
                }
        levels.push_back(std::move(c));
    }
    return levels;
}

}  // namespace reliefsim
