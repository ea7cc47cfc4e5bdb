// The exact reference: closed-form cases, and a dense oracle on random rays over every
// built-in map and random maps (docs/exact.md "Validation").
#include "metrics/exact.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.h"
#include "tests/common/fields.h"
#include "texture/procedural.h"

using namespace reliefsim;

namespace {

DepthField Field(int w, int h, auto&& depthAt) {
    return reliefsim::testing::MakeField(w, h, depthAt);
}

struct RayCase {
    double u0, v0, du, dv;
};

/// The dense oracle: g(t) = t - depth(ray(t)) at kSamples + 1 evenly spaced t, the first
/// sample inside, then bisection between it and the sample before (in double).
struct OracleHit {
    double t;        ///< bisected crossing
    double tInside;  ///< the first sample with g >= 0
    double tBefore;  ///< the sample before it (0 when the entry is inside)
};
constexpr int kSamples = 100000;

OracleHit Oracle(const ExactSurface& s, const RayCase& r) {
    auto g = [&](double t) { return t - s.DepthAt(r.u0 + t * r.du, r.v0 + t * r.dv); };
    if (g(0.0) >= 0) return {0.0, 0.0, 0.0};
    for (int k = 1; k <= kSamples; ++k) {
        const double t = double(k) / kSamples;
        if (g(t) < 0) continue;
        double lo = double(k - 1) / kSamples, hi = t;
        for (int it = 0; it < 80; ++it) {
            const double mid = 0.5 * (lo + hi);
            (g(mid) >= 0 ? hi : lo) = mid;
        }
        return {hi, t, double(k - 1) / kSamples};
    }
    return {1.0, 1.0, 1.0};
}

/// Random rays: entry anywhere over three tiles, uv travel per unit depth from 0
/// (vertical) to `maxTravel` (grazing: many cells), in every direction, plus rays along
/// the grid lines and the axes.
std::vector<RayCase> RandomRays(int n, double maxTravel, uint32_t seed, int w, int h) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> pos(-1.0, 2.0), ang(0.0, 6.283185307179586),
        unit(0.0, 1.0);
    std::vector<RayCase> rays;
    for (int k = 0; k < n; ++k) {
        const double len = maxTravel * unit(rng) * unit(rng), a = ang(rng);
        RayCase r{pos(rng), pos(rng), len * std::cos(a), len * std::sin(a)};
        switch (k % 8) {
            case 0:  // along a grid line of texel centres, moving along it
                r.v0 = (std::floor(r.v0 * h) + 0.5) / h;
                r.dv = 0;
                break;
            case 1:
                r.u0 = (std::floor(r.u0 * w) + 0.5) / w;
                r.du = 0;
                break;
            case 2:  // vertical
                r.du = r.dv = 0;
                break;
            case 3:  // exact diagonal through cell corners
                r.u0 = (std::floor(r.u0 * w) + 0.5) / w;
                r.v0 = (std::floor(r.v0 * h) + 0.5) / h;
                r.dv = r.du * double(w) / double(h);
                break;
            default:
                break;
        }
        rays.push_back(r);
    }
    return rays;
}

struct OracleStats {
    int rays = 0, thinTouches = 0;
    double worst = 0;  ///< largest |t_exact - t_oracle| where both see the same crossing
};

