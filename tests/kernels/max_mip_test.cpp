// The hierarchical tracers (kernels/max_mip.h): maxmip's exact bilinear-patch hit on
// analytic maps (flat, slanted, a step) in closed form, qdm's conservative box top,
// exact fetch accounting of the descent, fixed loops and budgets, the cell pyramid
// against brute force, and against the exact reference on the built-in scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/error.h"
#include "kernels/registry.h"
#include "metrics/reference_metrics.h"
#include "render/batch.h"
#include "render/frame.h"
#include "render/kernel_maps.h"
#include "render/scene.h"
#include "tests/common/fields.h"
#include "tests/kernels/every_width.h"
#include "texture/cell_pyramid.h"
#include "texture/procedural.h"

using namespace reliefsim;

namespace {

DepthField Field(int w, int h, float (*depth)(int i, int j)) {
    return reliefsim::testing::MakeField(w, h, depth, "analytic");
}

RayRun Trace(const char* method, const DepthField& f, const MarchInput& in,
             const std::vector<std::string>& set = {}) {
    const KernelInfo& info = FindMethod(method);
    const Kernel kernel = MakeKernel(info, ResolveParams(info, set));
    KernelMapSettings maps;
    maps.useCache = false;
    std::shared_ptr<const void> params;
    const BatchJob job =
        MakeBatchJob(kernel, BindKernelTextures(f, SamplerState{}, kernel, maps), params);
    return test::MarchEveryWidth(job, in);
}

// Cell-space ray depth where it meets the plane depth = a + b x (x = u W - 0.5).
double PlaneHit(double a, double b, double u0, double du, int w) {
    const double x0 = u0 * w - 0.5, ax = du * w;
    return (a + b * x0) / (1.0 - b * ax);
}

}  // namespace

TEST(CellPyramid, EveryNodeIsTheLeastCornerOfItsCells) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    for (auto [w, h] : {std::pair{16, 16}, {37, 23}, {1, 5}, {64, 3}}) {
        DepthField f;
        f.width = w;
        f.height = h;
        for (int k = 0; k < w * h; ++k) f.depth.push_back(uni(rng));
        const CellPyramid p = BuildCellPyramid(f);
        EXPECT_EQ(p.levelWidth.back(), 1);
        EXPECT_EQ(p.levelHeight.back(), 1);
        for (int k = 0; k < p.levels; ++k)
            for (int j = 0; j < p.levelHeight[size_t(k)]; ++j)
                for (int i = 0; i < p.levelWidth[size_t(k)]; ++i) {
                    // Brute force: every corner of every cell the node covers.
                    float m = std::numeric_limits<float>::infinity();
                    for (int y = j << k; y < std::min((j + 1) << k, h); ++y)
                        for (int x = i << k; x < std::min((i + 1) << k, w); ++x)
                            for (int b = 0; b < 2; ++b)
                                for (int a = 0; a < 2; ++a)
                                    m = std::min(m, f.At((x + a) % w, (y + b) % h));
                    ASSERT_EQ(p.At(k, i, j), m) << w << "x" << h << " level " << k;
                }
    }
}

TEST(MaxMip, FlatPlaneHitsExactlyAfterOneDescent) {
    // A vertical ray descends from the top node to its cell: levels + 0 crossings, so
    // top + 1 fetches; maxmip's last one reads the cell's four corners.
    const DepthField f = Field(64, 64, [](int, int) { return 0.5f; });
    const MarchInput in{{0.3f, 0.4f}, {0.0f, 0.0f}};
    for (const char* method : {"maxmip", "qdm"}) {
        const RayRun r = Trace(method, f, in);
        EXPECT_TRUE(r.result.hit) << method;
        EXPECT_EQ(r.result.depthHit, 0.5f) << method;
        EXPECT_EQ(r.result.nCoarse, 7) << method;  // levels 6, 5, ..., 0
        EXPECT_EQ(r.counts.nFetches, 7u) << method;
        EXPECT_EQ(r.counts.nTexelReads, std::string(method) == "maxmip" ? 10u : 7u)
            << method;
        EXPECT_EQ(r.result.nRefine, 0);
    }
    // A slanted ray over the flat plane: exact depth, the ray point at it.
    const MarchInput slant{{0.3f, 0.4f}, {0.21f, -0.13f}};
    const RayRun r = Trace("maxmip", f, slant);
    EXPECT_TRUE(r.result.hit);
    EXPECT_EQ(r.result.depthHit, 0.5f);
    EXPECT_FLOAT_EQ(r.result.uvHit.x, 0.3f + 0.21f * 0.5f);
    EXPECT_FLOAT_EQ(r.result.uvHit.y, 0.4f - 0.13f * 0.5f);
}

