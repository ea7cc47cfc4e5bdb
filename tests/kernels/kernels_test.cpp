// Kernels on analytic maps: closed-form hits, exact fetch counts, refinement convergence.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>

#include "kernels/registry.h"
#include "render/batch.h"
#include "render/view_ray.h"
#include "tests/kernels/every_width.h"
#include "texture/procedural.h"
#include "texture/sampler.h"

using namespace reliefsim;

namespace {

DepthField Constant(float depth, int n = 64) {
    DepthField f;
    f.width = f.height = n;
    f.depth.assign(size_t(n) * size_t(n), depth);
    f.name = "constant";
    return f;
}

// A linear-search kernel configured as the command line would configure it.
struct TestKernel {
    Refinement refinement;
    int linearSteps, refineSteps;
    bool earlyExit = true;
    uint32_t budget = 0;
    float secantTolerance = 0.01f;
};

TestKernel Configure(Refinement r, int linear, int refine, bool earlyExit = true,
                     uint32_t budget = 0) {
    return {r, linear, refine, earlyExit, budget};
}

const char* MethodName(Refinement r) {
    switch (r) {
        case Refinement::None:
            return "linear";
        case Refinement::Binary:
            return "relief";
        case Refinement::Interval:
            return "interval";
        case Refinement::Secant:
            return "secant";
        case Refinement::Pom:
            return "pom";
    }
    return "";
}

struct MarchRun {
    MarchResult result;
    FetchCounts counts;
};

// Runs the ray through the driver's single-lane reference, and through every other lane
// width this CPU runs (as lane 0 of a pack), which must agree bit for bit.
MarchRun March(const TestKernel& k, const DepthField& f, MarchInput in,
               SamplerState st = {}) {
    const KernelInfo& info = FindMethod(MethodName(k.refinement));
    ParamValues values = ResolveParams(info, {});
    values["linear_steps"] = k.linearSteps;
    if (values.count("refine_steps")) values["refine_steps"] = k.refineSteps;
    if (values.count("secant_tolerance")) values["secant_tolerance"] = k.secantTolerance;
    values["early_exit"] = k.earlyExit ? 1 : 0;
    values["budget"] = k.budget;
    std::shared_ptr<const void> params;
    const BatchJob job = MakeBatchJob(reliefsim::MakeKernel(info, values),
                                      reliefsim::BindTextures(f, st), params);
    const RayRun one = test::MarchEveryWidth(job, in);
    return {one.result, one.counts};
}

// Ray over the ramp field depth(u) = u (bilinear, clamp; exact for u in [0.5/W, 1 -
// 0.5/W]): u(t) = u0 + dx t meets it at t* = u0 / (1 - dx).
constexpr SamplerState kClampBilinear{Filter::Bilinear, WrapMode::Clamp};

}  // namespace

TEST(LinearSearch, FlatPlaneHitsAtItsDepth) {
    DepthField f = Constant(0.5f);
    MarchInput in{{0.3f, 0.4f}, {0.2f, -0.1f}};
    MarchRun r = March(Configure(Refinement::None, 32, 0), f, in);
    EXPECT_TRUE(r.result.hit);
    EXPECT_EQ(r.result.depthHit, 0.5f);  // 16/32 is on the sample grid
    EXPECT_EQ(r.result.nCoarse, 17);     // t = 0, 1/32, ..., 16/32
    EXPECT_EQ(r.counts.nFetches, 17u);
    EXPECT_EQ(r.counts.nTexelReads, 68u);
    EXPECT_FLOAT_EQ(r.result.uvHit.x, 0.3f + 0.2f * 0.5f);
    EXPECT_FLOAT_EQ(r.result.uvHit.y, 0.4f - 0.1f * 0.5f);
}

