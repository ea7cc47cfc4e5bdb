// Triangle meshes with a tangent frame per vertex, and the built-in test surfaces.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace reliefsim {

/// One mesh vertex. All vectors are in world space; the tangent frame need not be
/// orthonormal.
struct Vertex {
    glm::vec3 position;   // world position
    glm::vec2 uv;         // texture coordinates (texture space, DESIGN.md conventions)
    glm::vec3 tangent;    // world direction of +u
    glm::vec3 bitangent;  // world direction of +v
    glm::vec3 normal;     // world surface normal (front side)
};

/// Indexed triangle list; triangle t uses indices[3t..3t+2], counter-clockwise seen from
/// the front.
struct Mesh {
    std::vector<Vertex> vertices;
    std::vector<uint32_t> indices;
};

/// The scene's plane, defined once (render, trace, glcompare and the benchmarks draw it):
/// the world square [-0.5,0.5]^2 in the z = 0 plane, two triangles, normal +z, tangent +x
/// (u), bitangent -y (v), uv = (x + 0.5, 0.5 - y) * tiling, so texel row 0 (the image's
/// top row) lies on the far edge (+y) for azimuth 0 (kernels/view_ray.h PixelToRay
/// assumes exactly this plane).
Mesh MakePlane(float tiling);

}  // namespace reliefsim
