// Rasterizer tests: coverage, fill rule, interpolation, helpers, depth, tiles, threads.
#include "raster/rasterizer.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <glm/gtc/matrix_inverse.hpp>
#include <vector>

#include "core/error.h"
#include "raster/camera.h"
#include "raster/mesh.h"
#include "render/scene.h"

namespace reliefsim {
namespace {

/// Orthographic camera whose world (x, y) are our window coordinates in pixels (y down,
/// row 0 at the top) and whose world z is NDC z. Exact in float for power-of-two sizes.
Camera PixelCamera(int width, int height) {
    Camera cam{};
    cam.clipFromWorld = glm::mat4(1.0f);
    cam.clipFromWorld[0][0] = 2.0f / float(width);
    cam.clipFromWorld[3][0] = -1.0f;
    cam.clipFromWorld[1][1] = -2.0f / float(height);
    cam.clipFromWorld[3][1] = 1.0f;
    cam.viewFromWorld = glm::mat4(1.0f);
    cam.clipFromView = cam.clipFromWorld;
    return cam;
}

/// Mesh of window-space triangles; uv = window position so helper-lane uv can be checked.
Mesh WindowMesh(const std::vector<glm::vec3>& corners) {
    Mesh mesh;
    for (const glm::vec3& p : corners) {
        Vertex v{};
        v.position = p;
        v.uv = glm::vec2(p.x, p.y);
        v.normal = glm::vec3(0.0f, 0.0f, 1.0f);
        mesh.indices.push_back(uint32_t(mesh.vertices.size()));
        mesh.vertices.push_back(v);
    }
    return mesh;
}

/// Counts the writes of covered lanes per pixel and remembers the last writer.
struct CountProgram {
    int width, height;
    std::vector<int> count, lastTriangle;
    std::atomic<int> nBadLanes{0};
    CountProgram(int w, int h)
        : width(w), height(h), count(size_t(w * h), 0), lastTriangle(size_t(w * h), -1) {}
    void ShadeQuad(const QuadFragment& q, int /*tileIndex*/) {
        for (int lane = 0; lane < 4; ++lane) {
            const int x = q.pixel0.x + (lane & 1), y = q.pixel0.y + (lane >> 1);
            const bool inImage = x < width && y < height;
            if (bool(q.inImageMask & (1 << lane)) != inImage) ++nBadLanes;
            if (!(q.coveredMask & (1 << lane))) continue;
            if (!inImage) {
                ++nBadLanes;
                continue;
            }
            ++count[size_t(y * width + x)];
            lastTriangle[size_t(y * width + x)] = int(q.triangle);
        }
    }
};

/// Two triangles per axis-aligned rectangle with corners on pixel centres (x0+.5, y0+.5)
/// to (x1+.5, y1+.5), split along one diagonal; `flip` mirrors the winding of the second
/// one.
void AddRectangle(std::vector<glm::vec3>& c, float x0, float y0, float x1, float y1,
                  bool otherDiagonal, bool flip) {
    const glm::vec3 a(x0 + 0.5f, y0 + 0.5f, 0.0f), b(x1 + 0.5f, y0 + 0.5f, 0.0f);
    const glm::vec3 d(x1 + 0.5f, y1 + 0.5f, 0.0f), e(x0 + 0.5f, y1 + 0.5f, 0.0f);
    if (!otherDiagonal) {
        c.insert(c.end(), {a, b, d});
        c.insert(c.end(), flip ? std::initializer_list<glm::vec3>{a, e, d}
                               : std::initializer_list<glm::vec3>{a, d, e});
    } else {
        c.insert(c.end(), {b, d, e});
        c.insert(c.end(), flip ? std::initializer_list<glm::vec3>{b, a, e}
                               : std::initializer_list<glm::vec3>{b, e, a});
    }
}

/// Checks that exactly the pixels of the rectangle union [x0,x1) x (y0,y1] (Mesa's GL
/// rule in our row-0-top images: left and bottom edges in, right and top out) were
/// written once.
void ExpectRectangleCoverage(const CountProgram& p, int x0, int y0, int x1, int y1) {
    int nWrong = 0;
    for (int y = 0; y < p.height; ++y) {
        for (int x = 0; x < p.width; ++x) {
            const int expected = (x >= x0 && x < x1 && y > y0 && y <= y1) ? 1 : 0;
            if (p.count[size_t(y * p.width + x)] != expected && nWrong++ < 5) {
                ADD_FAILURE() << "pixel (" << x << ", " << y << ") written "
                              << p.count[size_t(y * p.width + x)] << " times, expected "
                              << expected;
            }
        }
    }
    EXPECT_EQ(nWrong, 0);
    EXPECT_EQ(p.nBadLanes.load(), 0);
}

TEST(Rasterizer, SharedEdgesOfQuadCoveredExactlyOnce) {
    const int w = 64, h = 64;
    for (int variant = 0; variant < 4; ++variant) {
        SCOPED_TRACE(variant);
        std::vector<glm::vec3> c;
        // 40x30 rectangle: its diagonals pass exactly through pixel centres every (4, 3).
        AddRectangle(c, 10, 10, 50, 40, variant & 1, variant & 2);
        CountProgram p(w, h);
        const RasterStats s = RasterizeFrame(WindowMesh(c), PixelCamera(w, h), w, h, p);
        ExpectRectangleCoverage(p, 10, 10, 50, 40);
        EXPECT_EQ(s.nCoveredLanes, uint64_t(40 * 30));
    }
    // 2x2 grid of rectangles sharing a vertical edge at x = 30.5 and a horizontal one at
    // y = 25.5, each split along alternating diagonals; one spans two tiles.
    std::vector<glm::vec3> c;
    AddRectangle(c, 10, 10, 30, 25, false, false);
    AddRectangle(c, 30, 10, 70, 25, true, true);
    AddRectangle(c, 10, 25, 30, 40, true, false);
    AddRectangle(c, 30, 25, 70, 40, false, true);
    CountProgram p(128, 64);
    RasterizeFrame(WindowMesh(c), PixelCamera(128, 64), 128, 64, p);
    ExpectRectangleCoverage(p, 10, 10, 70, 40);
}

/// Deterministic 64-bit mix (splitmix64) for test inputs.
uint64_t Mix(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

TEST(Rasterizer, SharedEdgesOfRandomFanCoveredExactlyOnce) {
    const int w = 128, h = 128;
    for (uint64_t seed = 0; seed < 8; ++seed) {
        SCOPED_TRACE(seed);
        // Centre on a pixel centre. Outer vertices: the 8 compass points at integer
        // offsets (spokes through pixel centres) plus random ones between them, all on
        // the 1/256 grid so the fixed-point snap is exact and the reference below is
        // exact in double.
        const glm::dvec2 centre(64.5, 64.5);
        std::vector<glm::dvec2> outer;
        const double kPi = 3.14159265358979323846;
        for (int k = 0; k < 8; ++k) {
            const int dx[8] = {40, 30, 0, -30, -40, -30, 0, 30};
            const int dy[8] = {0, 30, 40, 30, 0, -30, -40, -30};
            outer.push_back(centre + glm::dvec2(dx[k], dy[k]));
            const int nExtra = int(Mix(seed * 100 + uint64_t(k)) % 4);
            double prev = 0.0;
            for (int j = 0; j < nExtra; ++j) {
                const double u =
                    double(Mix(seed * 1000 + uint64_t(k * 10 + j)) >> 11) * 0x1p-53;
                prev = prev + (1.0 - prev) * u * 0.9;
                const double angle = (double(k) + prev) * kPi / 4.0;
                const double radius =
                    20.0 +
                    35.0 * double(Mix(seed + uint64_t(k * 77 + j)) % 1000) / 1000.0;
                glm::dvec2 q =
                    centre + radius * glm::dvec2(std::cos(angle), std::sin(angle));
                q = glm::round(q * 256.0) / 256.0;
                outer.push_back(q);
            }
        }
        std::vector<glm::vec3> c;
        const size_t n = outer.size();
        for (size_t k = 0; k < n; ++k) {
            const glm::dvec2 a = outer[k], b = outer[(k + 1) % n];
            // Alternate windings: both faces are drawn.
            if (k % 2) {
                c.insert(c.end(),
                         {glm::vec3(glm::vec2(centre), 0.0f),
                          glm::vec3(glm::vec2(a), 0.0f), glm::vec3(glm::vec2(b), 0.0f)});
            } else {
                c.insert(c.end(),
                         {glm::vec3(glm::vec2(b), 0.0f), glm::vec3(glm::vec2(a), 0.0f),
                          glm::vec3(glm::vec2(centre), 0.0f)});
            }
        }
        CountProgram p(w, h);
        RasterizeFrame(WindowMesh(c), PixelCamera(w, h), w, h, p);
        EXPECT_EQ(p.nBadLanes.load(), 0);

        auto cross = [](glm::dvec2 u, glm::dvec2 v) { return u.x * v.y - u.y * v.x; };
        int nWrong = 0, nInterior = 0;
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                const glm::dvec2 q(x + 0.5, y + 0.5);
                const int got = p.count[size_t(y * w + x)];
                if (got > 1) ++nWrong;
                // Exact classification: strictly inside a fan triangle, on an interior
                // spoke (or the centre), strictly outside every triangle, or on the outer
                // boundary.
                bool interior = false, onBoundary = false;
                for (size_t k = 0; k < n; ++k) {
                    const glm::dvec2 a = outer[k], b = outer[(k + 1) % n];
                    const double ea = cross(a - centre, q - centre);
                    const double eb = cross(b - a, q - a);
                    const double ec = cross(centre - b, q - b);
                    const double s = cross(a - centre, b - centre) > 0 ? 1.0 : -1.0;
                    if (s * ea > 0 && s * eb > 0 && s * ec > 0) interior = true;
                    if (s * ea >= 0 && s * eb >= 0 && s * ec >= 0) {
                        if (eb == 0) {
                            onBoundary = true;
                        } else {
                            interior = true;  // on a spoke or the centre, not on the rim
                        }
                    }
                }
                if (interior && !onBoundary) {
                    ++nInterior;
                    if (got != 1) ++nWrong;
                } else if (!interior && !onBoundary && got != 0) {
                    ++nWrong;
                }
            }
        }
        EXPECT_EQ(nWrong, 0);
        EXPECT_GT(nInterior, 2000);
    }
}

TEST(Rasterizer, FillRuleIncludesLeftAndBottomEdges) {
    // Rectangle with corners on the pixel centres (x0+.5, y0+.5) and (x1+.5, y1+.5).
    // Mesa's GL rule (verified against llvmpipe 22.3 through an FBO read back with rows
    // flipped, so row 0 is NDC y = +1): left and bottom edges are in, right and top edges
    // out, so exactly (x1 - x0) * (y1 - y0) pixels: columns x0..x1-1 and rows y0+1..y1.
    const int w = 32, h = 32, x0 = 5, y0 = 7, x1 = 21, y1 = 18;
    std::vector<glm::vec3> c;
    AddRectangle(c, x0, y0, x1, y1, false, false);
    CountProgram p(w, h);
    const RasterStats s = RasterizeFrame(WindowMesh(c), PixelCamera(w, h), w, h, p);
    EXPECT_EQ(s.nCoveredLanes, uint64_t((x1 - x0) * (y1 - y0)));
    EXPECT_EQ(p.count[size_t(y0 * w + 10)], 0);  // top edge row
    EXPECT_EQ(p.count[size_t(y1 * w + 10)], 1);  // bottom edge row
    EXPECT_EQ(p.count[size_t(10 * w + x0)], 1);  // left edge column
    EXPECT_EQ(p.count[size_t(10 * w + x1)], 0);  // right edge column
    ExpectRectangleCoverage(p, x0, y0, x1, y1);
}

/// Records uv, world position and depth of covered lanes.
struct AttributeProgram {
    int width, height;
    std::vector<glm::vec2> uv;
    std::vector<glm::vec3> worldPos;
    std::vector<float> depth;
    std::vector<uint8_t> covered;
    std::vector<RasterStats> perTile;
    AttributeProgram(int w, int h)
        : width(w),
          height(h),
          uv(size_t(w * h), glm::vec2(-1.0f)),
          worldPos(size_t(w * h), glm::vec3(-1.0f)),
          depth(size_t(w * h), -1.0f),
          covered(size_t(w * h), 0),
          perTile(size_t(TileCount(w, h))) {}
    void ShadeQuad(const QuadFragment& q, int tileIndex) {
        perTile[size_t(tileIndex)].nQuads++;
        for (int lane = 0; lane < 4; ++lane) {
            if (!(q.coveredMask & (1 << lane))) continue;
            const size_t i =
                size_t((q.pixel0.y + (lane >> 1)) * width + q.pixel0.x + (lane & 1));
            uv[i] = q.uv[lane];
            worldPos[i] = q.worldPos[lane];
            depth[i] = q.depth[lane];
            covered[i]++;
        }
    }
};

TEST(Rasterizer, PerspectiveCorrectUvMatchesRayPlaneIntersection) {
    const int w = 256, h = 256;
    const Camera cam = MakeOrbitCamera(60.0f, 30.0f, 2.0f, 45.0f, 1.0f);
    AttributeProgram p(w, h);
    RasterizeFrame(MakePlane(1.0f), cam, w, h, p);
    const glm::dmat4 worldFromClip = glm::inverse(glm::dmat4(cam.clipFromWorld));
    double maxUvError = 0.0, maxPosError = 0.0;
    int nCovered = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y * w + x);
            if (!p.covered[i]) continue;
            ++nCovered;
            // Pixel centre -> NDC (row 0 is NDC y = +1) -> world ray -> hit with z = 0.
            const double ndcX = 2.0 * (x + 0.5) / w - 1.0,
                         ndcY = 1.0 - 2.0 * (y + 0.5) / h;
            glm::dvec4 a = worldFromClip * glm::dvec4(ndcX, ndcY, -1.0, 1.0);
            glm::dvec4 b = worldFromClip * glm::dvec4(ndcX, ndcY, 1.0, 1.0);
            const glm::dvec3 pa = glm::dvec3(a) / a.w, pb = glm::dvec3(b) / b.w;
            const double t = pa.z / (pa.z - pb.z);
            const glm::dvec3 hit = pa + t * (pb - pa);
            const glm::dvec2 uvRef(hit.x + 0.5, 0.5 - hit.y);
            maxUvError = std::max(maxUvError, glm::length(glm::dvec2(p.uv[i]) - uvRef));
            maxPosError =
                std::max(maxPosError, glm::length(glm::dvec3(p.worldPos[i]) - hit));
        }
    }
    EXPECT_GT(nCovered, 5000);
    EXPECT_LT(maxUvError,
              1e-4);  // uv units; vertex snapping to 1/256 px bounds it near 2e-5
    EXPECT_LT(maxPosError, 1e-4);  // world units
}