/// Checks every ray against the oracle: the exact hit is on the surface or inside it, it
/// is never after the oracle's first inside sample, and it agrees with the bisected
/// crossing to 1e-9 unless it lies before the oracle's bracket (a feature thinner than
/// the sample spacing, which the exact hit must then really touch).
void CheckAgainstOracle(const ExactSurface& s, const std::vector<RayCase>& rays,
                        OracleStats& stats, const char* what) {
    for (const RayCase& r : rays) {
        const ExactHit e = s.FirstHit(r.u0, r.v0, r.du, r.dv);
        const OracleHit o = Oracle(s, r);
        const double gExact = e.t - s.DepthAt(r.u0 + e.t * r.du, r.v0 + e.t * r.dv);
        ++stats.rays;
        ASSERT_GE(e.t, 0.0);
        ASSERT_LE(e.t, 1.0);
        ASSERT_GE(gExact, -1e-12)
            << what << ": the exact hit is not on the surface, ray " << r.u0 << ","
            << r.v0 << " dir " << r.du << "," << r.dv;
        ASSERT_LE(e.t, o.tInside + 1e-12)
            << what << ": the oracle found the ray inside before the exact hit, ray "
            << r.u0 << "," << r.v0 << " dir " << r.du << "," << r.dv << " exact " << e.t
            << " oracle " << o.t;
        EXPECT_NEAR(e.u, r.u0 + e.t * r.du, 1e-15 + 1e-15 * std::abs(e.u));
        if (e.t < o.tBefore) {
            ++stats.thinTouches;
            continue;
        }
        const double d = std::abs(e.t - o.t);
        EXPECT_LE(d, 1e-9) << what << ": ray " << r.u0 << "," << r.v0 << " dir " << r.du
                           << "," << r.dv << " exact " << e.t << " oracle " << o.t;
        stats.worst = std::max(stats.worst, d);
    }
}

}  // namespace

TEST(Exact, FlatFieldIsHitAtItsDepthByEveryRay) {
    for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp}) {
        const ExactSurface s(Field(8, 8, [](int, int) { return 0.3f; }), wrap);
        for (const RayCase& r : RandomRays(200, 5.0, 7, 8, 8)) {
            const ExactHit e = s.FirstHit(r.u0, r.v0, r.du, r.dv);
            EXPECT_NEAR(e.t, double(0.3f), 1e-15);
            EXPECT_NEAR(e.v, r.v0 + double(0.3f) * r.dv, 1e-15 + 1e-15 * std::abs(e.v));
        }
    }
}

TEST(Exact, TopAndBottomOfTheRange) {
    const ExactSurface top(Field(4, 4, [](int, int) { return 0.0f; }), WrapMode::Repeat);
    EXPECT_EQ(top.FirstHit(0.3, 0.7, 0.5, -0.2).t, 0.0);
    const ExactSurface bottom(Field(4, 4, [](int, int) { return 1.0f; }),
                              WrapMode::Repeat);
    EXPECT_EQ(bottom.FirstHit(0.3, 0.7, 0.5, -0.2).t, 1.0);
}

TEST(Exact, VerticalRayMeetsTheBilinearDepthBelowItsEntry) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> d(0.0f, 1.0f);
    DepthField f = Field(9, 5, [&](int, int) { return d(rng); });
    for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp}) {
        const ExactSurface s(f, wrap);
        for (double u : {-0.7, 0.0, 0.05, 0.5, 0.93, 1.4})
            for (double v : {-0.2, 0.1, 0.61, 0.99}) {
                const ExactHit e = s.FirstHit(u, v, 0.0, 0.0);
                EXPECT_NEAR(e.t, s.DepthAt(u, v), 1e-15);
                EXPECT_EQ(e.u, u);
            }
    }
}

// Depth a + b u over texel centres: the bilinear surface is that plane between the first
// and last centre (clamp), so t = a + b (u0 + t du) gives t = (a + b u0) / (1 - b du).
TEST(Exact, SlantedPlaneMatchesTheClosedForm) {
    const int w = 64;
    const double a = 0.2, b = 0.5;
    const DepthField f =
        Field(w, 3, [&](int i, int) { return float(a + b * (i + 0.5) / w); });
    // The texels hold floats: the plane through them is a + b u up to float rounding.
    const ExactSurface s(f, WrapMode::Clamp);
    for (double u0 : {0.2, 0.4, 0.6})
        for (double du : {-0.3, -0.05, 0.0, 0.1, 0.25}) {
            const double expect = (a + b * u0) / (1 - b * du);
            const ExactHit e = s.FirstHit(u0, 0.5, du, 0.13);
            EXPECT_NEAR(e.t, expect, 1e-7) << u0 << " " << du;
        }
}

