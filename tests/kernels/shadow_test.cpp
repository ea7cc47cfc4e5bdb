// The light-ray kernels (kernels/shadow.h, `render --shadow`): closed forms on a flat
// plane and behind a wall, a scalar-sampler oracle on real relief, and one result at
// every lane width.
#include "kernels/shadow.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <vector>

#include "kernels/registry.h"
#include "maps/cone_map.h"
#include "render/batch.h"
#include "render/kernel_maps.h"
#include "texture/procedural.h"
#include "texture/sampler.h"

using namespace reliefsim;

namespace {

struct Lit {
    std::vector<float> visibility;
    std::vector<uint32_t> fetches;
    std::vector<float> ambient;
};

/// Vertical view rays (dirUv 0, so each hit lies at its entry uv) through `method` with
/// the light-ray kernel `shadow`, at every lane width this CPU runs; the widths must
/// agree bit for bit. Returns the single-lane results.
Lit LightRays(const DepthField& f, const ShadowJob& shadow,
              const std::vector<glm::vec2>& uv, const char* method = "relief") {
    const KernelInfo& info = FindMethod(method);
    const Kernel kernel = MakeKernel(info, ResolveParams(info, {}));
    KernelMapSettings maps;
    maps.useCache = false;
    std::shared_ptr<const void> params;
    BatchJob job = MakeBatchJob(kernel, BindKernelTextures(f, {}, kernel, maps), params);
    job.shadow = shadow;
    const size_t n = uv.size();
    std::vector<float> ue(n), ve(n), zero(n, 0.0f);
    for (size_t i = 0; i < n; ++i) ue[i] = uv[i].x, ve[i] = uv[i].y;
    Lit first;
    bool haveFirst = false;
    for (const LaneWidthInfo& w : LaneWidths()) {
        if (!w.supported) continue;
        std::vector<float> u(n), v(n), depth(n), vis(n, -1.0f), ao(n, -1.0f);
        std::vector<uint16_t> coarse(n), refine(n);
        std::vector<uint32_t> fetches(n), texels(n), shadowFetches(n, 999u);
        std::vector<uint8_t> flags(n);
        LaneBatch b;
        b.n = int(n);
        b.uEntry = ue.data(), b.vEntry = ve.data(), b.du = zero.data(),
        b.dv = zero.data();
        b.u = u.data(), b.v = v.data(), b.depth = depth.data();
        b.nCoarse = coarse.data(), b.nRefine = refine.data();
        b.fetches = fetches.data(), b.texelReads = texels.data(), b.flags = flags.data();
        b.shadowFetches = shadowFetches.data(), b.visibility = vis.data();
        b.ambient = ao.data();
        w.fn(job, b);
        if (!haveFirst) {
            first = {vis, shadowFetches, ao};
            haveFirst = true;
            continue;
        }
        for (size_t i = 0; i < n; ++i) {
            EXPECT_EQ(std::bit_cast<uint32_t>(vis[i]),
                      std::bit_cast<uint32_t>(first.visibility[i]))
                << "width " << w.width << " ray " << i;
            EXPECT_EQ(shadowFetches[i], first.fetches[i]) << "width " << w.width;
            EXPECT_EQ(std::bit_cast<uint32_t>(ao[i]),
                      std::bit_cast<uint32_t>(first.ambient[i]))
                << "width " << w.width << " ray " << i;
        }
    }
    return first;
}

ShadowJob Job(ShadowKind kind, float lu, float lv, int steps = 16,
              float softening = 0.58f) {
    ShadowJob s;
    s.kind = kind;
    s.steps = steps;
    s.stepInv = 1.0f / float(steps);
    s.softening = softening;
    s.lu = lu, s.lv = lv;
    return s;
}

/// Depth 0.75 (the floor) except the wall: columns 40..43 of 64 at depth 0 (the top).
DepthField Wall() {
    DepthField f = MakeBuiltinMap("flat", 64, 64);
    f.name = "wall";
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x)
            f.depth[size_t(y) * 64 + size_t(x)] = x >= 40 && x < 44 ? 0.0f : 0.75f;
    return f;
}

const glm::vec2 kFloor{32.5f / 64.0f, 32.5f / 64.0f};  // a texel centre of the floor

