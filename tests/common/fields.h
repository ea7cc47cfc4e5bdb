// Test helper for height maps: a DepthField from a list of depths or from a function of
// the texel.
#pragma once

#include <concepts>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "texture/depth_field.h"

namespace reliefsim::testing {

/// A w x h field named `name` with these depths, row by row.
inline DepthField MakeField(int w, int h, std::vector<float> depth,
                            std::string name = "test") {
    DepthField f;
    f.width = w;
    f.height = h;
    f.name = std::move(name);
    f.depth = std::move(depth);
    return f;
}

/// A w x h field named `name` whose texel (i, j) has depth depthAt(i, j), called row by
/// row (j outer, i inner: a random generator gives the same field every time).
template <class DepthAt>
requires std::invocable<DepthAt&, int, int> DepthField
MakeField(int w, int h, DepthAt&& depthAt, std::string name = "test") {
    std::vector<float> depth(size_t(w) * size_t(h));
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            depth[size_t(j) * size_t(w) + size_t(i)] = float(depthAt(i, j));
    return MakeField(w, h, std::move(depth), std::move(name));
}

}  // namespace reliefsim::testing
