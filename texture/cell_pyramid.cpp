#include "texture/cell_pyramid.h"

#include <algorithm>
#include <limits>

#include "core/error.h"

namespace reliefsim {

CellPyramid BuildCellPyramid(const DepthField& field) {
    RS_CHECK(!field.Empty());
    CellPyramid p;
    p.width = field.width;
    p.height = field.height;
    int w = field.width, h = field.height;
    for (;;) {
        p.levelWidth.push_back(w);
        p.levelHeight.push_back(h);
        p.offset.push_back(p.stride);
        p.stride += w;
        if (w == 1 && h == 1) break;
        w = (w + 1) / 2;
        h = (h + 1) / 2;
    }
    p.levels = int(p.levelWidth.size());
    if (p.levels > kMaxPyramidLevels)
        throw Error("height field \"" + field.name + "\": " +
                    std::to_string(field.width) + "x" + std::to_string(field.height) +
                    " needs more than 16 pyramid levels (at most 32768 texels a side)");
    p.atlasHeight = field.height;
    p.atlas.assign(size_t(p.stride) * size_t(p.atlasHeight),
                   std::numeric_limits<float>::infinity());
    auto at = [&](int level, int i, int j) -> float& {
        return p
            .atlas[size_t(j) * size_t(p.stride) + size_t(p.offset[size_t(level)] + i)];
    };
    const int W = field.width, H = field.height;
    for (int j = 0; j < H; ++j) {
        const int j1 = j + 1 == H ? 0 : j + 1;
        for (int i = 0; i < W; ++i) {
            const int i1 = i + 1 == W ? 0 : i + 1;
            at(0, i, j) = std::min(std::min(field.At(i, j), field.At(i1, j)),
                                   std::min(field.At(i, j1), field.At(i1, j1)));
        }
    }
    for (int k = 1; k < p.levels; ++k) {
        const int cw = p.levelWidth[size_t(k - 1)], ch = p.levelHeight[size_t(k - 1)];
        for (int j = 0; j < p.levelHeight[size_t(k)]; ++j)
            for (int i = 0; i < p.levelWidth[size_t(k)]; ++i) {
                float m = std::numeric_limits<float>::infinity();
                for (int b = 0; b < 2; ++b)
                    for (int a = 0; a < 2; ++a)
                        if (2 * i + a < cw && 2 * j + b < ch)
                            m = std::min(m, at(k - 1, 2 * i + a, 2 * j + b));
                at(k, i, j) = m;
            }
    }
    return p;
}

}  // namespace reliefsim