/// Checks quad invariants, and writes covered lanes only.
struct HelperProgram {
    int width, height;
    std::vector<int> written;
    std::vector<uint64_t> nHelpers, nQuadsWithHelpers;
    std::atomic<int> nBad{0};
    HelperProgram(int w, int h)
        : width(w),
          height(h),
          written(size_t(w * h), 0),
          nHelpers(size_t(TileCount(w, h))),
          nQuadsWithHelpers(size_t(TileCount(w, h))) {}
    void ShadeQuad(const QuadFragment& q, int tileIndex) {
        if (q.coveredMask == 0 || (q.coveredMask & ~q.inImageMask) != 0) ++nBad;
        if (q.pixel0.x % 2 != 0 || q.pixel0.y % 2 != 0) ++nBad;
        const int nCovered = std::popcount(unsigned(q.coveredMask));
        nHelpers[size_t(tileIndex)] += uint64_t(4 - nCovered);
        if (nCovered < 4) nQuadsWithHelpers[size_t(tileIndex)]++;
        for (int lane = 0; lane < 4; ++lane) {
            const int x = q.pixel0.x + (lane & 1), y = q.pixel0.y + (lane >> 1);
            // Orthographic pixel camera with uv = window position: every lane, helper or
            // not, carries the attribute extrapolated to its own pixel centre. Tolerance:
            // vertices snap by up to 1/512 px while their uv does not move.
            if (std::abs(q.uv[lane].x - (float(x) + 0.5f)) > 2e-2f ||
                std::abs(q.uv[lane].y - (float(y) + 0.5f)) > 2e-2f) {
                ++nBad;
            }
            if (q.coveredMask & (1 << lane)) written[size_t(y * width + x)]++;
        }
    }
};

