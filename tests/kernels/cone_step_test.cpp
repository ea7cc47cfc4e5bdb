// csm and rcs (kernels/cone_step.h): the closed form of cone steps over a flat plane,
// Listing 18-3's exact fetch accounting, the bound maps, and their bad settings.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>

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

DepthField Constant(float depth, int n = 32) {
    DepthField f;
    f.width = f.height = n;
    f.depth.assign(size_t(n) * size_t(n), depth);
    f.name = "constant";
    return f;
}

KernelMapSettings NoCache(std::optional<ConeEncoding> e = {}) {
    KernelMapSettings m;
    m.useCache = false;
    m.encoding = e;
    return m;
}

RayRun RunCone(const char* method, const DepthField& f, const MarchInput& in,
               const std::vector<std::string>& set, const KernelMapSettings& maps) {
    const KernelInfo& info = FindMethod(method);
    const Kernel kernel = MakeKernel(info, ResolveParams(info, set));
    std::shared_ptr<const void> params;
    const BatchJob job =
        MakeBatchJob(kernel, BindKernelTextures(f, {}, kernel, maps), params);
    return test::MarchEveryWidth(job, in);
}

}  // namespace

TEST(Csm, FlatPlaneConvergesGeometrically) {
    // Over a flat plane no texel is above the apex: u8sqrt stores the ratio clamped to
    // 1 (code 255, decoded 1). Each step covers the fraction r / (a + r) of the
    // remaining depth (a = |dirUv|), so after n steps t_n = D (1 - (a / (a + r))^n).
    const DepthField f = Constant(0.5f);
    const MarchInput in{{0.3f, 0.4f}, {0.3f, 0.4f}, 1.0f};  // a = 0.5
    for (int n : {1, 2, 5, 10}) {
        const RayRun r =
            RunCone("csm", f, in, {"cone_steps=" + std::to_string(n)}, NoCache());
        const double q = 0.5 / (0.5 + 1.0);
        EXPECT_NEAR(r.result.depthHit, 0.5 * (1.0 - std::pow(q, n)), 1e-6) << n;
        EXPECT_EQ(r.counts.nFetches, uint32_t(n));
        EXPECT_EQ(r.result.nCoarse, n);
        EXPECT_FALSE(r.result.hit);  // never inside: the step only approaches the plane
        // Alg. 4's unit-ray form is the same step, rounded differently.
        const RayRun a = RunCone(
            "csm", f, in, {"cone_steps=" + std::to_string(n), "cone_step=1"}, NoCache());
        EXPECT_NEAR(a.result.depthHit, r.result.depthHit, 1e-6) << n;
    }
}

TEST(Csm, StopsAtTheFirstPointInside) {
    // Depth 0 everywhere: the first sample (t = 0) is already on the surface.
    const DepthField f = Constant(0.0f);
    const RayRun r = RunCone("csm", f, {{0.5f, 0.5f}, {0.1f, 0.0f}, 1.0f}, {}, NoCache());
    EXPECT_TRUE(r.result.hit);
    EXPECT_EQ(r.counts.nFetches, 1u);
    EXPECT_EQ(r.result.depthHit, 0.0f);
    // Fixed loops keep fetching at the latched point: cone_steps fetches, same answer.
    const RayRun fixed = RunCone("csm", f, {{0.5f, 0.5f}, {0.1f, 0.0f}, 1.0f},
                                 {"early_exit=0", "cone_steps=7"}, NoCache());
    EXPECT_EQ(fixed.counts.nFetches, 7u);
    EXPECT_EQ(fixed.result.depthHit, 0.0f);
}

TEST(Rcs, ListingCostsConeStepsPlusBinaryStepsEverywhere) {
    // Listing 18-3 runs both loops for their full counts: every covered pixel costs
    // exactly cone_steps + binary_steps fetches (15 + 6 by default).
    RenderSettings s;
    s.method = "rcs";
    s.width = s.height = 48;
    s.reference = false;
    s.maps = NoCache();
    const DepthField f = MakeBuiltinMap("shapes", 64, 64);
    const RenderOutput out = Render(f, s);
    size_t covered = 0;
    for (size_t i = 0; i < out.record.nFetches.size(); ++i) {
        if (!out.record.Covered(i)) continue;
        ++covered;
        ASSERT_EQ(out.record.nFetches[i], 21u) << i;
        ASSERT_EQ(out.record.nCoarse[i], 15u);
        ASSERT_EQ(out.record.nRefine[i], 6u);
    }
    EXPECT_GT(covered, 1000u);
    s.set = {"cone_steps=4", "refine_steps=3"};
    const RenderOutput small = Render(f, s);
    for (size_t i = 0; i < small.record.nFetches.size(); ++i)
        if (small.record.Covered(i)) {
            ASSERT_EQ(small.record.nFetches[i], 7u);
        }
}

TEST(Rcs, BinarySearchConvergesOnAFlatPlane) {
    // The relaxed loop stops at K above the plane (depth 0.5); the binary search between
    // H = tK/2 and K then converges to K (the ray never pierces): t -> tK within
    // tK / 2^(b+1).
    const DepthField f = Constant(0.5f);
    const MarchInput in{{0.3f, 0.4f}, {0.3f, 0.4f}, 1.0f};
    const RayRun c = RunCone("rcs", f, in, {"refine_steps=0"}, NoCache());
    const RayRun r = RunCone("rcs", f, in, {"refine_steps=12"}, NoCache());
    const float tK = 2.0f * c.result.depthHit;  // refine_steps=0 answers H = tK / 2
    EXPECT_NEAR(r.result.depthHit, tK, tK / 4096.0f);
    EXPECT_LE(r.result.depthHit, 0.5f);
    EXPECT_EQ(r.counts.nFetches, 15u + 12u);
}

TEST(ConeKernels, BadMapSettingsAreOneError) {
    RenderSettings s;
    s.method = "csm";
    s.sampler.precision = Precision::Llvmpipe8;
    s.maps.encoding = ConeEncoding::Float;
    EXPECT_THROW(ValidateSettings(s), Error);  // an 8-bit texture needs 8-bit ratios
    s.maps.encoding = ConeEncoding::U8;
    EXPECT_NO_THROW(ValidateSettings(s));
    s.method = "relief";
    EXPECT_THROW(ValidateSettings(s), Error);  // relief reads no cone map
    // A cone kernel without its map bound: one error, not a crash.
    const DepthField f = Constant(0.5f);
    const KernelInfo& info = FindMethod("csm");
    std::shared_ptr<const void> params;
    EXPECT_THROW(MakeBatchJob(MakeKernel(info, ResolveParams(info, {})),
                              BindTextures(f, {}), params),
                 Error);
}

TEST(ConeKernels, DefaultEncodingsAreThePapers) {
    const KernelMapSettings none = NoCache();
    auto enc = [&](const char* m) {
        const KernelInfo& info = FindMethod(m);
        return KernelMapEncoding(MakeKernel(info, ResolveParams(info, {})), none);
    };
    EXPECT_EQ(enc("csm"), ConeEncoding::U8Sqrt);  // Dummer, 004 Alg. 4
    EXPECT_EQ(enc("rcs"), ConeEncoding::U8);      // GPU Gems 3
}
