// The cone kernels (kernels/cone_step.h): the closed form of cone steps over a flat
// plane, Listing 18-3's exact fetch accounting, the directional kernels' choice of
// layer against the generators' sectors, the bound maps, and their bad settings.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>

#include "core/error.h"
#include "kernels/registry.h"
#include "maps/cone_map_detail.h"
#include "metrics/reference_metrics.h"
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
               const std::vector<std::string>& set, const KernelMapSettings& maps,
               const SamplerState& sampler = {}) {
    const KernelInfo& info = FindMethod(method);
    const Kernel kernel = MakeKernel(info, ResolveParams(info, set));
    std::shared_ptr<const void> params;
    const BatchJob job =
        MakeBatchJob(kernel, BindKernelTextures(f, sampler, kernel, maps), params);
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
    // exactly cone_steps + binary_steps fetches (15 + 6 by default); rcns keeps them.
    for (const char* method : {"rcs", "rcns"}) {
        SCOPED_TRACE(method);
        RenderSettings s;
        s.method = method;
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
    EXPECT_EQ(enc("csm"), ConeEncoding::U8Sqrt);   // Dummer, 004 Alg. 4
    EXPECT_EQ(enc("rcs"), ConeEncoding::U8);       // GPU Gems 3
    EXPECT_EQ(enc("qcsm"), ConeEncoding::U8Sqrt);  // 004 Table 4.8, beside its CSM
    EXPECT_EQ(enc("acm4"), ConeEncoding::U8);      // 000 §II-D: RGBA texture
    EXPECT_EQ(enc("acm8"), ConeEncoding::U8);
    EXPECT_EQ(enc("cns"), ConeEncoding::U8);  // n_z in [0, 1], linear (004 is silent)
    EXPECT_EQ(enc("rcns"), ConeEncoding::U8);
    EXPECT_EQ(enc("mcns"), ConeEncoding::U8);
}

TEST(Cns, FlatPlaneIsReachedInOneStep) {
    // Over a flat plane nothing rises above any apex: the cone is 180° wide, n_z = 1
    // (code 255 in u8, exactly 1), which csm's ratio cannot store (it clamps to 1, a
    // 90° cone, and only approaches the plane). Eq. 3.2 with n_z = 1 steps by
    // (D - t) / (0 |dirUv| + 1): straight to the plane, then the second fetch is inside.
    const DepthField f = Constant(0.5f);
    const MarchInput in{{0.3f, 0.4f}, {0.3f, 0.4f}, 1.0f};
    for (const char* form : {"cone_step=0", "cone_step=1"}) {
        const RayRun one = RunCone("cns", f, in, {"cone_steps=1", form}, NoCache());
        EXPECT_EQ(one.result.depthHit, 0.5f) << form;
        EXPECT_FALSE(one.result.hit);
        const RayRun r = RunCone("cns", f, in, {form}, NoCache());
        EXPECT_EQ(r.result.depthHit, 0.5f);
        EXPECT_TRUE(r.result.hit);
        EXPECT_EQ(r.counts.nFetches, 2u);
        EXPECT_EQ(r.result.nCoarse, 2);
    }
}

TEST(Cns, StepsAsCsmWithTheSameCones) {
    // Eq. 3.2 is csm's step with r = n_z / sqrt(1 - n_z^2). With float maps (the ratio
    // and n_z of the same conservative cones) read at texel centres (nearest: bilinear
    // filtering interpolates n_z, a concave function of r, so between centres cns's
    // cone is narrower than csm's) the two kernels walk the same points up to
    // rounding: on builtin:ramp, where every cone but the top row's is bounded, each
    // ray ends at the same depth within 1e-5.
    const DepthField f = MakeBuiltinMap("ramp", 64, 64);
    const KernelMapSettings fl = NoCache(ConeEncoding::Float);
    SamplerState nearest;
    nearest.filter = Filter::Nearest;
    int sameSteps = 0;
    for (int k = 0; k < 64; ++k) {
        const float a = 0.15f + 0.01f * float(k % 8), phi = 0.7f * float(k);
        const MarchInput in{{0.013f * float(k), 0.029f * float(k)},
                            {a * std::cos(phi), a * std::sin(phi)},
                            1.0f};
        const RayRun c = RunCone("csm", f, in, {"cone_steps=12"}, fl, nearest);
        const RayRun n = RunCone("cns", f, in, {"cone_steps=12"}, fl, nearest);
        EXPECT_NEAR(n.result.depthHit, c.result.depthHit, 1e-5) << k;
        // A step that lands on the surface to within rounding may need one trip more
        // or less to see itself inside (and the top row's unbounded cone is 180° for
        // cns, ratio 1024 for csm).
        EXPECT_LE(std::abs(n.result.nCoarse - c.result.nCoarse), 1) << k;
        sameSteps += n.result.nCoarse == c.result.nCoarse;
    }
    EXPECT_GE(sameSteps, 48);
}

TEST(Cns, RcnsReadsTheRelaxedConeNormalMap) {
    // rcns names "cone-normal --relaxed": the bound layer is n_z of the Listing 18-2
    // relaxed cones (maps --kind cone-normal --relaxed), cns's is n_z of the
    // conservative ones. Relaxed cones are never narrower, except where the
    // conservative cone is wider than the Listing's initial ratio 1 (n_z = 1/sqrt 2).
    const DepthField f = MakeBuiltinMap("shapes", 32, 32);
    const KernelMapSettings fl = NoCache(ConeEncoding::Float);
    auto layer = [&](const char* m) {
        const KernelInfo& info = FindMethod(m);
        const auto layers =
            KernelConeLayers(f, MakeKernel(info, ResolveParams(info, {})), fl);
        EXPECT_EQ(layers.size(), 1u);
        return layers[0].depth;
    };
    ConeMapParams relaxed;
    relaxed.relaxed = true;
    EXPECT_EQ(layer("rcns"), GenerateConeMap(f, ConeKind::ConeNormal, relaxed).values);
    EXPECT_EQ(layer("cns"), GenerateConeMap(f, ConeKind::ConeNormal, {}).values);
    const auto c = layer("cns"), r = layer("rcns");
    size_t wider = 0;
    for (size_t i = 0; i < c.size(); ++i) {
        if (c[i] <= 0.70710677f) {
            EXPECT_GE(r[i], c[i]) << i;
        }
        wider += r[i] > c[i];
    }
    EXPECT_GT(wider, c.size() / 4);
    ASSERT_TRUE(ParseKernelMap("cone-normal --relaxed").has_value());
    EXPECT_TRUE(ParseKernelMap("cone-normal --relaxed")->params.relaxed);
    EXPECT_FALSE(ParseKernelMap("cone-normal")->params.relaxed);
    EXPECT_FALSE(ParseKernelMap("cone-normal --relax").has_value());
}

namespace {

using L1 = Lanes<1>;

template <detail::ConeFamily kF>
int LayerOf(float du, float dv) {
    return int(detail::ConeLayerOf<kF>(L1::F(du), L1::F(dv))[0]);
}

}  // namespace

TEST(DirectionalCones, LayerIsASectorOfTheGeneratorThatHoldsTheRay) {
    // acm4 / acm8: the layer the kernel reads must be a closed sector that the map
    // generator (maps/cone_map.cpp SectorMask) puts the ray's direction in, for square
    // and non-square maps (sectors are in uv space), including every sector boundary.
    for (auto [w, h] : {std::pair{16, 16}, {32, 8}, {8, 24}}) {
        const detail::Geometry g = detail::MakeGeometry(w, h);
        for (int dy = -4; dy <= 4; ++dy)
            for (int dx = -4; dx <= 4; ++dx) {
                if (dx == 0 && dy == 0) continue;
                const float du = float(dx) / float(w), dv = float(dy) / float(h);
                const int l4 = LayerOf<detail::ConeFamily::Acm4>(du, dv);
                const int l8 = LayerOf<detail::ConeFamily::Acm8>(du, dv);
                ASSERT_TRUE(detail::SectorMask(ConeKind::Acm4, g, dx, dy) & (1u << l4))
                    << w << "x" << h << " " << dx << "," << dy << " layer " << l4;
                ASSERT_TRUE(detail::SectorMask(ConeKind::Acm8, g, dx, dy) & (1u << l8))
                    << w << "x" << h << " " << dx << "," << dy << " layer " << l8;
                // qcsm: the layer's half planes (its channels, render/kernel_maps.cpp)
                // all hold the direction. Channels +x, -x, +y, -y = bits 1, 2, 4, 8.
                static constexpr unsigned kHalfPlanes[8] = {1 | 4, 2 | 4, 2 | 8, 1 | 8,
                                                            1,     4,     2,     8};
                const unsigned quad = detail::SectorMask(ConeKind::Quad, g, dx, dy);
                const int lq = LayerOf<detail::ConeFamily::Quad>(du, dv);
                ASSERT_EQ(kHalfPlanes[lq] & quad, kHalfPlanes[lq])
                    << dx << "," << dy << " layer " << lq;
            }
    }
    // Boundaries take the lowest sector holding them.
    EXPECT_EQ(LayerOf<detail::ConeFamily::Acm4>(0.0f, 1.0f), 0);
    EXPECT_EQ(LayerOf<detail::ConeFamily::Acm4>(-1.0f, 0.0f), 1);
    EXPECT_EQ(LayerOf<detail::ConeFamily::Acm8>(0.5f, 0.5f), 0);
    EXPECT_EQ(LayerOf<detail::ConeFamily::Acm8>(0.0f, -0.5f), 5);
    EXPECT_EQ(LayerOf<detail::ConeFamily::Quad>(0.0f, 0.0f), 4);  // vertical ray
}

TEST(DirectionalCones, FlatPlaneConvergesAsCsm) {
    // Over a flat plane every sector is unbounded: every directional kernel steps as
    // csm with the clamped ratio of its encoding (1 for u8 and u8sqrt), whatever the
    // direction class. t_n = D (1 - (a / (a + 1))^n).
    const DepthField f = Constant(0.5f);
    for (const char* m : {"qcsm", "acm4", "acm8"})
        for (glm::vec2 d :
             {glm::vec2{0.3f, 0.4f}, glm::vec2{-0.4f, 0.3f}, glm::vec2{-0.3f, -0.4f},
              glm::vec2{0.4f, -0.3f}, glm::vec2{0.5f, 0.0f}, glm::vec2{0.0f, -0.5f}}) {
            const RayRun r =
                RunCone(m, f, {{0.3f, 0.4f}, d, 1.0f}, {"cone_steps=5"}, NoCache());
            const double q = 0.5 / (0.5 + 1.0);
            EXPECT_NEAR(r.result.depthHit, 0.5 * (1.0 - std::pow(q, 5)), 1e-6)
                << m << " " << d.x << "," << d.y;
            EXPECT_EQ(r.counts.nFetches, 5u);
        }
}

TEST(DirectionalCones, ReadTheRaysSectorOfTheMap) {
    // A wall on one side only: texels x in [12, 20) are at depth 0 (the top), the rest
    // at depth 1. From x = 4 the wall is 8 texels away in +u; in -u it is 17 texels
    // away through the wrap, beyond the generators' half-width window (offsets in
    // [-16, 16]), so no texel bounds the cones toward -u. Every directional kernel's
    // cone toward -u is therefore wider than toward +u, and wider than csm's symmetric
    // cone: the first step goes deeper.
    DepthField f = Constant(1.0f, 32);
    for (int j = 0; j < 32; ++j)
        for (int i = 12; i < 20; ++i) f.depth[size_t(j) * 32 + size_t(i)] = 0.0f;
    const MarchInput minus{{4.5f / 32.0f, 0.5f}, {-0.05f, 0.0f}, 1.0f};
    const MarchInput plus{{4.5f / 32.0f, 0.5f}, {0.05f, 0.0f}, 1.0f};
    const KernelMapSettings fl = NoCache(ConeEncoding::Float);
    for (const char* m : {"qcsm", "acm4", "acm8"}) {
        const RayRun a = RunCone(m, f, minus, {"cone_steps=1"}, fl);
        const RayRun b = RunCone(m, f, plus, {"cone_steps=1"}, fl);
        const RayRun c = RunCone("csm", f, minus, {"cone_steps=1"}, fl);
        EXPECT_GT(a.result.depthHit, b.result.depthHit) << m;
        EXPECT_GT(a.result.depthHit, c.result.depthHit) << m;
        // Toward the wall the sector's cone is csm's (the wall is the nearest blocker).
        EXPECT_EQ(b.result.depthHit, c.result.depthHit) << m;
    }
}

TEST(DirectionalCones, FewerCoarseStepsThanCsmOnShapes) {
    // 000 §II-B: wider (directional) cones converge in fewer steps. With early exit and
    // enough steps, the average coarse iterations of acm4, acm8 and qcsm on
    // builtin:shapes are below csm's (same encoding, so only the cones differ).
    const DepthField f = MakeBuiltinMap("shapes", 128, 128);
    auto avgCoarse = [&](const char* m) {
        RenderSettings s;
        s.method = m;
        s.width = s.height = 96;
        s.reference = false;
        s.maps = NoCache(ConeEncoding::Float);
        s.set = {"cone_steps=64"};
        const RenderOutput out = Render(f, s);
        double sum = 0;
        size_t n = 0;
        for (size_t i = 0; i < out.record.nCoarse.size(); ++i)
            if (out.record.Covered(i)) sum += out.record.nCoarse[i], ++n;
        return sum / double(n);
    };
    const double csm = avgCoarse("csm");
    for (const char* m : {"qcsm", "acm4", "acm8"}) EXPECT_LT(avgCoarse(m), csm) << m;
    EXPECT_LT(avgCoarse("acm8"), avgCoarse("acm4"));  // narrower sectors, wider cones
}

TEST(ConeFilter, NamesTheWayTheRatioIsSampled) {
    const KernelInfo& csm = FindMethod("csm");
    EXPECT_EQ(ResolveParams(csm, {"cone_filter=min4"}).at("cone_filter"), 3.0);
    EXPECT_EQ(ResolveParams(csm, {"cone_filter=nearest"}).at("cone_filter"), 2.0);
    EXPECT_EQ(ResolveParams(csm, {"cone_filter=1"}).at("cone_filter"), 1.0);
    EXPECT_EQ(ResolveParams(csm, {}).at("cone_filter"), 0.0);  // auto
    for (const char* bad : {"cone_filter=bicubic", "cone_filter=4", "cone_filter=1.5",
                            "cone_filter=", "cone_filter=-1"}) {
        try {
            ResolveParams(csm, {bad});
            ADD_FAILURE() << bad;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("must be one of: auto, bilinear, "
                                                 "nearest, min4"),
                      std::string::npos)
                << e.what();
        }
    }
    EXPECT_THROW(ResolveParams(FindMethod("relief"), {"cone_filter=min4"}), Error);
    const Kernel k = MakeKernel(csm, ResolveParams(csm, {"cone_filter=min4"}));
    EXPECT_EQ(KernelConeFilter(k, Filter::Nearest), Filter::Min4);
    const Kernel a = MakeKernel(csm, ResolveParams(csm, {}));
    EXPECT_EQ(KernelConeFilter(a, Filter::Nearest), Filter::Nearest);
    // An 8-bit height texture samples both channels with one filter (llvmpipe's 8-bit
    // path is modelled for that only).
    RenderSettings s;
    s.method = "csm";
    s.sampler.precision = Precision::Llvmpipe8;
    s.set = {"cone_filter=min4"};
    EXPECT_THROW(ValidateSettings(s), Error);
    s.set = {"cone_filter=bilinear"};
    EXPECT_NO_THROW(ValidateSettings(s));
}

