// Any coarse search followed by any refinement (kernels/refine.h, `--set refine=`):
// closed forms on a plane and a ramp, the fetch accounting of each refinement after a
// cone search, the budget, and the linear presets as refinements of one search. And the
// cone kernels' least step (`min_step`), which makes a conservative search pierce.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "kernels/registry.h"
#include "render/batch.h"
#include "render/frame.h"
#include "render/kernel_maps.h"
#include "render/scene.h"
#include "tests/kernels/every_width.h"
#include "texture/procedural.h"

using namespace reliefsim;

namespace {

// The analytic built-ins (texture/procedural.h): flat is depth 0.5 everywhere; ramp is
// depth = u at texel centres, which bilinear with clamp reproduces exactly for u in
// [0.5/W, 1 - 0.5/W], so a ray u(t) = u0 + dx t meets it at t* = u0 / (1 - dx).
DepthField Flat() { return MakeBuiltinMap("flat", 32, 32); }
DepthField Ramp() { return MakeBuiltinMap("ramp", 64, 64); }

constexpr SamplerState kClampBilinear{Filter::Bilinear, WrapMode::Clamp};

KernelMapSettings NoCache() {
    KernelMapSettings m;
    m.useCache = false;  // each kernel's default encoding
    return m;
}

RayRun Shoot(const char* method, const DepthField& f, const MarchInput& in,
             const std::vector<std::string>& set, const SamplerState& sampler = {}) {
    const KernelInfo& info = FindMethod(method);
    const Kernel kernel = MakeKernel(info, ResolveParams(info, set));
    std::shared_ptr<const void> params;
    const BatchJob job =
        MakeBatchJob(kernel, BindKernelTextures(f, sampler, kernel, NoCache()), params);
    return test::MarchEveryWidth(job, in);
}

const char* const kConeMethods[] = {"csm",  "rcs", "qcsm", "acm4",
                                    "acm8", "cns", "rcns", "mcns"};

}  // namespace

TEST(Refine, IsAParameterOfEveryCoarseSearch) {
    for (const char* m : {"linear", "relief", "secant", "interval", "pom", "csm", "rcs",
                          "qcsm", "acm4", "acm8", "cns", "rcns", "mcns"}) {
        SCOPED_TRACE(m);
        const KernelInfo& info = FindMethod(m);
        EXPECT_EQ(ResolveParams(info, {"refine=secant"}).at("refine"), 3);
        EXPECT_EQ(ResolveParams(info, {"refine=pom"}).at("refine"), 4);
        EXPECT_EQ(ResolveParams(info, {"refine=0"}).at("refine"), 0);
        try {
            ResolveParams(info, {"refine=bisection"});
            ADD_FAILURE() << "accepted refine=bisection";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("none, binary, interval, secant, pom"),
                      std::string::npos)
                << e.what();
        }
    }
    // The defaults: each preset's own refinement; the cone kernels none, rcs binary.
    EXPECT_EQ(ResolveParams(FindMethod("linear"), {}).at("refine"), 0);
    EXPECT_EQ(ResolveParams(FindMethod("relief"), {}).at("refine"), 1);
    EXPECT_EQ(ResolveParams(FindMethod("interval"), {}).at("refine"), 2);
    EXPECT_EQ(ResolveParams(FindMethod("secant"), {}).at("refine"), 3);
    EXPECT_EQ(ResolveParams(FindMethod("pom"), {}).at("refine"), 4);
    EXPECT_EQ(ResolveParams(FindMethod("csm"), {}).at("refine"), 0);
    EXPECT_EQ(ResolveParams(FindMethod("rcs"), {}).at("refine"), 1);
    EXPECT_EQ(ResolveParams(FindMethod("rcns"), {}).at("refine"), 1);
    EXPECT_EQ(ResolveParams(FindMethod("csm"), {}).at("refine_steps"), 5);
    EXPECT_EQ(ResolveParams(FindMethod("rcs"), {}).at("refine_steps"), 6);
}