TEST(Rasterizer, HelperLanesAreCountedAndNotWritten) {
    // Odd image size, and a triangle leaving the image on the right and the bottom, so
    // quads also have lanes outside the image.
    const int w = 63, h = 45;
    const std::vector<glm::vec3> c = {
        {3.3f, 2.7f, 0.0f}, {80.1f, 20.2f, 0.0f}, {11.6f, 61.9f, 0.0f}};
    HelperProgram p(w, h);
    const RasterStats s = RasterizeFrame(WindowMesh(c), PixelCamera(w, h), w, h, p);
    EXPECT_EQ(p.nBad.load(), 0);
    uint64_t nHelpers = 0, nQuadsWithHelpers = 0;
    for (size_t t = 0; t < p.nHelpers.size(); ++t) {
        nHelpers += p.nHelpers[t];
        nQuadsWithHelpers += p.nQuadsWithHelpers[t];
    }
    EXPECT_GT(nQuadsWithHelpers, 20u);
    EXPECT_EQ(s.nHelperLanes, nHelpers);
    EXPECT_EQ(s.nHelperLanes, 4 * s.nQuads - s.nCoveredLanes);
    // Written pixels are exactly the covered ones: once each, each inside the triangle.
    uint64_t nWritten = 0;
    auto edge = [](glm::dvec2 a, glm::dvec2 b, glm::dvec2 q) {
        return (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
    };
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const int n = p.written[size_t(y * w + x)];
            EXPECT_LE(n, 1);
            nWritten += uint64_t(n);
            const glm::dvec2 q(x + 0.5, y + 0.5);
            const glm::dvec2 a(c[0]), b(c[1]), d(c[2]);
            const bool inside =
                edge(a, b, q) > 0 && edge(b, d, q) > 0 && edge(d, a, q) > 0;
            const bool outside =
                edge(a, b, q) < 0 || edge(b, d, q) < 0 || edge(d, a, q) < 0;
            // Snapping moves edges by < 1/256 px; only judge pixels clearly on one side.
            if (inside && n != 1)
                ADD_FAILURE() << "inside pixel not written: " << x << "," << y;
            if (outside && n != 0)
                ADD_FAILURE() << "outside pixel written: " << x << "," << y;
        }
    }
    EXPECT_EQ(nWritten, s.nCoveredLanes);
}

