// Triangle setup on the calling thread: transform, clipping, fixed-point edges, binning.
#include "raster/rasterizer.h"

#include <cmath>
#include <sstream>
#include <utility>

#include "core/error.h"

namespace reliefsim {
namespace detail {
namespace {

/// A vertex in clip space with the attributes carried through clipping.
struct ClipVertex {
    glm::vec4 clip;
    glm::vec2 uv;
    glm::vec3 worldPos, tangent, bitangent, normal;
};

/// a + t * (b - a) for every attribute (Mesa LINTERP).
ClipVertex Lerp(const ClipVertex& a, const ClipVertex& b, float t) {
    ClipVertex v;
    v.clip = a.clip + (b.clip - a.clip) * t;
    v.uv = a.uv + (b.uv - a.uv) * t;
    v.worldPos = a.worldPos + (b.worldPos - a.worldPos) * t;
    v.tangent = a.tangent + (b.tangent - a.tangent) * t;
    v.bitangent = a.bitangent + (b.bitangent - a.bitangent) * t;
    v.normal = a.normal + (b.normal - a.normal) * t;
    return v;
}

/// Inside iff dot(n, clip) + offset >= 0, evaluated left to right like Mesa's dot4.
struct ClipPlane {
    glm::vec4 n;
    float offset;
    float Distance(const glm::vec4& c) const {
        return (((n.x * c.x + n.y * c.y) + n.z * c.z) + n.w * c.w) + offset;
    }
};

/// Mesa's draw module clips x and y against the viewport (no guard band on llvmpipe),
/// then near and far, in this order (draw_context.c plane[0..5]). We add w >= eps last,
/// for matrices whose near plane does not keep w positive.
constexpr int kNumPlanes = 7;
constexpr int kMaxPolygon = 2 * (3 + kNumPlanes);
/// Smallest clip w kept.
constexpr float kMinClipW = 1e-6f;
constexpr ClipPlane kClipPlanes[kNumPlanes] = {
    {{-1.0f, 0.0f, 0.0f, 1.0f}, 0.0f},       // x <= w
    {{1.0f, 0.0f, 0.0f, 1.0f}, 0.0f},        // x >= -w
    {{0.0f, -1.0f, 0.0f, 1.0f}, 0.0f},       // y <= w
    {{0.0f, 1.0f, 0.0f, 1.0f}, 0.0f},        // y >= -w
    {{0.0f, 0.0f, 1.0f, 1.0f}, 0.0f},        // GL near: z >= -w
    {{0.0f, 0.0f, -1.0f, 1.0f}, 0.0f},       // GL far: z <= w
    {{0.0f, 0.0f, 0.0f, 1.0f}, -kMinClipW},  // w >= eps
};

/// Clips a polygon against one plane the way Mesa's draw_pipe_clip.c (do_clip_tri) does,
/// so clipped triangles cover the same pixels as on llvmpipe: a vertex is kept when its
/// distance is >= 0, and a new vertex on an edge whose distances differ in sign (a zero
/// counts, as in DIFFERENT_SIGNS) is interpolated from the outside vertex toward the
/// inside one, out + t * (in - out) with t = d_out / (d_out - d_in). That makes the new
/// vertex on an edge shared by two triangles bit-identical in both, so clipping opens no
/// cracks.
int ClipPolygon(const ClipPlane& plane, const ClipVertex* in, int nIn, ClipVertex* out) {
    int nOut = 0;
    const ClipVertex* prev = &in[0];
    float dPrev = plane.Distance(prev->clip);
    for (int i = 1; i <= nIn; ++i) {
        const ClipVertex* cur = &in[i % nIn];
        const float d = plane.Distance(cur->clip);
        if (dPrev >= 0.0f) out[nOut++] = *prev;
        if (d * dPrev <= 0.0f && d - dPrev != 0.0f) {
            if (d < 0.0f) {
                out[nOut++] = Lerp(*cur, *prev, d / (d - dPrev));  // going out
            } else {
                out[nOut++] = Lerp(*prev, *cur, dPrev / (dPrev - d));  // coming back in
            }
        }
        prev = cur;
        dPrev = d;
    }
    return nOut;
}

struct WindowVertex {
    int64_t x,
        y;  // fixed point, 1/256 pixel, origin at the centre of pixel (0,0), y down
    float invW, depth;
};

WindowVertex ToWindow(const glm::vec4& clip, int width, int height) {
    // Mesa: ndc = clip * (1/w), window = ndc * scale + translate with scale = translate =
    // size/2, then snap (window - 0.5) to 1/256 with round-to-nearest-even
    // (lp_setup_tri.c subpixel_snap). Snapping happens in GL's y-up window space; our row
    // r is GL row height-1-r, an exact integer flip.
    WindowVertex v;
    v.invW = 1.0f / clip.w;
    const float ndcX = clip.x * v.invW, ndcY = clip.y * v.invW, ndcZ = clip.z * v.invW;
    const float halfW = float(width) * 0.5f, halfH = float(height) * 0.5f;
    const float xWindow = ndcX * halfW + halfW;
    const float yWindowGl = ndcY * halfH + halfH;
    const float one = float(1 << kSubPixelBits);
    v.x = int64_t(std::llrint((xWindow - 0.5f) * one));
    const int64_t yGl = int64_t(std::llrint((yWindowGl - 0.5f) * one));
    v.y = (int64_t(height - 1) << kSubPixelBits) - yGl;
    v.depth = ndcZ * 0.5f + 0.5f;
    return v;
}

int64_t FloorDiv(int64_t a) { return a >> kSubPixelBits; }  // arithmetic shift (C++20)
int64_t CeilDiv(int64_t a) { return -((-a) >> kSubPixelBits); }

void SetupTriangleAndBin(const ClipVertex* verts, uint32_t triangle, int width,
                         int height, FrameSetup& setup) {
    WindowVertex w[3];
    for (int k = 0; k < 3; ++k) w[k] = ToWindow(verts[k].clip, width, height);
    int order[3] = {0, 1, 2};
    int64_t area2 =
        (w[1].x - w[0].x) * (w[2].y - w[0].y) - (w[1].y - w[0].y) * (w[2].x - w[0].x);
    if (area2 == 0) return;
    SetupTriangle tri;
    tri.triangle = triangle;
    // Our y points down, so a positive area is clockwise in GL window space: a back face.
    tri.frontFacing = area2 < 0;
    if (area2 < 0) {
        std::swap(order[1], order[2]);
        area2 = -area2;
    }
    glm::i64vec2 p[3];
    for (int k = 0; k < 3; ++k) {
        const int o = order[k];
        p[k] = glm::i64vec2(w[o].x, w[o].y);
        tri.invW[k] = w[o].invW;
        tri.depth[k] = w[o].depth;
        tri.uv[k] = verts[o].uv;
        tri.worldPos[k] = verts[o].worldPos;
        tri.tangent[k] = verts[o].tangent;
        tri.bitangent[k] = verts[o].bitangent;
        tri.normal[k] = verts[o].normal;
    }
    for (int k = 0; k < 3; ++k) {
        const glm::i64vec2 pa = p[k], pb = p[(k + 1) % 3];
        const int64_t dx = pb.x - pa.x, dy = pb.y - pa.y;
        // E(P) = dx * (P.y - pa.y) - dy * (P.x - pa.x) is > 0 inside (area2 > 0 after the
        // swap). Fill rule (Mesa GL, see RasterizeFrame): a pixel centre exactly on an
        // edge counts if the inside lies toward +x (left edge), or the edge is horizontal
        // with the inside toward -y (bottom edge in our images). lp_setup_tri.c adds this
        // as a +1 bias to c.
        const bool includeTies = dy < 0 || (dy == 0 && dx < 0);
        const int64_t bias = includeTies ? 1 : 0;
        tri.a[k] = -dy * (int64_t(1) << kSubPixelBits);
        tri.b[k] = dx * (int64_t(1) << kSubPixelBits);
        tri.c[k] = dy * pa.x - dx * pa.y + bias - 1;
        tri.unbias[k] = 1 - bias;
    }
    tri.invArea = 1.0f / float(area2);
    const int64_t minX = std::min({p[0].x, p[1].x, p[2].x});
    const int64_t maxX = std::max({p[0].x, p[1].x, p[2].x});
    const int64_t minY = std::min({p[0].y, p[1].y, p[2].y});
    const int64_t maxY = std::max({p[0].y, p[1].y, p[2].y});
    const int64_t x0 = std::max<int64_t>(CeilDiv(minX), 0);
    const int64_t y0 = std::max<int64_t>(CeilDiv(minY), 0);
    const int64_t x1 = std::min<int64_t>(FloorDiv(maxX), width - 1);
    const int64_t y1 = std::min<int64_t>(FloorDiv(maxY), height - 1);
    if (x0 > x1 || y0 > y1) return;
    tri.bboxMin = glm::ivec2(int(x0), int(y0));
    tri.bboxMax = glm::ivec2(int(x1), int(y1));

    const uint32_t index = uint32_t(setup.triangles.size());
    tri.piece = index;
    setup.triangles.push_back(tri);
    const int tilesX = TileCountX(width);
    for (int ty = tri.bboxMin.y / kTileSize; ty <= tri.bboxMax.y / kTileSize; ++ty) {
        for (int tx = tri.bboxMin.x / kTileSize; tx <= tri.bboxMax.x / kTileSize; ++tx) {
            setup.bins[size_t(ty * tilesX + tx)].push_back(index);
        }
    }
}

}  // namespace

FrameSetup SetupFrame(const Mesh& mesh, const Camera& camera, int width, int height) {
    if (width < 1 || height < 1 || width > kMaxImageSize || height > kMaxImageSize) {
        std::ostringstream s;
        s << "image size " << width << "x" << height << ": out of range; expected 1.."
          << kMaxImageSize << " pixels per side";
        throw Error(s.str());
    }
    if (mesh.indices.size() % 3 != 0) {
        std::ostringstream s;
        s << "mesh: " << mesh.indices.size()
          << " indices; expected a multiple of 3 (triangles)";
        throw Error(s.str());
    }
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
        if (mesh.indices[i] >= mesh.vertices.size()) {
            std::ostringstream s;
            s << "mesh: index " << i << " = " << mesh.indices[i]
              << " out of range; expected < " << mesh.vertices.size()
              << " (vertex count)";
            throw Error(s.str());
        }
    }