TEST(ConeFilter, FirstStepUsesTheFilteredRatio) {
    // The first fetch is at uvEntry (t = 0): the step is d = r D / (a + r), so the
    // ratio the kernel used is r = a d / (D - d). At u = (i + 0.75) / W, v = (j + 0.875)
    // / H the bilinear footprint is texels (i..i+1, j..j+1) with weights (0.25, 0.375)
    // and the nearest texel is (i, j). The height stays bilinear whatever cone_filter.
    const DepthField f = MakeBuiltinMap("bumps", 32, 32);
    const ConeMap cone = GenerateConeMap(f, ConeKind::Cone, {});
    const KernelMapSettings fl = NoCache(ConeEncoding::Float);
    auto lerp2 = [](float a, float b, float c, float d) {
        const float r0 = a + 0.25f * (b - a), r1 = c + 0.25f * (d - c);
        return r0 + 0.375f * (r1 - r0);
    };
    int checked = 0;
    for (int j = 3; j < 28; j += 6)
        for (int i = 2; i < 28; i += 5) {
            const float r00 = cone.At(i, j), r10 = cone.At(i + 1, j),
                        r01 = cone.At(i, j + 1), r11 = cone.At(i + 1, j + 1);
            if (std::max({r00, r10, r01, r11}) > 2.0f) continue;  // keep the test tight
            const float D =
                lerp2(f.At(i, j), f.At(i + 1, j), f.At(i, j + 1), f.At(i + 1, j + 1));
            if (D < 0.05f) continue;
            const MarchInput in{{(float(i) + 0.75f) / 32.0f, (float(j) + 0.875f) / 32.0f},
                                {0.2f, 0.1f},
                                1.0f};
            const float a = std::sqrt(0.2f * 0.2f + 0.1f * 0.1f);
            auto used = [&](const char* filter) {
                const RayRun r =
                    RunCone("csm", f, in,
                            {"cone_steps=1", std::string("cone_filter=") + filter}, fl);
                EXPECT_EQ(r.counts.nFetches, 1u);
                const float d = r.result.depthHit;
                return std::pair{a * d / (D - d), r.counts.nTexelReads};
            };
            const auto [bil, bilReads] = used("bilinear");
            const auto [nea, neaReads] = used("nearest");
            const auto [mn, mnReads] = used("min4");
            const float tol = 2e-4f;
            EXPECT_NEAR(bil, lerp2(r00, r10, r01, r11), tol) << i << "," << j;
            EXPECT_NEAR(nea, r00, tol) << i << "," << j;
            EXPECT_NEAR(mn, std::min({r00, r10, r01, r11}), tol) << i << "," << j;
            // One footprint when the cone is sampled as the height; a second one (1 or 4
            // texels) when it is not.
            EXPECT_EQ(bilReads, 4u);
            EXPECT_EQ(neaReads, 5u);
            EXPECT_EQ(mnReads, 8u);
            ++checked;
        }
    EXPECT_GE(checked, 10);
}

