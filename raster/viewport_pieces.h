// The mesh split into the pieces llvmpipe's draw module rasterizes (clipped to the
// viewport) and the triangle that covers each pixel: CPU-only geometry for the lane-cost
// check.
#pragma once

#include <cstdint>
#include <glm/mat4x4.hpp>
#include <vector>

#include "raster/camera.h"
#include "raster/mesh.h"

namespace reliefsim {

/// The mesh clipped in world space to the camera's side planes, each pulled in by 2^-12
/// of w (far less than half a pixel), and fan-triangulated from each polygon's first
/// vertex. llvmpipe's draw module clips triangles that leave the viewport and rasterizes
/// the pieces separately, so a 4x2 block on a piece boundary runs once per piece. The
/// lane-cost run draws this pre-clipped mesh, so the pieces are explicit and identical in
/// both paths: GL never clips again, and gl_PrimitiveID and the C++ triangle index name
/// the same piece. (The record comparison draws the unclipped mesh: the new vertices can
/// move a clipped edge by up to 1/256 pixel and flip the coverage of a pixel centre lying
/// that close to it.) Only positions are kept.
Mesh ClipMeshToViewport(const Mesh& mesh, const glm::mat4& clipFromWorld);

/// gl_PrimitiveID of each covered pixel as the C++ rasterizer assigns it (triangle
/// index), -1 where no triangle covers it.
std::vector<int16_t> TrianglePerPixel(const Mesh& mesh, const Camera& camera, int width,
                                      int height);

/// The rasterizer's piece (QuadFragment::piece: a triangle after clipping) of each
/// covered pixel, -1 where none covers it: the split of the lane groups the frame driver
/// executes.
std::vector<int32_t> PiecePerPixel(const Mesh& mesh, const Camera& camera, int width,
                                   int height);

}  // namespace reliefsim
