// Triangle meshes with a tangent frame per vertex (the scene's plane is render/scene.h
// MakePlane).
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

}  // namespace reliefsim