TEST(MaxMip, SlantedPlaneHitIsTheClosedForm) {
    // depth = 0.1 + 0.01 i: the bilinear surface of every cell off the wrap seam is the
    // plane depth = 0.1 + 0.01 x.
    const DepthField f =
        Field(64, 64, [](int i, int) { return 0.1f + 0.01f * float(i); });
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u0(0.1f, 0.4f), d(-0.3f, 0.3f);
    for (int k = 0; k < 200; ++k) {
        const MarchInput in{{u0(rng), u0(rng)}, {d(rng), d(rng)}};
        const double exact = PlaneHit(0.1, 0.01, in.uvEntry.x, in.dirUv.x, 64);
        const RayRun m = Trace("maxmip", f, in);
        ASSERT_TRUE(m.result.hit);
        EXPECT_NEAR(m.result.depthHit, exact, 2e-6) << k;
        // qdm stops on the box top of the cell it reaches: never below the plane, at
        // most one cell's relief (0.01 of depth, stretched by the ray's slope) above.
        const RayRun q = Trace("qdm", f, in);
        ASSERT_TRUE(q.result.hit);
        EXPECT_LE(q.result.depthHit, exact + 1e-6) << k;
        EXPECT_GE(q.result.depthHit, exact - 0.02) << k;
    }
}

TEST(MaxMip, StepWallIsHitOnTheBilinearRamp) {
    // Deep (0.8) left half, shallow (0.2) right half: between texel centres 31 and 32
    // the bilinear surface ramps, depth = 0.8 - 0.6 (x - 31) for x in [31, 32].
    const DepthField f = Field(64, 64, [](int i, int) { return i < 32 ? 0.8f : 0.2f; });
    for (float du : {0.05f, 0.1f, 0.2f}) {
        // Enter at u = 0.4 (x = 25.1) heading +u: the ray is at depth t at x = 25.1 +
        // 64 du t and meets the ramp where 0.8 - 0.6 (x - 31) = t.
        const MarchInput in{{0.4f, 0.5f}, {du, 0.0f}};
        const double x0 = 0.4 * 64 - 0.5, ax = double(du) * 64;
        const double ramp = (0.8 + 0.6 * 31 - 0.6 * x0) / (1.0 + 0.6 * ax);
        const double deep = 0.8;  // the deep half, reached before the wall when slow
        const double xAtFloor = x0 + ax * deep;
        const double exact = xAtFloor <= 31.0 ? deep : ramp;
        const RayRun r = Trace("maxmip", f, in);
        ASSERT_TRUE(r.result.hit) << du;
        EXPECT_NEAR(r.result.depthHit, exact, 2e-6) << du;
        const RayRun q = Trace("qdm", f, in);
        EXPECT_LE(q.result.depthHit, exact + 1e-6) << du;
    }
}

TEST(MaxMip, FixedLoopsLatchTheHitAndBudgetsStopConservatively) {
    const DepthField f = MakeBuiltinMap("noise", 64, 64);
    const MarchInput in{{0.2f, 0.7f}, {0.31f, 0.17f}};
    for (const char* method : {"maxmip", "qdm"}) {
        const RayRun early = Trace(method, f, in);
        ASSERT_TRUE(early.result.hit);
        const RayRun fixed = Trace(method, f, in, {"early_exit=0", "max_steps=300"});
        EXPECT_EQ(fixed.counts.nFetches, 300u) << method;
        EXPECT_EQ(fixed.result.nCoarse, 300) << method;
        EXPECT_EQ(fixed.result.depthHit, early.result.depthHit) << method;
        EXPECT_EQ(fixed.result.uvHit, early.result.uvHit) << method;
        ASSERT_GT(early.counts.nFetches, 4u);
        const uint32_t budget = early.counts.nFetches / 2;
        const RayRun cut = Trace(method, f, in, {"budget=" + std::to_string(budget)});
        EXPECT_EQ(cut.counts.nFetches, budget) << method;
        EXPECT_TRUE(cut.result.budgetExhausted || !cut.result.hit) << method;
        EXPECT_LE(cut.result.depthHit, early.result.depthHit) << method;
        const RayRun few = Trace(method, f, in, {"max_steps=3"});
        EXPECT_EQ(few.counts.nFetches, 3u) << method;
        EXPECT_FALSE(few.result.hit) << method;
    }
}

TEST(MaxMip, ClampWrapIsOneError) {
    const DepthField f = MakeBuiltinMap("noise", 32, 32);
    for (const char* method : {"maxmip", "qdm"}) {
        RenderSettings s;
        s.method = method;
        s.width = s.height = 16;
        s.sampler.wrap = WrapMode::Clamp;
        try {
            ValidateSettings(s);
            ADD_FAILURE() << method << ": clamp accepted";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(method), std::string::npos) << what;
            EXPECT_NE(what.find("repeat"), std::string::npos) << what;
        }
    }
}