TEST(ConeFilter, Min4RemovesMostStepsPastTheFirstHit) {
    // Texel-centre cone maps are not conservative for the bilinear surface
    // (docs/kernels.md "Conservative, but for which surface?"): bilinear sampling of the
    // ratio steps past the exact first hit on many pixels (the dissertation's Fig. 4.6
    // artifact), min4 on far fewer; csm over a flat plane never does (its cones are
    // unbounded and the step only approaches the plane).
    auto past = [](const DepthField& f, const char* filter) {
        RenderSettings s;
        s.method = "csm";
        s.width = s.height = 96;
        s.maps = NoCache(ConeEncoding::Float);
        s.set = {"cone_steps=64", std::string("cone_filter=") + filter};
        return Render(f, s).referenceSummary.pastFirstHitPixels;
    };
    const DepthField shapes = MakeBuiltinMap("shapes", 128, 128);
    const uint64_t bilinear = past(shapes, "bilinear"), min4 = past(shapes, "min4");
    EXPECT_GT(bilinear, 100u);
    EXPECT_LT(min4 * 3, bilinear);
    EXPECT_EQ(past(Constant(0.5f, 64), "bilinear"), 0u);
    EXPECT_EQ(past(Constant(0.5f, 64), "min4"), 0u);
}

TEST(ConeFilter, BilinearBoundsNeverStepPastTheFirstHit) {
    // With maps conservative for the bilinear surface (--cone-bounds bilinear,
    // maps/cone_map_bilinear.h) no conservative kernel answers a point past the exact
    // first hit, whatever the cone filter, on every built-in scene; float maps and the
    // rounded-down 8-bit encoding. What remains of PastFirstHit's 2^-20 in depth is the
    // rounding of the ray point itself: the kernel's hit uv within 2^-22 (4 float ulps)
    // of the exact hit's, at walls so steep that one ulp of uv is more than 2^-20 of
    // depth (builtin:shapes has such pixels: docs/kernels.md).
    int rounding = 0;
    for (const char* map : {"shapes", "bumps", "steps", "noise"}) {
        const DepthField f = MakeBuiltinMap(map, 128, 128);
        for (const char* method : {"csm", "qcsm", "acm4", "acm8", "cns"})
            for (const char* filter : {"min4", "bilinear"})
                for (ConeEncoding e : {ConeEncoding::Float, ConeEncoding::U8Sqrt}) {
                    if (e != ConeEncoding::Float && std::string(method) != "csm")
                        continue;
                    RenderSettings s;
                    s.method = method;
                    s.width = s.height = 96;
                    s.maps = NoCache(e);
                    s.maps.bounds = ConeBounds::Bilinear;
                    s.set = {"cone_steps=64", std::string("cone_filter=") + filter};
                    const RenderOutput out = Render(f, s);
                    ASSERT_TRUE(out.hasReference);
                    int past = 0, covered = 0;
                    for (size_t i = 0; i < out.record.hitDepth.size(); ++i) {
                        if (!out.record.Covered(i)) continue;
                        ++covered;
                        if (!PastFirstHit(out.record.hitDepth[i], out.reference.depth[i]))
                            continue;
                        const double du = double(out.record.hitU[i]) -
                                          double(out.reference.u[i]),
                                     dv = double(out.record.hitV[i]) -
                                          double(out.reference.v[i]);
                        if (std::sqrt(du * du + dv * dv) <= 0x1p-22)
                            ++rounding;
                        else
                            ++past;
                    }
                    EXPECT_GT(covered, 5000);
                    EXPECT_EQ(past, 0)
                        << method << " on " << map << ", cone_filter=" << filter << ", "
                        << ToString(e);
                }
    }
    EXPECT_LT(rounding, 200);
}

