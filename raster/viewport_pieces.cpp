// Viewport clipping into llvmpipe's pieces, and the triangle index per pixel.
#include "raster/viewport_pieces.h"

#include "raster/rasterizer.h"

namespace reliefsim {

namespace {

/// Writes, for each covered pixel, the mesh triangle (kPiece = false) or the piece.
template <class T, bool kPiece>
class TriangleIdProgram {
  public:
    static constexpr bool kReadsAttributes = false;
    TriangleIdProgram(std::vector<T>& ids, int width) : ids_(ids), width_(width) {}
    void ShadeQuad(const QuadFragment& q, int /*tileIndex*/) {
        for (int k = 0; k < 4; ++k) {
            if (!((q.coveredMask >> k) & 1u)) continue;
            const int x = q.pixel0.x + (k & 1), y = q.pixel0.y + (k >> 1);
            ids_[size_t(y) * size_t(width_) + size_t(x)] =
                T(kPiece ? q.piece : q.triangle);
        }
    }

  private:
    std::vector<T>& ids_;
    int width_;
};

}  // namespace

Mesh ClipMeshToViewport(const Mesh& mesh, const glm::mat4& clipFromWorld) {
    // Side planes in world space: inside iff dot(plane, (p, 1)) >= 0, with plane = k *
    // row3
    // -+ row0 / row1 of clipFromWorld (x <= k w, x >= -k w, y <= k w, y >= -k w).
    const float k = 1.0f - 1.0f / 4096.0f;
    auto row = [&](int r) {
        return glm::vec4(clipFromWorld[0][r], clipFromWorld[1][r], clipFromWorld[2][r],
                         clipFromWorld[3][r]);
    };
    const glm::vec4 planes[4] = {k * row(3) - row(0), k * row(3) + row(0),
                                 k * row(3) - row(1), k * row(3) + row(1)};
    Mesh out;
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        std::vector<glm::vec3> poly = {mesh.vertices[mesh.indices[t]].position,
                                       mesh.vertices[mesh.indices[t + 1]].position,
                                       mesh.vertices[mesh.indices[t + 2]].position};
        for (const glm::vec4& pl : planes) {
            std::vector<glm::vec3> next;
            const size_t n = poly.size();
            for (size_t i = 0; i < n; ++i) {
                const glm::vec3 a = poly[i], b = poly[(i + 1) % n];
                const float da = pl.x * a.x + pl.y * a.y + pl.z * a.z + pl.w;
                const float db = pl.x * b.x + pl.y * b.y + pl.z * b.z + pl.w;
                if (da >= 0.0f) next.push_back(a);
                if ((da >= 0.0f) != (db >= 0.0f))
                    next.push_back(a + (b - a) * (da / (da - db)));
            }
            poly.swap(next);
            if (poly.size() < 3) break;
        }
        if (poly.size() < 3) continue;
        const uint32_t base = uint32_t(out.vertices.size());
        for (const glm::vec3& p : poly) {
            Vertex v{};
            v.position = p;
            out.vertices.push_back(v);
        }
        for (uint32_t i = 2; i < poly.size(); ++i)
            out.indices.insert(out.indices.end(), {base, base + i - 1, base + i});
    }
    return out;
}

std::vector<int16_t> TrianglePerPixel(const Mesh& mesh, const Camera& camera, int width,
                                      int height) {
    std::vector<int16_t> ids(size_t(width) * size_t(height), int16_t(-1));
    TriangleIdProgram<int16_t, false> program(ids, width);
    RasterizeFrame(mesh, camera, width, height, program);
    return ids;
}

std::vector<int32_t> PiecePerPixel(const Mesh& mesh, const Camera& camera, int width,
                                   int height) {
    std::vector<int32_t> ids(size_t(width) * size_t(height), -1);
    TriangleIdProgram<int32_t, true> program(ids, width);
    RasterizeFrame(mesh, camera, width, height, program);
    return ids;
}

}  // namespace reliefsim