TEST(Refine, LinearPresetsAreOneSearchWithTheirRefinement) {
    // linear + refine=R answers exactly what the preset of R answers, fetch for fetch.
    const DepthField f = MakeBuiltinMap("noise", 64, 64);
    const std::pair<const char*, const char*> presets[] = {{"relief", "binary"},
                                                           {"interval", "interval"},
                                                           {"secant", "secant"},
                                                           {"pom", "pom"}};
    for (const auto& [preset, refine] : presets)
        for (int i = 0; i < 24; ++i) {
            SCOPED_TRACE(std::string(preset) + " ray " + std::to_string(i));
            const MarchInput in{{0.03f * float(i), 0.7f - 0.02f * float(i)},
                                {0.4f - 0.03f * float(i), 0.1f + 0.02f * float(i)}};
            const std::vector<std::string> set = {"linear_steps=10", "refine_steps=5"};
            std::vector<std::string> asLinear = set;
            asLinear.push_back(std::string("refine=") + refine);
            const RayRun a = Shoot(preset, f, in, set);
            const RayRun b = Shoot("linear", f, in, asLinear);
            EXPECT_EQ(a.result.depthHit, b.result.depthHit);
            EXPECT_EQ(a.result.nRefine, b.result.nRefine);
            EXPECT_EQ(a.counts.nFetches, b.counts.nFetches);
        }
}

TEST(Refine, ChordIsExactOnARampAfterTheRelaxedSearch) {
    // rcs pierces the ramp; the chord through the samples either side of the crossing
    // lies on the plane, so interval and secant hit t* after one iteration and pom
    // without a fetch. binary (the listing's) is within tK / 2^(b+1).
    const DepthField f = Ramp();
    // The ray climbs the ramp: u(t) = 0.6 - 0.25 t meets depth u at t* = 0.6 / 1.25.
    const MarchInput in{{0.6f, 0.5f}, {-0.25f, 0.0f}, 1.0f};
    const double tStar = 0.6 / 1.25;
    for (const char* method : {"rcs", "rcns"}) {
        SCOPED_TRACE(method);
        const RayRun none = Shoot(method, f, in, {"refine=none"}, kClampBilinear);
        ASSERT_TRUE(none.result.hit);
        EXPECT_EQ(none.counts.nFetches, 15u);
        EXPECT_GE(none.result.depthHit, tStar);  // inside
        for (const char* r : {"interval", "secant"}) {
            SCOPED_TRACE(r);
            const RayRun x =
                Shoot(method, f, in, {std::string("refine=") + r, "refine_steps=1"},
                      kClampBilinear);
            EXPECT_NEAR(x.result.depthHit, tStar, 2e-6);
            EXPECT_EQ(x.result.nRefine, 1);
            EXPECT_EQ(x.counts.nFetches, 16u);
        }
        const RayRun pom = Shoot(method, f, in, {"refine=pom"}, kClampBilinear);
        EXPECT_NEAR(pom.result.depthHit, tStar, 2e-6);
        EXPECT_EQ(pom.result.nRefine, 1);
        EXPECT_EQ(pom.counts.nFetches, 15u);
        const RayRun bin = Shoot(method, f, in, {"refine_steps=10"}, kClampBilinear);
        EXPECT_NEAR(bin.result.depthHit, tStar,
                    double(none.result.depthHit) / 2048.0 + 1e-6);
        EXPECT_EQ(bin.counts.nFetches, 25u);
    }
}

TEST(Refine, BinaryAfterConeStepsClosedFormOnAPlane) {
    // csm over a flat plane at D: t_n = D (1 - q^n), q = a / (a + 1) (tests of Csm).
    // All samples lie above the plane, so Alg. 2 from K = t_n back over the last step
    // s = t_n - t_(n-1) moves forward every time: after b steps t = K - (s / 2) / 2^b.
    const DepthField f = Flat();
    const MarchInput in{{0.3f, 0.4f}, {0.3f, 0.4f}, 1.0f};  // a = 0.5
    const double q = 0.5 / 1.5, d = 0.5;
    for (int n : {2, 4, 8})
        for (int b : {1, 3, 6}) {
            SCOPED_TRACE("cone_steps " + std::to_string(n) + " refine_steps " +
                         std::to_string(b));
            const RayRun r = Shoot("csm", f, in,
                                   {"cone_steps=" + std::to_string(n), "refine=binary",
                                    "refine_steps=" + std::to_string(b)});
            const double k = d * (1 - std::pow(q, n));
            const double s = d * std::pow(q, n - 1) * (1 - q);
            EXPECT_NEAR(r.result.depthHit, k - s / 2 / std::pow(2.0, b), 2e-6);
            EXPECT_EQ(r.counts.nFetches, uint32_t(n + b));
            EXPECT_EQ(r.result.nCoarse, n);
            EXPECT_EQ(r.result.nRefine, b);
            EXPECT_FALSE(r.result.hit);
        }
}