TEST(Mcns, ReadsNzOfTheFourStackedCones) {
    // mcns names "stacked --normal": four layers, layer k the n_z of stacked cone k
    // (apex d (4 - k) / 4); layer 0 is cns's cone up to the rounding of n_z.
    const DepthField f = MakeBuiltinMap("shapes", 32, 32);
    const KernelInfo& info = FindMethod("mcns");
    const auto layers = KernelConeLayers(f, MakeKernel(info, ResolveParams(info, {})),
                                         NoCache(ConeEncoding::Float));
    ASSERT_EQ(layers.size(), 4u);
    ConeMapParams p;
    p.normal = true;
    const ConeMap st = GenerateConeMap(f, ConeKind::Stacked, p);
    const ConeMap cn = GenerateConeMap(f, ConeKind::ConeNormal, {});
    for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 32; ++j)
            for (int i = 0; i < 32; ++i) {
                ASSERT_EQ(layers[size_t(k)].At(i, j), st.At(i, j, k)) << k;
                if (k == 0) {
                    ASSERT_NEAR(st.At(i, j, 0), cn.At(i, j), 1e-6);
                }
            }
}

TEST(Mcns, FlatPlaneIsReachedInOneStep) {
    const DepthField f = Constant(0.5f);
    const RayRun r =
        RunCone("mcns", f, {{0.3f, 0.4f}, {0.3f, 0.4f}, 1.0f}, {}, NoCache());
    EXPECT_EQ(r.result.depthHit, 0.5f);
    EXPECT_TRUE(r.result.hit);
    EXPECT_EQ(r.counts.nFetches, 2u);
    EXPECT_EQ(r.counts.nTexelReads, 2u * 4u * 4u);  // four layers' footprints per fetch
}