TEST(Rasterizer, DepthTestIsIndependentOfSubmissionOrder) {
    const int w = 96, h = 80;
    // Near triangle at NDC z = -0.5, far one at z = 0.5; they overlap in the middle.
    const std::vector<glm::vec3> nearTri = {
        {5.0f, 5.0f, -0.5f}, {70.0f, 12.0f, -0.5f}, {20.0f, 70.0f, -0.5f}};
    const std::vector<glm::vec3> farTri = {
        {90.0f, 75.0f, 0.5f}, {15.0f, 30.0f, 0.5f}, {80.0f, 3.0f, 0.5f}};
    std::vector<glm::vec3> nearFirst = nearTri, farFirst = farTri;
    nearFirst.insert(nearFirst.end(), farTri.begin(), farTri.end());
    farFirst.insert(farFirst.end(), nearTri.begin(), nearTri.end());
    CountProgram a(w, h), b(w, h);
    RasterizeFrame(WindowMesh(nearFirst), PixelCamera(w, h), w, h, a);
    RasterizeFrame(WindowMesh(farFirst), PixelCamera(w, h), w, h, b);
    int nOverlap = 0;
    for (size_t i = 0; i < a.lastTriangle.size(); ++i) {
        // Map triangle ids to "near" (0) / "far" (1) in both submissions.
        const int idA = a.lastTriangle[i] < 0 ? -1 : a.lastTriangle[i];
        const int idB = b.lastTriangle[i] < 0 ? -1 : 1 - b.lastTriangle[i];
        EXPECT_EQ(idA, idB) << "pixel " << i;
        if (b.count[i] == 2) ++nOverlap;  // far first, then near overwrote it
    }
    EXPECT_GT(nOverlap, 100);
    // With the depth test off, the last submitted triangle wins.
    CountProgram c(w, h);
    RasterizeFrame(WindowMesh(farFirst), PixelCamera(w, h), w, h, c,
                   RasterOptions{false});
    int nNearWins = 0;
    for (size_t i = 0; i < c.lastTriangle.size(); ++i)
        nNearWins += c.lastTriangle[i] == 1;
    EXPECT_GT(nNearWins, 0);
}