/// The light ray of kernels/shadow.h with the scalar sampler (texture/sampler.h), an
/// implementation apart from the lanes' sampler: (visibility, fetches).
std::pair<float, uint32_t> Oracle(const DepthField& f, const ShadowJob& s,
                                  glm::vec2 uv0) {
    Sampler<false> smp(f, SamplerState{});
    const float h0 = smp.Sample(uv0);
    uint32_t n = 1;
    if (s.kind == ShadowKind::Hard) {
        const float step = h0 * s.stepInv;
        for (int i = 1; i < s.steps; ++i) {
            const float rise = float(i) * step, t = h0 - rise;
            ++n;
            if (smp.Sample({uv0.x + rise * s.lu, uv0.y + rise * s.lv}) < t)
                return {0.0f, n};
        }
        return {1.0f, n};
    }
    float occlusion = 0.0f;
    for (size_t k = 0; k < kSoftShadowFraction.size(); ++k) {
        const float fr = kSoftShadowFraction[k], t = h0 - fr;
        const float h = smp.Sample({uv0.x + fr * s.lu, uv0.y + fr * s.lv});
        occlusion = MaxSse(occlusion, (t - h) * (kSoftShadowWeight[k] * s.softening));
    }
    return {MaxSse(1.0f - occlusion, 0.0f), 8u};
}

}  // namespace

TEST(Shadow, AFlatPlaneNeverShadowsItself) {
    const DepthField flat = MakeBuiltinMap("flat", 32, 32);
    const std::vector<glm::vec2> uv = {{0.3f, 0.7f}, {0.51f, 0.02f}, {0.9f, 0.9f}};
    for (const ShadowJob& s :
         {Job(ShadowKind::Hard, 0.3f, -0.2f), Job(ShadowKind::Hard, -2.0f, 5.0f, 7),
          Job(ShadowKind::Soft, 0.3f, -0.2f),
          Job(ShadowKind::Soft, 4.0f, 1.0f, 16, 50.0f)}) {
        const Lit r = LightRays(flat, s, uv);
        for (size_t i = 0; i < uv.size(); ++i) {
            EXPECT_EQ(r.visibility[i], 1.0f);
            // hard: the start and steps-1 samples; soft: the start and Tatarchuk's seven
            EXPECT_EQ(r.fetches[i], s.kind == ShadowKind::Hard ? uint32_t(s.steps) : 8u);
        }
    }
}

TEST(Shadow, HardShadowStopsAtTheWall) {
    // From the floor (h0 = 0.75) towards +u at a quarter uv per unit of rise: sample i
    // rises 0.75 i / 16 to depth 0.75 (1 - i/16) at u * 64 = 32.5 + 0.75 i (all exact in
    // binary). i = 10 (u * 64 = 40, on the wall's ramp) passes: the surface, at depth
    // 0.375, lies below the ray at 0.28125; i = 11 (40.75, surface depth 0 < 0.234375) is
    // blocked: occluded after 1 + 11 fetches.
    const DepthField wall = Wall();
    Lit r = LightRays(wall, Job(ShadowKind::Hard, 0.25f, 0.0f), {kFloor});
    EXPECT_EQ(r.visibility[0], 0.0f);
    EXPECT_EQ(r.fetches[0], 12u);
    // Away from the wall (-u: u * 64 falls to 21.25) and short of it (u * 64 <= 34.75):
    // lit, after all 16 fetches.
    for (float lu : {-0.25f, 0.05f}) {
        r = LightRays(wall, Job(ShadowKind::Hard, lu, 0.0f), {kFloor});
        EXPECT_EQ(r.visibility[0], 1.0f) << lu;
        EXPECT_EQ(r.fetches[0], 16u) << lu;
    }
    // On top of the wall: h0 = 0, nothing can lie above the light ray.
    r = LightRays(wall, Job(ShadowKind::Hard, 0.25f, 0.0f), {{41.5f / 64.0f, 0.5f}});
    EXPECT_EQ(r.visibility[0], 1.0f);
}