// A wall: depth 0.9 for texels i < 8, 0.1 from i = 8 on (16 wide, clamp). Between the
// centres 7.5/16 and 8.5/16 the bilinear surface is the ramp
// depth(u) = 0.9 - 0.8 (16 u - 7.5), so a ray from the deep side that meets the ramp does
// so at t = depth(u0 + t du), and a steeper ray passes over the ramp and lands on the
// plateau at depth 0.1.
TEST(Exact, StepWallIsHitOnItsBilinearRampOrBeyondIt) {
    const DepthField f = Field(16, 4, [](int i, int) { return i < 8 ? 0.9f : 0.1f; });
    const ExactSurface s(f, WrapMode::Clamp);
    const double u0 = 0.2, du = 0.5;
    const double expect = (0.9 - 0.8 * (16 * u0 - 7.5)) / (1 + 0.8 * 16 * du);
    const ExactHit e = s.FirstHit(u0, 0.5, du, 0.0);
    ASSERT_GT(e.u, 7.5 / 16);
    ASSERT_LT(e.u, 8.5 / 16);
    EXPECT_NEAR(e.t, expect, 1e-7);
    // du = 5: the ray is at depth 0.066 when it leaves the ramp at u = 8.5/16, above the
    // plateau, which it meets at t = 0.1.
    const ExactHit g = s.FirstHit(u0, 0.5, 5.0, 0.0);
    EXPECT_EQ(g.t, double(0.1f));
}

TEST(Exact, PyramidLevelsFollowTheSize) {
    auto flat = [](int, int) { return 0.5f; };
    EXPECT_EQ(ExactSurface(Field(64, 64, flat), WrapMode::Repeat).PyramidLevels(), 6);
    EXPECT_EQ(ExactSurface(Field(64, 16, flat), WrapMode::Repeat).PyramidLevels(), 4);
    EXPECT_EQ(ExactSurface(Field(37, 23, flat), WrapMode::Repeat).PyramidLevels(), 0);
    // Clamp: the 65 distinct cells per side in blocks up to 128 (then 256 at most).
    EXPECT_EQ(ExactSurface(Field(64, 64, flat), WrapMode::Clamp).PyramidLevels(), 7);
    EXPECT_EQ(ExactSurface(Field(37, 23, flat), WrapMode::Clamp).PyramidLevels(), 6);
    EXPECT_EQ(ExactSurface(Field(1024, 8, flat), WrapMode::Clamp).PyramidLevels(), 8);
}

TEST(Exact, RefusesAFieldOutsideTheDepthRange) {
    EXPECT_THROW(
        ExactSurface(Field(4, 4, [](int, int) { return NAN; }), WrapMode::Repeat), Error);
    EXPECT_THROW(
        ExactSurface(Field(4, 4, [](int, int) { return 1.5f; }), WrapMode::Clamp), Error);
}

// Every built-in map (64^2: the pyramid has 6 levels) in both wraps, and random maps of
// odd size (no pyramid) and of power-of-two size, on random rays from vertical to very
// grazing (up to 6 tiles of travel). The worst disagreement is printed.
TEST(Exact, AgreesWithADenseOracleOnEveryBuiltinAndRandomMaps) {
    OracleStats stats;
    uint32_t seed = 11;
    for (const std::string& name : BuiltinMapNames()) {
        const DepthField f = MakeBuiltinMap(name, 64, 64);
        for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp}) {
            const ExactSurface s(f, wrap);
            CheckAgainstOracle(s, RandomRays(40, 6.0, seed++, 64, 64), stats,
                               name.c_str());
        }
    }
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> d(0.0f, 1.0f);
    for (auto [w, h] :
         {std::pair{17, 13}, std::pair{32, 32}, std::pair{1, 1}, std::pair{2, 7}}) {
        const DepthField f = Field(w, h, [&](int, int) { return d(rng); });
        for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp}) {
            const ExactSurface s(f, wrap);
            CheckAgainstOracle(s, RandomRays(60, 6.0, seed++, w, h), stats, "random");
        }
    }
    std::printf(
        "exact vs dense oracle: %d rays, worst |t difference| %.3g, %d thin "
        "features only the exact hit saw\n",
        stats.rays, stats.worst, stats.thinTouches);
    EXPECT_GT(stats.rays, 1000);
}
