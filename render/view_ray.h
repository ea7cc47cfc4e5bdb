// Pixel -> texture-space view ray for the scene's plane: the fragment's kernel input.
// Written once over a lane type: the frame's lanes (render/lane_driver.h) and the scalar
// PixelToRay of trace and glcompare are instantiations of the same operations. The GLSL
// twin (kernels/glsl/view_ray.glsl) computes the same float operations in the same order
// (DESIGN.md "The GLSL twin"), so both paths feed the kernels bit-identical inputs.
#pragma once

#include <glm/vec3.hpp>

#include "core/error.h"
#include "kernels/kernel.h"
#include "kernels/lanes.h"

namespace reliefsim {

/// Camera and plane uniforms, in float as a shader receives them. The plane is the
/// scene's (render/scene.h MakePlane): the world square [-0.5,0.5]^2 at z = 0, uv = ((x +
/// 0.5) * tiling, (0.5 - y) * tiling), tangent +x, bitangent -y, normal +z.
struct ViewUniforms {
    glm::vec3 eye;        ///< camera position, world
    glm::vec3 forward;    ///< unit view direction, world
    glm::vec3 right;      ///< camera right * tan(fovX/2), world
    glm::vec3 up;         ///< camera up * tan(fovY/2), world
    float width, height;  ///< framebuffer size in pixels
    float tiling;         ///< uv repeats across the plane
    float depthScale;     ///< relief depth in plane units (depth 1 = depthScale)
    /// The orthographic texture-space view (--camera ortho): every pixel's ray enters at
    /// uv ((x + 0.5)/W, (y + 0.5)/H) and moves (orthoDu, orthoDv) uv per unit depth; the
    /// fields above are then unused.
    int ortho = 0;
    float orthoDu = 0.0f, orthoDv = 0.0f;
    float orthoViewZ = 1.0f;  ///< |view.z| of the unit view direction
};

/// The kernel input of the pixels (px, py) of each lane, row 0 at the top, sampled at the
/// pixel centre. Rays that graze the plane are bounded (|view.z| >= 1e-6) so they never
/// produce Inf or NaN. viewZ = -dz / |d| of the clamped direction d.
template <class L>
RS_INLINE LaneRay<L> PixelToRayLanes(const ViewUniforms& u, const typename L::F& px,
                                     const typename L::F& py) {
    using F = typename L::F;
    const F fx = px + F(0.5f), fy = py + F(0.5f);
    if (u.ortho) {
        LaneRay<L> r;
        r.uEntry = fx / F(u.width);
        r.vEntry = fy / F(u.height);
        r.du = F(u.orthoDu);
        r.dv = F(u.orthoDv);
        r.viewZ = F(u.orthoViewZ);
        return r;
    }
    const F ndcX = (fx * F(2.0f)) / F(u.width) - F(1.0f);
    const F ndcY = F(1.0f) - (fy * F(2.0f)) / F(u.height);
    const F dx = (F(u.forward.x) + F(u.right.x) * ndcX) + F(u.up.x) * ndcY;
    const F dy = (F(u.forward.y) + F(u.right.y) * ndcX) + F(u.up.y) * ndcY;
    F dz = (F(u.forward.z) + F(u.right.z) * ndcX) + F(u.up.z) * ndcY;
    dz = Select(dz < F(-1e-6f), dz, F(-1e-6f));
    const F tPlane = F(-u.eye.z) / dz;
    const F hitX = F(u.eye.x) + dx * tPlane;
    const F hitY = F(u.eye.y) + dy * tPlane;
    const F k(u.depthScale * u.tiling);
    LaneRay<L> r;
    r.uEntry = (hitX + F(0.5f)) * F(u.tiling);
    r.vEntry = (F(0.5f) - hitY) * F(u.tiling);
    // Tangent frame: T = +x (u), B = -y (v), N = +z; view_ts = (dx, -dy, dz).
    r.du = -(dx / dz) * k;
    r.dv = (dy / dz) * k;
    r.viewZ = -dz / stdx::sqrt((dx * dx + dy * dy) + dz * dz);
    return r;
}

/// The kernel input of pixel (px, py): PixelToRayLanes at one lane.
inline MarchInput PixelToRay(const ViewUniforms& u, int px, int py) {
    using L = Lanes<1>;
    const LaneRay<L> r = PixelToRayLanes<L>(u, L::F(float(px)), L::F(float(py)));
    MarchInput in;
    in.uvEntry = glm::vec2(float(r.uEntry[0]), float(r.vEntry[0]));
    in.dirUv = glm::vec2(float(r.du[0]), float(r.dv[0]));
    in.viewZ = float(r.viewZ[0]);
    return in;
}

}  // namespace reliefsim