TEST(Shadow, SoftShadowIsTatarchuksLargestWeightedPenetration) {
    // The samples at f = 0.66 and 0.55 land on the wall (u * 64 = 32.5 + 16 f = 43.06 and
    // 41.3, depth 0) with the ray at depth 0.75 - f: penetrations 0.09 and 0.2, weights 4
    // and 6; at the others the floor or the ramp lies below the ray (h > 0.75 - f), which
    // adds nothing. Softening 0.1: the light keeps 1 - 0.2 * 6 * 0.1 = 0.88; the SDK's
    // 0.58 keeps 1 - 0.696; softening 1 puts the point in full shadow.
    const DepthField wall = Wall();
    Lit r = LightRays(wall, Job(ShadowKind::Soft, 0.25f, 0.0f, 16, 0.1f), {kFloor});
    EXPECT_NEAR(r.visibility[0], 1.0 - 0.2 * 6 * 0.1, 1e-5);
    EXPECT_EQ(r.fetches[0], 8u);
    r = LightRays(wall, Job(ShadowKind::Soft, 0.25f, 0.0f), {kFloor});
    EXPECT_NEAR(r.visibility[0], 1.0 - 0.2 * 6 * 0.58, 1e-5);
    r = LightRays(wall, Job(ShadowKind::Soft, 0.25f, 0.0f, 16, 1.0f), {kFloor});
    EXPECT_EQ(r.visibility[0], 0.0f);
    // Softening 0 sees no occluder at all.
    r = LightRays(wall, Job(ShadowKind::Soft, 0.25f, 0.0f, 16, 0.0f), {kFloor});
    EXPECT_EQ(r.visibility[0], 1.0f);
}

TEST(Shadow, EqualsTheScalarOracleOnRealRelief) {
    // 400 rays over the noise and shapes built-ins, both kernels, several lights.
    for (const char* map : {"noise", "shapes"}) {
        const DepthField f = MakeBuiltinMap(map, 96, 64);
        std::vector<glm::vec2> uv;
        for (int k = 0; k < 200; ++k)
            uv.push_back({float((k * 37) % 200) / 200.0f + 0.0013f,
                          float((k * 91) % 200) / 200.0f});
        int shadowed = 0, lit = 0;
        for (const ShadowJob& s :
             {Job(ShadowKind::Hard, 0.6f, -0.3f, 24),
              Job(ShadowKind::Hard, -0.1f, 0.35f, 5), Job(ShadowKind::Soft, 0.6f, -0.3f),
              Job(ShadowKind::Soft, -0.1f, 0.35f, 16, 2.0f)}) {
            const Lit r = LightRays(f, s, uv);
            for (size_t i = 0; i < uv.size(); ++i) {
                const auto [vis, fetches] = Oracle(f, s, uv[i]);
                EXPECT_EQ(std::bit_cast<uint32_t>(r.visibility[i]),
                          std::bit_cast<uint32_t>(vis))
                    << map << " ray " << i;
                EXPECT_EQ(r.fetches[i], fetches) << map << " ray " << i;
                (r.visibility[i] < 1.0f ? shadowed : lit) += 1;
            }
        }
        EXPECT_GT(shadowed, 50) << map;  // the case is not trivially lit
        EXPECT_GT(lit, 50) << map;
    }
}

TEST(Shadow, NoShadowsCostNothing) {
    const DepthField wall = Wall();
    const Lit r = LightRays(wall, ShadowJob{}, {kFloor});
    EXPECT_EQ(r.visibility[0], 1.0f);
    EXPECT_EQ(r.fetches[0], 0u);
}

TEST(Shadow, ConeShadowOnAFlatPlaneIsTheDistanceFieldPenumbra) {
    // cns's cone-normal map of a flat plane holds n_z = 1 (a 180-degree cone: nothing is
    // near), so every sample lies a = rise above the surface with d = a, and k d / s = k
    // /
    // |(lu, lv, 1)| whatever the step: visibility min(1, k / 1.118034) for lu = 0.3, lv =
    // -0.4.
    const DepthField flat = MakeBuiltinMap("flat", 32, 32);
    const float len = std::sqrt(0.3f * 0.3f + 0.4f * 0.4f + 1.0f);
    for (float k : {0.5f, 1.0f, 8.0f}) {
        ShadowJob s = Job(ShadowKind::Cone, 0.3f, -0.4f);
        s.penumbra = k;
        s.rayLength = len;
        const Lit r = LightRays(flat, s, {{0.3f, 0.7f}, {0.9f, 0.1f}}, "cns");
        for (size_t i = 0; i < 2; ++i) {
            EXPECT_NEAR(r.visibility[i], std::min(1.0, double(k) / 1.118034), 1e-5) << k;
            EXPECT_EQ(r.fetches[i], 16u);
        }
    }
}