/// A mesh with many triangles in several depths, for determinism checks.
Mesh BusyMesh() {
    Mesh mesh = MakePlane(3.0f);
    for (int k = 0; k < 40; ++k) {
        const uint64_t r = Mix(uint64_t(k));
        const float cx = float(r % 1000) / 1000.0f - 0.5f;
        const float cy = float((r >> 10) % 1000) / 1000.0f - 0.5f;
        const float z = float((r >> 20) % 1000) / 2000.0f;
        const uint32_t base = uint32_t(mesh.vertices.size());
        for (int j = 0; j < 3; ++j) {
            Vertex v = mesh.vertices[size_t(j)];
            const float angle = float(j) * 2.1f + float(k);
            v.position =
                glm::vec3(cx + 0.3f * std::cos(angle), cy + 0.3f * std::sin(angle), z);
            v.uv = glm::vec2(v.position) * 2.0f;
            mesh.vertices.push_back(v);
            mesh.indices.push_back(base + uint32_t(j));
        }
    }
    return mesh;
}

TEST(Rasterizer, OutputIsIdenticalForOneAndTwoThreads) {
    const int w = 300, h = 200;
    const Mesh mesh = BusyMesh();
    const Camera cam = MakeOrbitCamera(50.0f, 20.0f, 1.5f, 60.0f, float(w) / float(h));
    auto render = [&](int nThreads, AttributeProgram& p) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                  size_t(nThreads));
        return RasterizeFrame(mesh, cam, w, h, p);
    };
    AttributeProgram one(w, h), two(w, h);
    const RasterStats s1 = render(1, one);
    const RasterStats s2 = render(2, two);
    EXPECT_GT(s1.nQuads, 1000u);
    EXPECT_EQ(s1.nQuads, s2.nQuads);
    EXPECT_EQ(s1.nCoveredLanes, s2.nCoveredLanes);
    EXPECT_EQ(s1.nHelperLanes, s2.nHelperLanes);
    EXPECT_EQ(
        std::memcmp(one.uv.data(), two.uv.data(), one.uv.size() * sizeof(glm::vec2)), 0);
    EXPECT_EQ(std::memcmp(one.worldPos.data(), two.worldPos.data(),
                          one.worldPos.size() * sizeof(glm::vec3)),
              0);
    EXPECT_EQ(
        std::memcmp(one.depth.data(), two.depth.data(), one.depth.size() * sizeof(float)),
        0);
    EXPECT_EQ(one.covered, two.covered);
    for (size_t t = 0; t < one.perTile.size(); ++t) {
        EXPECT_EQ(one.perTile[t].nQuads, two.perTile[t].nQuads) << "tile " << t;
    }
}