TEST(LinearSearch, MapNeverHitCostsExactlyNFetches) {
    DepthField f = Constant(1.0f);  // the bottom: samples stop at t = (N-1)/N
    for (int n : {1, 5, 32, 100}) {
        MarchRun r =
            March(Configure(Refinement::None, n, 0), f, {{0.1f, 0.1f}, {0.3f, 0.2f}});
        EXPECT_FALSE(r.result.hit);
        EXPECT_EQ(r.counts.nFetches, uint32_t(n));
        EXPECT_EQ(r.result.nCoarse, n);
        EXPECT_EQ(r.counts.nTexelReads, uint32_t(4 * n));
        EXPECT_NEAR(r.result.depthHit, 1.0f, 1e-5f);
    }
}

TEST(LinearSearch, FixedLoopsFetchEveryStepButLatchTheHit) {
    DepthField f = Constant(0.25f);
    MarchInput in{{0.5f, 0.5f}, {0.1f, 0.1f}};
    MarchRun brk = March(Configure(Refinement::None, 16, 0, true), f, in);
    MarchRun fixed = March(Configure(Refinement::None, 16, 0, false), f, in);
    EXPECT_EQ(brk.counts.nFetches, 5u);  // t = 0 .. 4/16
    EXPECT_EQ(fixed.counts.nFetches, 16u);
    EXPECT_EQ(fixed.result.nCoarse, 16);
    EXPECT_EQ(brk.result.depthHit, fixed.result.depthHit);
    EXPECT_EQ(brk.result.uvHit, fixed.result.uvHit);
}

TEST(LinearSearch, BudgetStopsAndFlags) {
    DepthField f = Constant(0.9f);
    MarchRun r = March(Configure(Refinement::Binary, 32, 6, true, 10), f,
                       {{0.2f, 0.2f}, {0.1f, 0.0f}});
    EXPECT_TRUE(r.result.budgetExhausted);
    EXPECT_EQ(r.counts.nFetches, 10u);
    EXPECT_EQ(r.result.nCoarse, 10);
    EXPECT_FALSE(r.result.hit);
    // A budget that is never reached flags nothing.
    MarchRun ok = March(Configure(Refinement::Binary, 32, 6, true, 1000), f,
                        {{0.2f, 0.2f}, {0.1f, 0.0f}});
    EXPECT_FALSE(ok.result.budgetExhausted);
    EXPECT_EQ(ok.counts.nFetches, 30u + 6u);  // hit at t = 29/32 (30 samples) + 6 binary
}

TEST(LinearSearch, HitAtTopIsExactWithoutRefinement) {
    DepthField f = Constant(0.0f);
    MarchRun r =
        March(Configure(Refinement::Binary, 32, 6), f, {{0.2f, 0.2f}, {0.4f, 0.1f}});
    EXPECT_TRUE(r.result.hit);
    EXPECT_EQ(r.result.depthHit, 0.0f);
    EXPECT_EQ(r.counts.nFetches, 1u);
    EXPECT_EQ(r.result.nRefine, 0);
}

TEST(Relief, FlatPlaneErrorBoundedByBisection) {
    DepthField f = Constant(0.53f);
    for (int refine : {0, 1, 2, 4, 8}) {
        MarchRun r = March(Configure(Refinement::Binary, 16, refine), f,
                           {{0.3f, 0.3f}, {0.2f, 0.2f}});
        float bound = (1.0f / 16.0f) / float(1 << (refine + 1));
        EXPECT_LE(std::fabs(r.result.depthHit - 0.53f), bound) << refine;
        EXPECT_EQ(r.result.nRefine, refine);
        EXPECT_EQ(r.counts.nFetches, uint32_t(10 + refine));  // hit at t = 9/16
    }
}

TEST(Relief, SlantedPlaneMatchesClosedForm) {
    DepthField f = MakeBuiltinMap("ramp", 256, 4);
    MarchInput in{{0.6f, 0.5f}, {-0.3f, 0.0f}};
    const float tStar = 0.6f / 1.3f;
    MarchRun r = March(Configure(Refinement::Binary, 32, 10), f, in, kClampBilinear);
    EXPECT_NEAR(r.result.depthHit, tStar, (1.0f / 32.0f) / 2048.0f + 1e-6f);
    EXPECT_NEAR(r.result.uvHit.x, 0.6f - 0.3f * tStar, 1e-4f);
}