TEST(Refine, ChordRefinementsFetchTheEndOfAConservativeSearchOnce) {
    // A conservative search ends outside, short of the surface: interval, secant and pom
    // fetch that end point K once; it is outside, so K is the answer and no refinement
    // iteration runs. A budget that refuses that fetch answers K too.
    const DepthField f = Flat();
    const MarchInput in{{0.3f, 0.4f}, {0.3f, 0.4f}, 1.0f};
    // (cns and mcns store n_z = 1 over a plane, a 180 degree cone: their first step
    // lands on it.)
    for (const char* method : {"csm", "qcsm", "acm4", "acm8"}) {
        const RayRun none = Shoot(method, f, in, {"cone_steps=6"});
        ASSERT_FALSE(none.result.hit) << method;
        for (const char* r : {"interval", "secant", "pom"}) {
            SCOPED_TRACE(std::string(method) + " " + r);
            const RayRun x =
                Shoot(method, f, in, {"cone_steps=6", std::string("refine=") + r});
            EXPECT_EQ(x.result.depthHit, none.result.depthHit);
            EXPECT_EQ(x.counts.nFetches, 7u);
            EXPECT_EQ(x.result.nRefine, 0);
            const RayRun cut = Shoot(
                method, f, in, {"cone_steps=6", std::string("refine=") + r, "budget=6"});
            EXPECT_EQ(cut.result.depthHit, none.result.depthHit);
            EXPECT_EQ(cut.counts.nFetches, 6u);
            EXPECT_TRUE(cut.result.budgetExhausted);
        }
    }
}

TEST(Refine, ChordRefinesAConeSearchThatEndsInside) {
    // With bilinearly filtered ratios csm sometimes steps inside the relief (004 Fig.
    // 4.6). interval then refines between the last point outside and that point K: the
    // answer never lies past K, and the cost is the cone steps, one fetch of K if the
    // loop ended outside, and the refinement iterations. A ray it does not refine
    // answers what csm answers.
    const DepthField f = MakeBuiltinMap("shapes", 64, 64);
    int refined = 0;
    for (int i = 0; i < 400; ++i) {
        const float a = 0.0157f * float(i);
        const MarchInput in{{0.37f + 0.0011f * float(i), 0.21f + 0.0017f * float(i)},
                            {0.6f * std::cos(a), 0.6f * std::sin(a)},
                            1.0f};
        const RayRun none = Shoot("csm", f, in, {"cone_steps=12"});
        const RayRun x =
            Shoot("csm", f, in, {"cone_steps=12", "refine=interval", "refine_steps=4"});
        if (x.result.nRefine == 0) {
            EXPECT_EQ(x.result.depthHit, none.result.depthHit) << i;
            continue;
        }
        ++refined;
        // Refining never moves the answer past K, the point the search stopped at.
        EXPECT_LE(x.result.depthHit, none.result.depthHit) << i;
        EXPECT_EQ(x.counts.nFetches, none.counts.nFetches + uint32_t(x.result.nRefine) +
                                         (none.result.hit ? 0u : 1u))
            << i;
    }
    EXPECT_GT(refined, 0);  // some rays of csm with bilinear ratios do end inside
}

TEST(Refine, BinaryAndIntervalReduceCsmErrorOnAFrame) {
    // The dissertation's observation (004 §4.3.1, Table 4.6): a refinement after CSM
    // repairs the overshoot of bilinearly filtered ratios. Against the exact reference.
    const DepthField f = MakeBuiltinMap("shapes", 128, 128);
    auto mse = [&](const std::vector<std::string>& set) {
        RenderSettings s;
        s.method = "csm";
        s.width = s.height = 96;
        s.set = set;
        s.maps = NoCache();
        return Render(f, s).referenceSummary.mseExactDepth;
    };
    const double none = mse({});
    const double binary = mse({"refine=binary"});
    const double interval = mse({"refine=interval"});
    EXPECT_LT(binary, 0.8 * none);
    EXPECT_LT(interval, 0.8 * none);
}