TEST(MaxMip, ExactOnTheBuiltinsAndQdmNeverPastTheFirstHit) {
    // Against the exact reference (metrics/exact.h, the first hit of the bilinear
    // surface): maxmip's hit is that point up to float rounding on nearly every pixel;
    // neither kernel answers a point past it (the zero-violation test of the
    // conservative kernels; the same 2^-22 uv rounding allowance as
    // ConeFilter.BilinearBoundsNeverStepPastTheFirstHit), with either texture format
    // and on a map whose size is neither square nor a power of two.
    struct Scene {
        const char* map;
        int w, h;
        Precision precision;
    };
    const Scene scenes[] = {
        {"shapes", 128, 128, Precision::Float},     {"bumps", 128, 128, Precision::Float},
        {"steps", 128, 128, Precision::Float},      {"noise", 128, 128, Precision::Float},
        {"shapes", 128, 128, Precision::Llvmpipe8}, {"noise", 75, 41, Precision::Float}};
    int rounding = 0;
    for (const Scene& sc : scenes) {
        DepthField f = MakeBuiltinMap(sc.map, sc.w, sc.h);
        if (sc.precision == Precision::Llvmpipe8) f = QuantizeToUnorm8(f);
        for (const char* method : {"maxmip", "qdm"}) {
            RenderSettings s;
            s.method = method;
            s.width = s.height = 96;
            s.sampler.precision = sc.precision;
            const RenderOutput out = Render(f, s);
            ASSERT_TRUE(out.hasReference);
            int past = 0, covered = 0, close = 0;
            for (size_t i = 0; i < out.record.hitDepth.size(); ++i) {
                if (!out.record.Covered(i)) continue;
                ++covered;
                if (std::abs(double(out.record.hitDepth[i]) -
                             double(out.reference.depth[i])) <= 1e-4)
                    ++close;
                if (!PastFirstHit(out.record.hitDepth[i], out.reference.depth[i]))
                    continue;
                const double du = double(out.record.hitU[i]) - double(out.reference.u[i]),
                             dv = double(out.record.hitV[i]) - double(out.reference.v[i]);
                if (std::sqrt(du * du + dv * dv) <= 0x1p-22)
                    ++rounding;
                else {
                    ++past;
                    ADD_FAILURE()
                        << method << " on " << sc.map << ": past the first hit at pixel "
                        << i % 96 << "," << i / 96 << " hit " << out.record.hitDepth[i]
                        << " ref " << out.reference.depth[i] << " uv "
                        << out.record.hitU[i] << "," << out.record.hitV[i] << " ref uv "
                        << out.reference.u[i] << "," << out.reference.v[i];
                }
            }
            EXPECT_GT(covered, 5000);
            EXPECT_EQ(past, 0) << method << " on " << sc.map;
            if (std::string(method) == "maxmip") {
                EXPECT_GE(close, covered - covered / 200) << sc.map;  // >= 99.5%
            }
        }
    }
    EXPECT_LT(rounding, 200);
}

TEST(Qdm, RefinementInTheFinestBoxCostsTwoBracketFetchesPlusItsSteps) {
    // On the slanted plane the finest box's top A lies above the plane and the cell's
    // exit B below it (the ray descends faster than the plane), so the bracket holds:
    // two height fetches (A, B), then refine_steps iterations; interval's chord of a
    // plane is the plane's hit, binary halves the bracket per step.
    const DepthField f =
        Field(64, 64, [](int i, int) { return 0.1f + 0.01f * float(i); });
    const MarchInput in{{0.25f, 0.3f}, {0.05f, 0.02f}};
    const double exact = PlaneHit(0.1, 0.01, in.uvEntry.x, in.dirUv.x, 64);
    const RayRun none = Trace("qdm", f, in);
    ASSERT_TRUE(none.result.hit);
    ASSERT_LT(none.result.depthHit, exact - 1e-4);  // the box top, above the plane
    for (int steps : {1, 3, 6}) {
        const RayRun b = Trace(
            "qdm", f, in, {"refine=binary", "refine_steps=" + std::to_string(steps)});
        EXPECT_EQ(b.result.nCoarse, none.result.nCoarse);
        EXPECT_EQ(b.result.nRefine, steps);
        EXPECT_EQ(b.counts.nFetches, none.counts.nFetches + 2u + uint32_t(steps));
        // Binary after k steps lies within the bracket / 2^k of the hit.
        // B - A is at most the ray's depth across one cell: 1 / (du W).
        const double bracket = 1.0 / (0.05 * 64);
        EXPECT_NEAR(b.result.depthHit, exact, bracket / double(1 << steps)) << steps;
    }
    const RayRun i = Trace("qdm", f, in, {"refine=interval", "refine_steps=1"});
    EXPECT_EQ(i.result.nRefine, 1);
    EXPECT_NEAR(i.result.depthHit, exact, 1e-6);
    const RayRun pom = Trace("qdm", f, in, {"refine=pom"});
    EXPECT_EQ(pom.counts.nFetches, none.counts.nFetches + 2u);  // the chord, no fetch
    EXPECT_NEAR(pom.result.depthHit, exact, 1e-6);
    // maxmip takes no refinement: it is exact.
    EXPECT_THROW(ResolveParams(FindMethod("maxmip"), {"refine=binary"}), Error);
}
