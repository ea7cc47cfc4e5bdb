// The rasterizer: setup and binning into 64x64 tiles, then 2x2 quads per tile (oneTBB).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "raster/camera.h"
#include "raster/interpolation.h"
#include "raster/mesh.h"

#if defined(__SSE__) || defined(_M_X64) || defined(_M_IX86)
#include <xmmintrin.h>
#define RS_HAVE_MXCSR 1
#endif

namespace reliefsim {

/// Tile edge in pixels (llvmpipe TILE_ORDER 6). Tile t covers pixels
/// [64 * (t % TileCountX), +64) x [64 * (t / TileCountX), +64).
constexpr int kTileSize = 64;
/// Sub-pixel bits of the fixed-point vertex positions (llvmpipe FIXED_ORDER 8).
constexpr int kSubPixelBits = 8;
/// Largest accepted image width or height.
constexpr int kMaxImageSize = 16384;

/// One 2x2 quad of fragments of one triangle. Lane k: 0 = (x, y), 1 = (x+1, y), 2 = (x,
/// y+1), 3 = (x+1, y+1) relative to pixel0; y grows downward (row 0 is the top of the
/// image). Helper lanes (not covered) carry attributes extrapolated from the triangle, as
/// on a GPU.
struct QuadFragment {
    glm::ivec2 pixel0;    // top-left pixel of the quad, both coordinates even
    uint8_t coveredMask;  // bit k: lane k is inside the triangle (pixel centre, fill
                          // rule), inside the image and passed the depth test; it writes
    uint8_t inImageMask;  // bit k: lane k's pixel is inside the image
    bool frontFacing;     // counter-clockwise in GL window space (y up): GL_CCW front
    uint32_t triangle;    // index of the mesh triangle (indices[3*triangle..])
    uint32_t piece;   // the clipped piece of it being drawn: EndTriangleInTile ends one
                      // piece, so lane groups are per (group, piece)
    glm::vec2 uv[4];  // perspective-correct uv at each lane's pixel centre
    glm::vec3 worldPos[4];  // perspective-correct world position
    // Perspective-correct tangent frame, not renormalised.
    glm::vec3 tangent[4], bitangent[4], normal[4];
    float depth[4];  // window depth in [0,1] (NDC z * 0.5 + 0.5), linear in window space
};

struct RasterOptions {
    // Depth test LESS against a per-tile depth buffer cleared to 1 (GL's default clear).
    bool depthTest = true;
};

/// Per-frame totals. A helper lane is a lane of a shaded quad that is not covered
/// (outside the triangle or the image, or failed the depth test): nHelperLanes = 4 *
/// nQuads - nCoveredLanes.
struct RasterStats {
    uint64_t nQuads = 0;         // quads passed to ShadeQuad
    uint64_t nCoveredLanes = 0;  // lanes with their coveredMask bit set
    uint64_t nHelperLanes = 0;   // lanes of those quads without it
};

inline int TileCountX(int width) { return (width + kTileSize - 1) / kTileSize; }
inline int TileCountY(int height) { return (height + kTileSize - 1) / kTileSize; }
inline int TileCount(int width, int height) {
    return TileCountX(width) * TileCountY(height);
}

/// Whether a fragment program reads the interpolated attributes of QuadFragment (uv,
/// worldPos, tangent frame). A program that computes its own inputs from the pixel
/// declares `static constexpr bool kReadsAttributes = false;` and the rasterizer then
/// interpolates only what the depth test needs.
template <class Program>
constexpr bool ReadsAttributes() {
    if constexpr (requires { Program::kReadsAttributes; })
        return Program::kReadsAttributes;
    else
        return true;
}

namespace detail {

/// A triangle after clipping, in fixed point, ready for the tile loop. Edge k (from
/// vertex k to vertex k+1) has E_k(px, py) = a[k]*px + b[k]*py + c[k] at the centre of
/// pixel (px, py); c holds the fill-rule bias minus one, so a pixel is inside iff all
/// three E_k >= 0. The plain edge function (the barycentric numerator of the opposite
/// vertex) is E_k + unbias[k].
struct SetupTriangle {
    int64_t a[3], b[3], c[3];
    int64_t unbias[3];
    glm::ivec2 bboxMin, bboxMax;  // inclusive pixel bounds, clipped to the image
    float invArea;                // 1 / (twice the area in fixed-point units squared)
    glm::vec3 invW;               // 1 / clip w per vertex
    glm::vec3 depth;              // window depth per vertex
    glm::vec2 uv[3];
    glm::vec3 worldPos[3], tangent[3], bitangent[3], normal[3];
    uint32_t triangle;
    uint32_t piece;  ///< index among the setup triangles (clipping's pieces), in order
    bool frontFacing;
};

struct FrameSetup {
    std::vector<SetupTriangle> triangles;     // in submission order
    std::vector<std::vector<uint32_t>> bins;  // per tile: triangle indices, in order
};

/// Vertex transform, clipping, fixed-point setup and binning, on the calling thread.
/// Throws reliefsim::Error for a bad image size or out-of-range indices.
FrameSetup SetupFrame(const Mesh& mesh, const Camera& camera, int width, int height);

/// Sets MXCSR flush-to-zero and denormals-are-zero for its lifetime (llvmpipe rasterizer
/// threads, research/llvmpipe.md §2.4) and restores the previous value. No-op without
/// SSE.
class DenormalsAreZeroScope {
  public:
#ifdef RS_HAVE_MXCSR
    DenormalsAreZeroScope() : saved(_mm_getcsr()) { _mm_setcsr(saved | 0x8040u); }
    ~DenormalsAreZeroScope() { _mm_setcsr(saved); }