struct TileCheckProgram {
    int width;
    std::atomic<int> nOutside{0};
    std::atomic<int> nCalls{0};
    void ShadeQuad(const QuadFragment& q, int tileIndex) {
        ++nCalls;
        const int tilesX = TileCountX(width);
        const int tx0 = (tileIndex % tilesX) * kTileSize,
                  ty0 = (tileIndex / tilesX) * kTileSize;
        for (int lane = 0; lane < 4; ++lane) {
            const int x = q.pixel0.x + (lane & 1), y = q.pixel0.y + (lane >> 1);
            if (x < tx0 || x >= tx0 + kTileSize || y < ty0 || y >= ty0 + kTileSize)
                ++nOutside;
        }
    }
};

TEST(Rasterizer, ShadeQuadPixelsLieInTheirTile) {
    const int w = 201, h = 133;  // partial tiles on the right and bottom
    TileCheckProgram p{w};
    const RasterStats s = RasterizeFrame(
        BusyMesh(), MakeOrbitCamera(30.0f, 70.0f, 1.2f, 60.0f, float(w) / float(h)), w, h,
        p);
    EXPECT_EQ(p.nOutside.load(), 0);
    EXPECT_EQ(uint64_t(p.nCalls.load()), s.nQuads);
    EXPECT_GT(s.nQuads, 1000u);
    EXPECT_EQ(TileCount(w, h), 4 * 3);
}

