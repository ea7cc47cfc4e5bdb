// Pixel -> texture-space view ray for the textured plane: the fragment's kernel input.
// The GLSL twin computes the same float operations in the same order (DESIGN.md "The GLSL
// twin"), so both paths feed the kernels bit-identical inputs.
#pragma once

#include <glm/vec3.hpp>

#include "kernels/kernel.h"

namespace reliefsim {

/// Camera and plane uniforms, in float as a shader receives them. The plane is the world
/// square [-0.5,0.5]^2 at z = 0 with uv = ((x + 0.5) * tiling, (0.5 - y) * tiling), so
/// texel row 0 (the image's top row) lies on the far edge (+y) for azimuth 0.
struct ViewUniforms {
    glm::vec3 eye;        ///< camera position, world
    glm::vec3 forward;    ///< unit view direction, world
    glm::vec3 right;      ///< camera right * tan(fovX/2), world
    glm::vec3 up;         ///< camera up * tan(fovY/2), world
    float width, height;  ///< framebuffer size in pixels
    float tiling;         ///< uv repeats across the plane
    float depthScale;     ///< relief depth in plane units (depth 1 = depthScale)
};

/// The kernel input of pixel (px, py), row 0 at the top, sampled at the pixel centre.
/// Rays that graze the plane are bounded (|view.z| >= 1e-6) so they never produce Inf or
/// NaN.
inline MarchInput PixelToRay(const ViewUniforms& u, int px, int py) {
    const float fx = float(px) + 0.5f, fy = float(py) + 0.5f;
    const float ndcX = (fx * 2.0f) / u.width - 1.0f;
    const float ndcY = 1.0f - (fy * 2.0f) / u.height;
    const float dx = (u.forward.x + u.right.x * ndcX) + u.up.x * ndcY;
    const float dy = (u.forward.y + u.right.y * ndcX) + u.up.y * ndcY;
    float dz = (u.forward.z + u.right.z * ndcX) + u.up.z * ndcY;
    dz = dz < -1e-6f ? dz : -1e-6f;
    const float tPlane = -u.eye.z / dz;
    const float hitX = u.eye.x + dx * tPlane;
    const float hitY = u.eye.y + dy * tPlane;
    const float k = u.depthScale * u.tiling;
    MarchInput in;
    in.uvEntry = glm::vec2((hitX + 0.5f) * u.tiling, (0.5f - hitY) * u.tiling);
    // Tangent frame: T = +x (u), B = -y (v), N = +z; view_ts = (dx, -dy, dz).
    in.dirUv = glm::vec2(-(dx / dz) * k, (dy / dz) * k);
    return in;
}

}  // namespace reliefsim