TEST(Relief, ErrorHalvesPerBinaryStep) {
    DepthField f = MakeBuiltinMap("ramp", 1024, 4);
    double previous = 0.0;
    for (int refine = 0; refine <= 8; ++refine) {
        double sum = 0.0;
        int n = 0;
        for (int k = 0; k < 500; ++k) {
            float u0 = 0.3f + 0.6f * float(k) / 500.0f;
            float dx = -0.25f - 0.1f * float(k % 7) / 7.0f;
            double tStar = double(u0) / (1.0 - double(dx));
            MarchRun r = March(Configure(Refinement::Binary, 16, refine), f,
                               {{u0, 0.5f}, {dx, 0.0f}}, kClampBilinear);
            sum += std::fabs(double(r.result.depthHit) - tStar);
            ++n;
        }
        double mean = sum / n;
        if (refine > 0) {
            double factor = previous / mean;
            EXPECT_GE(factor, 1.6) << "refine " << refine;
            EXPECT_LE(factor, 2.5) << "refine " << refine;
        }
        previous = mean;
    }
}

TEST(Interval, SlantedPlaneIsExactAfterOneStep) {
    DepthField f = MakeBuiltinMap("ramp", 256, 4);
    MarchInput in{{0.6f, 0.5f}, {-0.3f, 0.0f}};
    MarchRun r = March(Configure(Refinement::Interval, 16, 1), f, in, kClampBilinear);
    EXPECT_NEAR(r.result.depthHit, 0.6f / 1.3f, 2e-6f);
    EXPECT_EQ(r.result.nRefine, 1);
}

TEST(Pom, OneSecantStepWithoutFetch) {
    DepthField f = MakeBuiltinMap("ramp", 256, 4);
    MarchInput in{{0.6f, 0.5f}, {-0.3f, 0.0f}};
    MarchRun lin = March(Configure(Refinement::None, 16, 0), f, in, kClampBilinear);
    MarchRun pom = March(Configure(Refinement::Pom, 16, 0), f, in, kClampBilinear);
    EXPECT_EQ(pom.counts.nFetches, lin.counts.nFetches);
    EXPECT_EQ(pom.result.nRefine, 1);
    EXPECT_NEAR(pom.result.depthHit, 0.6f / 1.3f, 2e-6f);
}

TEST(Secant, ConvergesWithinToleranceAndStops) {
    DepthField f = MakeBuiltinMap("bumps", 256, 256);
    TestKernel k = Configure(Refinement::Secant, 32, 10);
    k.secantTolerance = 1e-4f;
    TestKernel dense = Configure(Refinement::Binary, 1024, 20);
    int converged = 0;
    for (int i = 0; i < 200; ++i) {
        MarchInput in{{float(i) / 200.0f, 0.37f}, {0.35f, 0.12f}};
        MarchRun r = March(k, f, in);
        MarchRun ref = March(dense, f, in);
        ASSERT_TRUE(r.result.hit);
        EXPECT_LE(r.result.nRefine, 10);
        if (r.result.nRefine < 10) ++converged;
        // the returned point sits on the surface within the tolerance...
        Sampler<false> s(f, {});
        EXPECT_LE(std::fabs(s.Sample(r.result.uvHit) - r.result.depthHit), 2e-3f);
        // ...and, starting from the same linear bracket, on the same crossing as a dense
        // march
        EXPECT_NEAR(r.result.depthHit, ref.result.depthHit, 1.0f / 32.0f);
    }
    EXPECT_GT(converged, 150);  // early termination is the point of the method
}

TEST(Secant, FlatPlaneConvergesInOneIteration) {
    DepthField f = Constant(0.4f);
    MarchRun r =
        March(Configure(Refinement::Secant, 10, 10), f, {{0.5f, 0.5f}, {0.3f, 0.0f}});
    EXPECT_EQ(r.result.nRefine, 1);
    EXPECT_NEAR(r.result.depthHit, 0.4f, 1e-6f);
}