TEST(Shadow, ConeShadowIsBlockedWhereTheHardShadowIs) {
    // Behind the wall the ray meets the surface at the hard shadow's sample (1 + 11
    // fetches): visibility 0. Away from it the light stays, softened by the cones.
    const DepthField wall = Wall();
    ShadowJob s = Job(ShadowKind::Cone, 0.25f, 0.0f);
    s.rayLength = std::sqrt(0.25f * 0.25f + 1.0f);
    Lit r = LightRays(wall, s, {kFloor}, "cns");
    EXPECT_EQ(r.visibility[0], 0.0f);
    EXPECT_EQ(r.fetches[0], 12u);
    s.lu = -0.25f;
    r = LightRays(wall, s, {kFloor}, "cns");
    EXPECT_GT(r.visibility[0], 0.0f);
    EXPECT_LE(r.visibility[0], 1.0f);
    EXPECT_EQ(r.fetches[0], 16u);
    // A small penumbra factor darkens what the cones see as near: the estimate grows
    // with k.
    s.penumbra = 0.05f;
    const Lit dim = LightRays(wall, s, {kFloor}, "cns");
    EXPECT_LT(dim.visibility[0], r.visibility[0]);
}

TEST(Shadow, AmbientOcclusionIsTheVisibleSkyOfTheCone) {
    // --ao cone: the cone at the hit leaves sin²θ of the cosine-weighted sky open: n_z²
    // of cns's cone normal, r² / (1 + r²) of csm's ratio; one fetch of the map at the
    // hit.
    ShadowJob ao;
    ao.ao = AoKind::Cone;
    // A flat plane: nothing is near. cns stores n_z = 1 (the whole sky); csm's 8-bit
    // ratio is capped at 1 (45 degrees), which leaves half: the dissertation's "extra
    // darkening" of CSM's AO.
    const DepthField flat = MakeBuiltinMap("flat", 32, 32);
    ao.aoFromNz = true;
    Lit r = LightRays(flat, ao, {{0.3f, 0.7f}}, "cns");
    EXPECT_EQ(r.ambient[0], 1.0f);
    EXPECT_EQ(r.fetches[0], 1u);
    EXPECT_EQ(r.visibility[0], 1.0f);
    ao.aoFromNz = false;
    r = LightRays(flat, ao, {{0.3f, 0.7f}}, "csm");
    EXPECT_EQ(r.ambient[0], 0.5f);
    EXPECT_EQ(r.fetches[0], 1u);
    // The floor beside a wall, at texel centres (the bilinear fetch is the texel's own
    // value): exactly the formula on the stored map, and darker nearer the wall.
    const DepthField wall = Wall();
    const std::vector<glm::vec2> uv = {{38.5f / 64.0f, kFloor.y},
                                       {30.5f / 64.0f, kFloor.y}};
    ao.aoFromNz = true;
    const Lit cns = LightRays(wall, ao, uv, "cns");
    std::vector<uint16_t> codes;
    QuantizeConeMap(GenerateConeMap(wall, ConeKind::ConeNormal), ConeEncoding::U8,
                    &codes);
    for (size_t i = 0; i < uv.size(); ++i) {
        const size_t texel = size_t(uv[i].y * 64.0f) * 64 + size_t(uv[i].x * 64.0f);
        const float nz = Unorm8ToFloat(uint8_t(codes[texel]));
        EXPECT_EQ(cns.ambient[i], nz * nz) << i;
        EXPECT_EQ(cns.fetches[i], 1u);
    }
    EXPECT_LT(cns.ambient[0], cns.ambient[1]);
    EXPECT_LT(cns.ambient[0], 1.0f);
    ao.aoFromNz = false;
    const Lit csm = LightRays(wall, ao, uv, "csm");
    QuantizeConeMap(GenerateConeMap(wall, ConeKind::Cone), ConeEncoding::U8Sqrt, &codes);
    for (size_t i = 0; i < uv.size(); ++i) {
        const size_t texel = size_t(uv[i].y * 64.0f) * 64 + size_t(uv[i].x * 64.0f);
        const float s = Unorm8ToFloat(uint8_t(codes[texel]));
        const float r2 =
            (s * s) * (s * s);  // u8sqrt: the ratio is squared after sampling
        EXPECT_EQ(csm.ambient[i], r2 / (1.0f + r2)) << i;
    }
    EXPECT_LT(csm.ambient[0], csm.ambient[1]);
    // Without AO the factor is 1 and nothing is fetched.
    const Lit none = LightRays(wall, ShadowJob{}, uv, "csm");
    EXPECT_EQ(none.ambient[0], 1.0f);
    EXPECT_EQ(none.fetches[0], 0u);
}