TEST(Mcns, LargestStackedStepIsNeverShorterThanCns) {
    // Cone 0 is cns's cone, so the largest step of the stack is at least cns's; on
    // builtin:shapes the higher cones make it longer on many rays.
    const DepthField f = MakeBuiltinMap("shapes", 64, 64);
    const KernelMapSettings fl = NoCache(ConeEncoding::Float);
    int longer = 0;
    for (int k = 0; k < 64; ++k) {
        const float a = 0.2f + 0.02f * float(k % 5), phi = 0.9f * float(k);
        const MarchInput in{{0.017f * float(k), 0.031f * float(k)},
                            {a * std::cos(phi), a * std::sin(phi)},
                            1.0f};
        const RayRun c = RunCone("cns", f, in, {"cone_steps=1"}, fl);
        const RayRun m = RunCone("mcns", f, in, {"cone_steps=1"}, fl);
        EXPECT_GE(m.result.depthHit, c.result.depthHit - 1e-6f) << k;
        longer += m.result.depthHit > c.result.depthHit + 1e-4f;
    }
    EXPECT_GT(longer, 8);
    // 004 §4.3.5: at the same step count the error is slightly lower with the stack.
    auto mse = [&](const char* m) {
        RenderSettings s;
        s.method = m;
        s.width = s.height = 96;
        s.maps = NoCache();
        s.set = {"cone_steps=8"};
        return Render(f, s).referenceSummary.mseExactDepth;
    };
    EXPECT_LT(mse("mcns"), mse("cns"));
}
