// Built-in meshes.
#include "raster/mesh.h"

namespace reliefsim {

Mesh MakePlane(float tiling) {
    Mesh mesh;
    const glm::vec2 corners[4] = {
        {-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
    for (const glm::vec2& c : corners) {
        Vertex v;
        v.position = glm::vec3(c, 0.0f);
        v.uv = glm::vec2((c.x + 0.5f) * tiling, (0.5f - c.y) * tiling);
        v.tangent = glm::vec3(1.0f, 0.0f, 0.0f);
        v.bitangent = glm::vec3(0.0f, -1.0f, 0.0f);
        v.normal = glm::vec3(0.0f, 0.0f, 1.0f);
        mesh.vertices.push_back(v);
    }
    mesh.indices = {0, 1, 2, 0, 2, 3};  // counter-clockwise seen from +z
    return mesh;
}

}  // namespace reliefsim