  private:
    unsigned saved;
#else
    DenormalsAreZeroScope() {}
#endif
    DenormalsAreZeroScope(const DenormalsAreZeroScope&) = delete;
    DenormalsAreZeroScope& operator=(const DenormalsAreZeroScope&) = delete;
};

/// Fills the attributes of all four lanes of a quad (kAttributes = false: depth only).
template <bool kAttributes = true>
inline void InterpolateQuad(const SetupTriangle& tri, const int64_t (&e)[4][3],
                            QuadFragment& frag) {
    for (int lane = 0; lane < 4; ++lane) {
        if constexpr (!kAttributes) {
            const glm::vec3 bary(float(e[lane][1] + tri.unbias[1]) * tri.invArea,
                                 float(e[lane][2] + tri.unbias[2]) * tri.invArea,
                                 float(e[lane][0] + tri.unbias[0]) * tri.invArea);
            frag.depth[lane] = Interpolate(bary, tri.depth.x, tri.depth.y, tri.depth.z);
            continue;
        }
        // Window-space barycentrics: vertex 2 is opposite edge 0, vertex 0 opposite edge
        // 1, vertex 1 opposite edge 2.
        const glm::vec3 bary(float(e[lane][1] + tri.unbias[1]) * tri.invArea,
                             float(e[lane][2] + tri.unbias[2]) * tri.invArea,
                             float(e[lane][0] + tri.unbias[0]) * tri.invArea);
        const glm::vec3 w = PerspectiveWeights(bary, tri.invW);
        frag.uv[lane] = Interpolate(w, tri.uv[0], tri.uv[1], tri.uv[2]);
        frag.worldPos[lane] =
            Interpolate(w, tri.worldPos[0], tri.worldPos[1], tri.worldPos[2]);
        frag.tangent[lane] =
            Interpolate(w, tri.tangent[0], tri.tangent[1], tri.tangent[2]);
        frag.bitangent[lane] =
            Interpolate(w, tri.bitangent[0], tri.bitangent[1], tri.bitangent[2]);
        frag.normal[lane] = Interpolate(w, tri.normal[0], tri.normal[1], tri.normal[2]);
        frag.depth[lane] = Interpolate(bary, tri.depth.x, tri.depth.y, tri.depth.z);
    }
}

/// Walks the quads of one triangle inside [x0,x1] x [y0,y1] (pixels, x0 and y0 even).
/// kTestEdges = false is the fast path for a region known to lie inside all three edges.
template <bool kTestEdges, class Program>
void RasterizeTriangleInTile(const SetupTriangle& tri, int x0, int y0, int x1, int y1,
                             int width, int height, int tileX0, int tileY0,
                             float* depthBuffer, Program& program, int tileIndex,
                             RasterStats& stats) {
    QuadFragment frag;
    frag.triangle = tri.triangle;
    frag.piece = tri.piece;
    frag.frontFacing = tri.frontFacing;
    int64_t rowE[3];
    for (int k = 0; k < 3; ++k) rowE[k] = tri.a[k] * x0 + tri.b[k] * y0 + tri.c[k];
    for (int qy = y0; qy <= y1; qy += 2) {
        int64_t e00[3] = {rowE[0], rowE[1], rowE[2]};
        const uint8_t rowInImage = qy + 1 < height ? 0xF : 0x3;
        for (int qx = x0; qx <= x1; qx += 2) {
            int64_t e[4][3];
            for (int k = 0; k < 3; ++k) {
                e[0][k] = e00[k];
                e[1][k] = e00[k] + tri.a[k];
                e[2][k] = e00[k] + tri.b[k];
                e[3][k] = e00[k] + tri.a[k] + tri.b[k];
                e00[k] += 2 * tri.a[k];
            }
            const uint8_t inImage =
                qx + 1 < width ? rowInImage : uint8_t(rowInImage & 0x5);
            uint8_t mask = inImage;
            if constexpr (kTestEdges) {
                for (int lane = 0; lane < 4; ++lane) {
                    if ((e[lane][0] | e[lane][1] | e[lane][2]) < 0)
                        mask &= uint8_t(~(1u << lane));
                }
            }
            if (mask == 0) continue;
            bool interpolated = false;
            if (depthBuffer) {
                InterpolateQuad<ReadsAttributes<Program>()>(tri, e, frag);
                interpolated = true;
                for (int lane = 0; lane < 4; ++lane) {
                    if (!(mask & (1u << lane))) continue;
                    float& stored = depthBuffer[(qy + (lane >> 1) - tileY0) * kTileSize +
                                                (qx + (lane & 1) - tileX0)];
                    if (frag.depth[lane] < stored) {
                        stored = frag.depth[lane];
                    } else {
                        mask &= uint8_t(~(1u << lane));
                    }
                }
                if (mask == 0) continue;
            }
            if (!interpolated) InterpolateQuad<ReadsAttributes<Program>()>(tri, e, frag);
            frag.pixel0 = glm::ivec2(qx, qy);
            frag.coveredMask = mask;
            frag.inImageMask = inImage;
            program.ShadeQuad(static_cast<const QuadFragment&>(frag), tileIndex);
            const int nCovered = std::popcount(unsigned(mask));
            stats.nQuads += 1;
            stats.nCoveredLanes += uint64_t(nCovered);
            stats.nHelperLanes += uint64_t(4 - nCovered);
        }
        for (int k = 0; k < 3; ++k) rowE[k] += 2 * tri.b[k];
    }
}

/// Renders the binned triangles of one tile in submission order.
template <class Program>
RasterStats RasterizeTile(const FrameSetup& setup, int tileIndex, int width, int height,
                          Program& program, const RasterOptions& options) {
    RasterStats stats;
    const std::vector<uint32_t>& bin = setup.bins[size_t(tileIndex)];
    if (bin.empty()) return stats;
    DenormalsAreZeroScope fpScope;
    const int tilesX = TileCountX(width);
    const int tileX0 = (tileIndex % tilesX) * kTileSize;
    const int tileY0 = (tileIndex / tilesX) * kTileSize;
    const int tileX1 = std::min(tileX0 + kTileSize, width) - 1;   // inclusive
    const int tileY1 = std::min(tileY0 + kTileSize, height) - 1;  // inclusive
    std::array<float, kTileSize * kTileSize> depth;
    if (options.depthTest) depth.fill(1.0f);
    float* depthBuffer = options.depthTest ? depth.data() : nullptr;

    for (uint32_t t : bin) {
        const SetupTriangle& tri = setup.triangles[t];
        // Quad-aligned region of bbox ∩ tile; tiles start on even pixels, so quads never
        // straddle tiles. Lanes span [x0, x1 | 1] x [y0, y1 | 1].
        const int x0 = std::max(tri.bboxMin.x, tileX0) & ~1;
        const int y0 = std::max(tri.bboxMin.y, tileY0) & ~1;
        const int x1 = std::min(tri.bboxMax.x, tileX1);
        const int y1 = std::min(tri.bboxMax.y, tileY1);
        if (x0 > x1 || y0 > y1) continue;
        // Edge extrema over the lane rectangle: reject if outside one edge, fast path if
        // inside all three (edge functions are linear, so the corners bound them).
        bool outside = false, inside = true;
        for (int k = 0; k < 3; ++k) {
            const int64_t ax0 = tri.a[k] * x0, ax1 = tri.a[k] * (x1 | 1);
            const int64_t by0 = tri.b[k] * y0, by1 = tri.b[k] * (y1 | 1);
            const int64_t eMax = std::max(ax0, ax1) + std::max(by0, by1) + tri.c[k];
            const int64_t eMin = std::min(ax0, ax1) + std::min(by0, by1) + tri.c[k];
            outside = outside || eMax < 0;
            inside = inside && eMin >= 0;
        }
        if (outside) continue;
        if (inside) {
            RasterizeTriangleInTile<false>(tri, x0, y0, x1, y1, width, height, tileX0,
                                           tileY0, depthBuffer, program, tileIndex,
                                           stats);
        } else {
            RasterizeTriangleInTile<true>(tri, x0, y0, x1, y1, width, height, tileX0,
                                          tileY0, depthBuffer, program, tileIndex, stats);
        }
        if constexpr (requires { program.EndTriangleInTile(tileIndex); })
            program.EndTriangleInTile(tileIndex);
    }
    return stats;
}

}  // namespace detail

/// Renders the mesh with `program` as the fragment stage.
///
/// Pipeline (llvmpipe's, research/llvmpipe.md §3): on the calling thread, vertices go
/// through camera.clipFromWorld; triangles that cross the view volume are clipped as
/// Mesa's draw module does (x, y against the viewport, then the GL near and far planes,
/// then w > eps), mapped to window space, snapped to 1/256 pixel and binned into 64x64
/// tiles. After clipping, window coordinates lie in [0, size], so the 64-bit edge
/// functions cannot overflow. Then tbb::parallel_for runs over tiles; each tile takes its
/// triangles in submission order, walks 2x2 quads over bbox ∩ tile and calls
///     program.ShadeQuad(const QuadFragment&, int tileIndex)
/// for every quad with at least one covered lane, and, when the program has it,
///     program.EndTriangleInTile(int tileIndex)
/// after the quads of each triangle in each tile (a program that batches quads runs them
/// there, in order). Both faces are drawn; zero-area
/// triangles draw nothing.
///
/// Conventions:
/// * Viewport: NDC x in [-1,1] -> window x in [0,width]; NDC y = +1 is row 0, the TOP
///   row of our images. GL puts NDC y = -1 at its row 0, so the GL twin flips rows on
///   read-back.
/// * Coverage is exactly llvmpipe's for the same clip-space vertices: samples at pixel
///   centres, vertices snapped to 8 sub-pixel bits in GL window space (round to nearest
///   even), exact 64-bit edge functions, Mesa's clipper, and Mesa's GL fill rule. That
///   rule includes the pixels on a triangle's LEFT edges and on its BOTTOM horizontal
///   edges in our row-0-top images (the edges at the smallest GL window y: gallium
///   bottom_edge_rule = 0 on an FBO). Shared edges are covered exactly once.
/// * Attributes: perspective-correct from window-space barycentrics at the pixel centre
///   (PerspectiveWeights), depth linear in window space. Depth test LESS per pixel, the
///   buffer owned by the tile and cleared to 1.
///
/// Each pixel is owned by exactly one tile, so the program may write per-pixel buffers
/// without locks and keep per-tile partial sums in slot tileIndex (reduce them in tile
/// order). While a tile runs, MXCSR FTZ and DAZ are set (and restored afterwards), like
/// llvmpipe's rasterizer threads (§2.4); a no-op on non-x86. ShadeQuad may be called
/// concurrently for different tiles. Output is bit-identical for any thread count.
/// Returns the stats, summed in tile-index order. Throws reliefsim::Error if width or
/// height is outside [1, kMaxImageSize] or an index is out of range.
template <class Program>
RasterStats RasterizeFrame(const Mesh& mesh, const Camera& camera, int width, int height,
                           Program& program, const RasterOptions& options = {}) {
    const detail::FrameSetup setup = detail::SetupFrame(mesh, camera, width, height);
    const int nTiles = TileCount(width, height);
    std::vector<RasterStats> tileStats(static_cast<size_t>(nTiles));
    tbb::parallel_for(
        tbb::blocked_range<int>(0, nTiles, 1), [&](const tbb::blocked_range<int>& range) {
            for (int t = range.begin(); t != range.end(); ++t) {
                tileStats[size_t(t)] =
                    detail::RasterizeTile(setup, t, width, height, program, options);
            }
        });
    RasterStats total;
    for (const RasterStats& s : tileStats) {
        total.nQuads += s.nQuads;
        total.nCoveredLanes += s.nCoveredLanes;
        total.nHelperLanes += s.nHelperLanes;
    }
    return total;
}

}  // namespace reliefsim