TEST(Rasterizer, HugeClippedTrianglesCoverPixelsOnce) {
    // A plane far larger than the view, seen from close by: its triangles cross the near
    // plane and the viewport, and are clipped. The shared diagonal must still be covered
    // exactly once.
    Mesh mesh = MakePlane(1.0f);
    for (Vertex& v : mesh.vertices) v.position *= 1.0e5f;
    const int w = 160, h = 120;
    CountProgram p(w, h);
    const RasterStats s = RasterizeFrame(
        mesh, MakeOrbitCamera(80.0f, 10.0f, 1.0f, 60.0f, 4.0f / 3.0f), w, h, p);
    EXPECT_EQ(p.nBadLanes.load(), 0);
    int nWritten = 0;
    for (int n : p.count) {
        EXPECT_LE(n, 1);
        nWritten += n;
    }
    EXPECT_EQ(uint64_t(nWritten), s.nCoveredLanes);
    EXPECT_GT(nWritten, w * h / 4);  // the lower part of the image sees the plane
    EXPECT_LT(nWritten, w * h);      // the horizon is in view
}

TEST(Rasterizer, ZeroAreaTrianglesProduceNothing) {
    const std::vector<glm::vec3> c = {{2.5f, 2.5f, 0.0f},   {20.5f, 20.5f, 0.0f},
                                      {11.5f, 11.5f, 0.0f},  // collinear
                                      {5.0f, 30.0f, 0.0f},  {5.0f, 30.0f, 0.0f},
                                      {25.0f, 3.0f, 0.0f}};  // repeated vertex
    CountProgram p(32, 32);
    const RasterStats s = RasterizeFrame(WindowMesh(c), PixelCamera(32, 32), 32, 32, p);
    EXPECT_EQ(s.nQuads, 0u);
}

TEST(Rasterizer, BadImageSizeThrowsWithValidRange) {
    CountProgram p(1, 1);
    try {
        RasterizeFrame(MakePlane(1.0f), PixelCamera(1, 1), 0, 10, p);
        FAIL() << "expected reliefsim::Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("expected 1..16384"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(MakeOrbitCamera(90.0f, 0.0f, 1.0f, 45.0f, 1.0f), Error);
}

TEST(Rasterizer, OrbitCameraConventions) {
    // Azimuth 0: the camera is on the -y side and image up points toward +y.
    const Camera cam = MakeOrbitCamera(60.0f, 0.0f, 2.0f, 45.0f, 1.0f);
    EXPECT_NEAR(cam.eye.x, 0.0f, 1e-6f);
    EXPECT_LT(cam.eye.y, 0.0f);
    EXPECT_NEAR(glm::length(cam.eye), 2.0f, 1e-5f);
    EXPECT_NEAR(cam.eye.z, 1.0f, 1e-5f);  // cos(60°) * 2
    // Looking straight down is well defined; world +y projects upward (NDC y grows).
    const Camera top = MakeOrbitCamera(0.0f, 0.0f, 2.0f, 45.0f, 1.0f);
    const glm::vec4 a = top.clipFromWorld * glm::vec4(0.0f, 0.1f, 0.0f, 1.0f);
    const glm::vec4 b = top.clipFromWorld * glm::vec4(0.1f, 0.0f, 0.0f, 1.0f);
    EXPECT_GT(a.y / a.w, 0.0f);
    EXPECT_GT(b.x / b.w, 0.0f);
    EXPECT_FALSE(std::isnan(a.x));
}

}  // namespace
}  // namespace reliefsim
