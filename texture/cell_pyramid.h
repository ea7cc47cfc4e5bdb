// The cell pyramid of the hierarchical tracers (maxmip, qdm; kernels/max_mip.h): the
// minimum depth (= maximum height) of the bilinear surface over every cell and every
// quadtree node of cells, in one atlas texture.
//
// A cell is the square between four texel centres: cell (i, j) spans the cell-space
// square [i, i+1) x [j, j+1), cell space being x = u W - 0.5, y = v H - 0.5, and its
// corners are texels (i, j), (i+1, j), (i, j+1), (i+1, j+1), indices wrapped (repeat).
// The bilinear surface over a cell interpolates its corners, so its least depth is the
// least corner (Tevs et al. 2008, "Maximum mipmaps": the maximum of a bilinear patch is
// at a corner).
//
// Level 0 holds the W x H cells; level k + 1 has ceil(w_k / 2) x ceil(h_k / 2) nodes,
// node (i, j) the minimum of children (2i + a, 2j + b), a, b in {0, 1}, that exist (no
// wrap: the last node of an odd level has one child column). So node (i, j) of level k
// covers cells [i 2^k, min((i+1) 2^k, W)) x [j 2^k, min((j+1) 2^k, H)). The top level
// has one node. Levels lie side by side in one atlas row-major array (the GLSL twin's
// R32F texture, read with texelFetch): node (i, j) of level k at atlas texel
// (offset[k] + i, j).
#pragma once

#include <vector>

#include "texture/depth_field.h"

namespace reliefsim {

struct CellPyramid {
    int width = 0, height = 0;  ///< cells of level 0 (the field's size)
    int levels = 0;             ///< level count; the top, levels - 1, is 1x1
    std::vector<int> offset;    ///< per level: its first atlas column
    std::vector<int> levelWidth, levelHeight;
    int stride = 0;            ///< atlas width (sum of the level widths)
    int atlasHeight = 0;       ///< = height
    std::vector<float> atlas;  ///< stride * atlasHeight minimum depths (unused: +inf)

    float At(int level, int i, int j) const {
        return atlas[size_t(j) * size_t(stride) + size_t(offset[size_t(level)] + i)];
    }
};

/// The most levels a pyramid has (maps up to 2^15 texels a side; the twin's offset
/// uniform array has this many entries).
inline constexpr int kMaxPyramidLevels = 16;

/// The cell pyramid of `field` (its texel values, the values texelFetch returns).
CellPyramid BuildCellPyramid(const DepthField& field);

}  // namespace reliefsim