namespace {

// Every fetch of one ray (uv and ray depth), through the single-lane driver.
std::vector<TracedFetch> Fetches(const char* method, const DepthField& f,
                                 const MarchInput& in,
                                 const std::vector<std::string>& set) {
    const KernelInfo& info = FindMethod(method);
    const Kernel kernel = MakeKernel(info, ResolveParams(info, set));
    std::shared_ptr<const void> params;
    const BatchJob job =
        MakeBatchJob(kernel, BindKernelTextures(f, {}, kernel, NoCache()), params);
    std::vector<TracedFetch> out;
    MarchRay(job, in, [&](const TracedFetch& x) { out.push_back(x); });
    return out;
}

}  // namespace

TEST(MinStep, CellStepPiercesAPlaneAndIntervalMakesItExact) {
    // Over a flat plane csm only approaches the surface (t_n = D (1 - q^n)). With the
    // cell-border least step (Ban et al. 2024) it crosses a cell per step at least, so
    // it ends inside, less than one cell step past the plane; interval's chord then
    // lands on it.
    const DepthField f = Flat();
    const MarchInput in{{0.3f, 0.4f}, {0.3f, 0.4f}, 1.0f};
    EXPECT_EQ(ResolveParams(FindMethod("csm"), {"min_step=cell"}).at("min_step"), 2);
    EXPECT_EQ(ResolveParams(FindMethod("rcs"), {"min_step=texel"}).at("min_step"), 1);
    for (const char* method : {"csm", "qcsm", "acm4", "acm8"}) {
        SCOPED_TRACE(method);
        EXPECT_FALSE(Shoot(method, f, in, {}).result.hit);
        for (const char* least : {"min_step=cell", "min_step=texel"}) {
            SCOPED_TRACE(least);
            const RayRun r = Shoot(method, f, in, {least, "cone_steps=64"});
            ASSERT_TRUE(r.result.hit);
            EXPECT_GE(r.result.depthHit, 0.5f);
            // One cell along the ray is at most 1 / (32 * 0.4) in depth (+ 1e-5).
            EXPECT_LE(r.result.depthHit, 0.5f + 1.0f / (32.0f * 0.4f) + 1e-4f);
            const RayRun x =
                Shoot(method, f, in,
                      {least, "cone_steps=64", "refine=interval", "refine_steps=1"});
            EXPECT_NEAR(x.result.depthHit, 0.5, 1e-6);
            EXPECT_EQ(x.counts.nFetches, r.counts.nFetches + 1);
        }
    }
}

TEST(MinStep, EveryCellStepCrossesACellBorder) {
    // The invariant of the cell least step: consecutive fetches of the cone loop lie in
    // different bilinear cells (the grid through the texel centres), on a real map and
    // for any direction. Without it csm takes many steps inside one cell.
    const DepthField f = MakeBuiltinMap("shapes", 64, 64);
    auto cell = [&](const TracedFetch& x) {
        return std::pair{int(std::floor(x.u * 64.0f - 0.5f)),
                         int(std::floor(x.v * 64.0f - 0.5f))};
    };
    int sameCellWithout = 0, steps = 0;
    for (int i = 0; i < 200; ++i) {
        const float a = 0.0314f * float(i);
        const MarchInput in{{0.31f + 0.0021f * float(i), 0.17f + 0.0013f * float(i)},
                            {0.5f * std::cos(a), 0.5f * std::sin(a)},
                            1.0f};
        const std::vector<TracedFetch> with =
            Fetches("csm", f, in, {"min_step=cell", "cone_steps=40"});
        for (size_t k = 1; k < with.size(); ++k) {
            if (with[k - 1].t >= with[k - 1].sampled) break;  // the loop ended inside
            if (with[k].t == 1.0f) break;  // the step was cut at the bottom
            ++steps;
            EXPECT_NE(cell(with[k]), cell(with[k - 1])) << "ray " << i << " fetch " << k;
        }
        const std::vector<TracedFetch> without = Fetches("csm", f, in, {"cone_steps=40"});
        for (size_t k = 1; k < without.size(); ++k)
            sameCellWithout += cell(without[k]) == cell(without[k - 1]) ? 1 : 0;
    }
    EXPECT_GT(steps, 500);
    EXPECT_GT(sameCellWithout, 500);
}