    FrameSetup setup;
    setup.bins.resize(size_t(TileCount(width, height)));

    std::vector<ClipVertex> transformed(mesh.vertices.size());
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Vertex& v = mesh.vertices[i];
        ClipVertex& c = transformed[i];
        c.clip = camera.clipFromWorld * glm::vec4(v.position, 1.0f);
        c.uv = v.uv;
        c.worldPos = v.position;
        c.tangent = v.tangent;
        c.bitangent = v.bitangent;
        c.normal = v.normal;
    }

    const size_t nTriangles = mesh.indices.size() / 3;
    for (size_t t = 0; t < nTriangles; ++t) {
        ClipVertex poly[kMaxPolygon], scratch[kMaxPolygon];
        for (int k = 0; k < 3; ++k)
            poly[k] = transformed[mesh.indices[3 * t + size_t(k)]];
        unsigned outMask[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k) {
            for (int i = 0; i < kNumPlanes; ++i) {
                if (!(kClipPlanes[i].Distance(poly[k].clip) >= 0.0f))
                    outMask[k] |= 1u << i;
            }
        }
        if (outMask[0] & outMask[1] & outMask[2]) continue;  // all outside one plane
        if ((outMask[0] | outMask[1] | outMask[2]) == 0) {
            SetupTriangleAndBin(poly, uint32_t(t), width, height, setup);
            continue;
        }
        int n = 3;
        // Only planes that some vertex violates, as Mesa does (its clip mask).
        for (int i = 0; i < kNumPlanes && n >= 3; ++i) {
            if (!((outMask[0] | outMask[1] | outMask[2]) & (1u << i))) continue;
            n = ClipPolygon(kClipPlanes[i], poly, n, scratch);
            std::copy(scratch, scratch + n, poly);
        }
        // Fan in a fixed order; every piece keeps the original triangle index.
        for (int k = 1; k + 1 < n; ++k) {
            const ClipVertex fan[3] = {poly[0], poly[k], poly[k + 1]};
            SetupTriangleAndBin(fan, uint32_t(t), width, height, setup);
        }
    }
    return setup;
}

}  // namespace detail
}  // namespace reliefsim
