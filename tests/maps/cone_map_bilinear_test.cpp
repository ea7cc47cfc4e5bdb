// Bilinear-bound cone maps (maps/cone_map_bilinear.h): the fast search equals every cell
// pair bit for bit, a ridge gives the closed-form ratios, and a dense march of the
// bilinear surface finds no point inside any sampled cone (where the texel-centre maps
// do have such points).
#include "maps/cone_map_bilinear.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.h"
#include "core/hash.h"
#include "maps/cone_map_detail.h"
#include "tests/common/fields.h"
#include "texture/procedural.h"

namespace reliefsim {
namespace {

DepthField Field(int w, int h, uint64_t seed, bool smooth) {
    return testing::MakeField(
        w, h,
        [&](int i, int j) {
            const uint64_t r =
                Mix64(seed * 1000003ull + uint64_t(j) * uint64_t(w) + uint64_t(i));
            const float v = float(r >> 40) * (1.0f / 16777216.0f);
            if (!smooth) return v;
            return v < 0.85f ? 0.5f + 0.3f * std::sin(float(i) * 0.7f) *
                                          std::cos(float(j) * 0.45f)
                             : 0.5f * v;
        },
        "random");
}

constexpr ConeKind kKinds[] = {ConeKind::Cone, ConeKind::ConeNormal, ConeKind::Quad,
                               ConeKind::Acm4, ConeKind::Acm8};

TEST(BilinearConeMap, FastEqualsBruteForce) {
    const DepthField fields[] = {Field(24, 24, 1, false), Field(24, 24, 2, true),
                                 Field(20, 12, 3, true), MakeBuiltinMap("shapes", 32, 32),
                                 MakeBuiltinMap("steps", 32, 32)};
    for (const DepthField& hf : fields)
        for (ConeKind kind : kKinds) {
            const ConeMap fast = GenerateBilinearConeMap(hf, kind);
            const ConeMap brute = GenerateBilinearConeMapBruteForce(hf, kind);
            ASSERT_EQ(fast.values.size(), brute.values.size());
            ASSERT_EQ(fast.channels,
                      detail::SectorCount(kind == ConeKind::ConeNormal ? ConeKind::Cone
                                                                       : kind));
            EXPECT_EQ(std::memcmp(fast.values.data(), brute.values.data(),
                                  fast.values.size() * sizeof(float)),
                      0)
                << ToString(kind) << " on " << hf.width << "x" << hf.height;
        }
}

/// A one-texel ridge at column 8 (depth 0.2) on a plane at 0.8, 32x32.
DepthField Ridge() {
    DepthField hf;
    hf.width = hf.height = 32;
    hf.name = "ridge";
    hf.depth.assign(32 * 32, 0.8f);
    for (int j = 0; j < 32; ++j) hf.depth[size_t(j) * 32 + 8] = 0.2f;
    return hf;
}

TEST(BilinearConeMap, RidgeGivesTheClosedFormRatios) {
    // Texel T = 8 + n (n >= 3): its cells' far blockers are the cells holding the ridge
    // (shallowest corner 0.2) n - 2 texels away across the gap, the apexes at 0.8, and
    // the 3x3 cells around are flat: r = (n - 2) / 32 / 0.6. For n = 1, 2 a cell next to
    // the ridge is among the 3x3 (gradient 0.6 * 32 per uv): r = 1 / (0.6 * 32), which
    // the far cells (gap 1) give as well.
    const DepthField hf = Ridge();
    const ConeMap cone = GenerateBilinearConeMap(hf, ConeKind::Cone);
    const ConeMap acm4 = GenerateBilinearConeMap(hf, ConeKind::Acm4);
    const double dd = double(0.8f) - double(0.2f);
    for (int n = 1; n <= 12; ++n) {
        const double exact = n <= 2 ? 1.0 / (dd * 32.0) : (n - 2) / 32.0 / dd;
        for (int j : {0, 13, 31}) {
            const float r = cone.At(8 + n, j);
            EXPECT_LE(double(r), exact) << n;
            EXPECT_NEAR(double(r), exact, exact * 1e-6) << n;
            // Mirrored on the other side.
            EXPECT_EQ(cone.At(detail::Wrap(8 - n, 32), j), r) << n;
            // acm4: the quadrants facing the ridge (-x: 1 and 2) have it; those facing
            // away see no blocker once the ridge's cells are out of their Minkowski
            // reach (n >= 4: neither far nor among the 3x3 cells).
            EXPECT_EQ(acm4.At(8 + n, j, 1), r) << n;
            EXPECT_EQ(acm4.At(8 + n, j, 2), r) << n;
            if (n >= 4) {
                EXPECT_EQ(acm4.At(8 + n, j, 0), kConeRatioCap) << n;
                EXPECT_EQ(acm4.At(8 + n, j, 3), kConeRatioCap) << n;
            }
        }
    }
    // A flat map has no blocker anywhere.
    DepthField flat = hf;
    std::fill(flat.depth.begin(), flat.depth.end(), 0.5f);
    for (float v : GenerateBilinearConeMap(flat, ConeKind::Acm8).values)
        EXPECT_EQ(v, kConeRatioCap);
}

/// The bilinear surface in double, wrapped, at texel coordinates (x, y) (texel centres
/// at integers).
double Surface(const DepthField& hf, double x, double y) {
    const int W = hf.width, H = hf.height;
    const double fx = std::floor(x), fy = std::floor(y);
    const double a = x - fx, b = y - fy;
    const int i = detail::Wrap(int(fx), W), j = detail::Wrap(int(fy), H);
    const int i1 = detail::Wrap(i + 1, W), j1 = detail::Wrap(j + 1, H);
    const double d00 = hf.At(i, j), d10 = hf.At(i1, j), d01 = hf.At(i, j1),
                 d11 = hf.At(i1, j1);
    return (1 - b) * ((1 - a) * d00 + a * d10) + b * ((1 - a) * d01 + a * d11);
}

/// Points p and q of the surface (8x8 per cell) for which q lies inside the cone at p
/// that the map gives with the widest of the four texels around p (nearest, bilinear
/// and min-of-4 all give at most that), in the sector holding q - p: how many.
int InsideCones(const DepthField& hf, const ConeMap& m, ConeKind sectors) {
    const int W = hf.width, H = hf.height, S = 8;
    const detail::Geometry g = detail::MakeGeometry(W, H);
    int inside = 0;
    std::vector<double> depth(size_t(W * S) * size_t(H * S));
    for (int y = 0; y < H * S; ++y)
        for (int x = 0; x < W * S; ++x)
            depth[size_t(y) * size_t(W * S) + size_t(x)] =
                Surface(hf, double(x) / S, double(y) / S);
    for (int py = 0; py < H * S; ++py)
        for (int px = 0; px < W * S; ++px) {
            const int i = px / S, j = py / S;
            const double dp = depth[size_t(py) * size_t(W * S) + size_t(px)];
            double r[8];
            for (int c = 0; c < m.channels; ++c) {
                r[c] = 0;
                for (int cy = 0; cy <= 1; ++cy)
                    for (int cx = 0; cx <= 1; ++cx)
                        r[c] = std::max(r[c], double(m.At(detail::Wrap(i + cx, W),
                                                          detail::Wrap(j + cy, H), c)));
            }
            for (int qy = 0; qy < H * S; ++qy)
                for (int qx = 0; qx < W * S; ++qx) {
                    const double dq = depth[size_t(qy) * size_t(W * S) + size_t(qx)];
                    if (!(dq < dp)) continue;
                    // The nearest image of q - p, in texels.
                    int ex = qx - px, ey = qy - py;
                    if (ex > W * S / 2) ex -= W * S;
                    if (ex < -W * S / 2) ex += W * S;
                    if (ey > H * S / 2) ey -= H * S;
                    if (ey < -H * S / 2) ey += H * S;
                    const double du = double(ex) / (S * W), dv = double(ey) / (S * H);
                    const double dist = std::sqrt(du * du + dv * dv);
                    // Sectors of the direction (ex, ey): SectorMask of the texel offsets
                    // scaled by S keeps the same direction.
                    const unsigned mask = sectors == ConeKind::Cone
                                              ? 1u
                                              : detail::SectorMask(sectors, g, ex, ey);
                    for (int c = 0; c < m.channels; ++c)
                        if ((mask >> c & 1u) && dist < r[c] * (dp - dq) * (1 - 1e-9)) {
                            ++inside;
                            break;
                        }
                }
        }
    return inside;
}

TEST(BilinearConeMap, NoSurfacePointInsideASampledCone) {
    // A dense oracle of the definition's claim, on sharp and smooth random maps: no
    // point of the bilinear surface lies inside the cone at any other point. The
    // texel-centre maps of the same fields have such points (what min4 cannot repair).
    const DepthField fields[] = {Field(10, 10, 5, false), Field(12, 8, 6, true)};
    for (const DepthField& hf : fields) {
        EXPECT_EQ(
            InsideCones(hf, GenerateBilinearConeMap(hf, ConeKind::Cone), ConeKind::Cone),
            0);
        EXPECT_EQ(
            InsideCones(hf, GenerateBilinearConeMap(hf, ConeKind::Acm4), ConeKind::Acm4),
            0);
        EXPECT_EQ(
            InsideCones(hf, GenerateBilinearConeMap(hf, ConeKind::Quad), ConeKind::Quad),
            0);
        EXPECT_GT(InsideCones(hf, GenerateConeMap(hf, ConeKind::Cone), ConeKind::Cone),
                  0);
    }
    const DepthField sq = Field(8, 8, 7, false);
    EXPECT_EQ(
        InsideCones(sq, GenerateBilinearConeMap(sq, ConeKind::Acm8), ConeKind::Acm8), 0);
}

TEST(BilinearConeMap, RefusesKindsAndParametersWithoutAVariant) {
    const DepthField hf = Field(8, 8, 1, true);
    for (ConeKind k : {ConeKind::Relaxed, ConeKind::RelaxedExact, ConeKind::Stacked,
                       ConeKind::MinMip, ConeKind::MaxMip}) {
        EXPECT_FALSE(HasBilinearBounds(k));
        EXPECT_THROW(GenerateBilinearConeMap(hf, k), Error) << ToString(k);
    }
    ConeMapParams relaxed;
    relaxed.relaxed = true;
    EXPECT_THROW(GenerateBilinearConeMap(hf, ConeKind::ConeNormal, relaxed), Error);
    ConeMapParams adaptive;
    adaptive.adaptive = true;
    EXPECT_THROW(GenerateBilinearConeMap(hf, ConeKind::Acm4, adaptive), Error);
    DepthField nan = hf;
    nan.depth[5] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THROW(GenerateBilinearConeMap(nan, ConeKind::Cone), Error);
    DepthField empty;
    EXPECT_THROW(GenerateBilinearConeMap(empty, ConeKind::Cone), Error);
}

}  // namespace
}  // namespace reliefsim