TEST(LinearSearch, StepEdgeHitsTheWall) {
    // depth 0.2 for u < 0.5, 0.8 beyond; ray from u = 0.6 towards -u: the wall at u = 0.5
    // is reached at t = 0.2, where the depth there (0.2) is already below the ray: hit =
    // 0.2.
    DepthField f = MakeBuiltinMap("step", 256, 4);
    MarchInput in{{0.6f, 0.5f}, {-0.5f, 0.0f}};
    SamplerState nearest{Filter::Nearest, WrapMode::Clamp};
    MarchRun relief = March(Configure(Refinement::Binary, 32, 12), f, in, nearest);
    EXPECT_NEAR(relief.result.depthHit, 0.2f, (1.0f / 32.0f) / 4096.0f + 1e-6f);
    EXPECT_NEAR(relief.result.uvHit.x, 0.5f, 1e-3f);
}

TEST(LinearSearch, GrazingRaysTerminateFinite) {
    DepthField f = MakeBuiltinMap("noise", 64, 64);
    for (float big : {1e3f, 1e6f, 1e9f}) {
        for (Refinement r : {Refinement::None, Refinement::Binary, Refinement::Interval,
                             Refinement::Secant, Refinement::Pom}) {
            MarchRun run = March(Configure(r, 32, 8), f, {{0.5f, 0.5f}, {big, -big}});
            EXPECT_TRUE(std::isfinite(run.result.depthHit));
            EXPECT_TRUE(std::isfinite(run.result.uvHit.x));
            EXPECT_LE(run.counts.nFetches, 32u + 9u);
        }
    }
}

TEST(ViewRay, StraightDownRayHasNoSlope) {
    // View angle 0: the eye straight above the plane's centre, looking down (-z). The
    // centre pixel of an odd-sized image has ndc (0, 0) exactly, so its ray is the
    // forward vector: dirUv must vanish (tolerance 1e-7, far below one texel of any map)
    // and the ray enters at the plane's centre.
    for (int n : {1, 3, 257}) {
        ViewUniforms u;
        u.eye = {0.0f, 0.0f, 2.0f};
        u.forward = {0.0f, 0.0f, -1.0f};
        u.right = {0.4f, 0.0f, 0.0f};
        u.up = {0.0f, 0.4f, 0.0f};
        u.width = u.height = float(n);
        u.tiling = 1.0f;
        u.depthScale = 0.1f;
        MarchInput in = PixelToRay(u, n / 2, n / 2);
        EXPECT_NEAR(in.dirUv.x, 0.0f, 1e-7f) << n << "x" << n;
        EXPECT_NEAR(in.dirUv.y, 0.0f, 1e-7f) << n << "x" << n;
        EXPECT_NEAR(in.uvEntry.x, 0.5f, 1e-7f);
        EXPECT_NEAR(in.uvEntry.y, 0.5f, 1e-7f);
    }
}

TEST(ViewRay, CornerPixelSlopeIsMinusXyOverZTimesDepthScale) {
    ViewUniforms u;
    u.eye = {0.0f, 0.0f, 2.0f};
    u.forward = {0.0f, 0.0f, -1.0f};
    u.right = {0.5f, 0.0f, 0.0f};
    u.up = {0.0f, 0.5f, 0.0f};
    u.width = u.height = 2.0f;
    u.tiling = 1.0f;
    u.depthScale = 0.1f;
    MarchInput in = PixelToRay(u, 1, 0);         // right column, top row: ndc (0.5, 0.5)
    EXPECT_FLOAT_EQ(in.uvEntry.x, 0.5f + 0.5f);  // x = 2 * 0.25 = 0.5 -> u = 1.0
    EXPECT_FLOAT_EQ(in.uvEntry.y, 0.5f - 0.5f);  // y = 0.5 -> v = 0
    EXPECT_FLOAT_EQ(in.dirUv.x, 0.25f * 0.1f);  // -dx/dz * depthScale, dx = 0.25, dz = -1
    EXPECT_FLOAT_EQ(in.dirUv.y, -0.25f * 0.1f);
}
