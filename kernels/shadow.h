// Light-ray kernels: the self-shadowing of a hit (render --shadow none|hard|soft|cone),
// written once over a lane type like the view kernels; kernels/glsl/shadow.glsl is the
// same code. docs/methods/shadows.md has the equations and what each counts.
//
// Both trace the light ray from the shaded point towards the light, in texture space:
// rising r depth units moves uv by r * (lu, lv) with (lu, lv) = L.xy / L.z * k (L the
// unit tangent-space direction towards the light, k the uv per plane unit times the
// depth scale, as the view ray's dirUv), and the ray starts on the surface at the hit's
// uv, h0 = h(uv0) (a fetch: the hit a coarse search returns can lie a step inside the
// relief, and the surface height at its uv does not, so a flat or slanted plane never
// shadows itself).
//  * hard (dissertation 004 §2.6 and §4.4: the coarse search of occlusion reused for the
//    light ray; McGuire's steep parallax shadows): the ray from h0 to the top in
//    shadow_steps equal steps; sample i = 1 .. steps-1 at depth t = h0 - i * h0 / steps
//    (the top itself cannot be occluded). Occluded, visibility 0, at the first sample
//    whose surface lies above the ray (h < t); the loop leaves there, as a GPU shader's
//    break. Fetches: 1 + the samples taken.
//  * soft (Tatarchuk 2006, "Dynamic parallax occlusion mapping with approximate soft
//    shadows", as in the DirectX SDK's ParallaxOcclusionMapping sample): seven samples at
//    the fractions f = 0.88, 0.77, ..., 0.22 of a light vector that rises one full depth,
//    each weighted (1, 2, 4, 6, 8, 10, 12: nearer samples count more) by how far the
//    surface lies above the ray there, times shadow_softening; visibility = 1 - the
//    largest, clamped to [0, 1]. Fetches: always 8. The sample keeps the ray's geometry
//    (L.xy / L.z); the SDK's shader steps L.xy alone, which only matches for a light
//    overhead.
//  * cone (dissertation 004 §4.4, cone-normal soft shadows; cns's map): the hard
//    shadow's samples, each also reading the cone normal's n_z there. The ray lies
//    a = h - t above the surface (a < 0: blocked, visibility 0, the loop leaves); the
//    cone's distance estimate is d = a n_z (eq. 3.1), and the penumbra that of a
//    distance field (Quilez 2010): visibility = min(1, min_i k d_i / s_i), s_i = rise_i
//    |(lu, lv, 1)| the distance travelled in the map's (uv, depth) space, k =
//    shadow_penumbra. Fetches: as hard (each reads depth and n_z in one footprint).
// Lanes with no hit get visibility 1 and no fetch.
//
// Ambient occlusion (AmbientOcclusion, render --ao cone; dissertation 004 §4.5, which
// shows the cone ratio of CSM and the cone normal of CNS used as the AO term but gives no
// formula): the cone at the hit bounds the open sky above it, so the ambient term is
// scaled by the cosine-weighted fraction of the hemisphere inside the cone, sin²θ for a
// cone of half angle θ from the normal: n_z² for cns's map (n_z = sin θ, §3.1), r² / (1 +
// r²) for csm's ratio r = tan θ. One fetch of the cone map at the hit, counted with the
// light rays'.
#pragma once

#include "kernels/lanes.h"
#include "kernels/shadow_job.h"
#include "texture/lane_sampler.h"

namespace reliefsim {

/// The light's visibility in [0, 1] at each lane's hit (u0, v0) where `hit`, counting
/// each lane's light-ray fetches into `fetches`. 1 elsewhere.
template <class L>
RS_INLINE typename L::F LightVisibility(const LaneTextures& tex, const ShadowJob& s,
                                        const typename L::F& u0, const typename L::F& v0,
                                        const typename L::M& hit,
                                        typename L::F& fetches) {
    using F = typename L::F;
    using M = typename L::M;
    F vis(1.0f);
    if (s.kind == ShadowKind::None || !Any(hit)) return vis;
    F texels(0.0f);  // the view ray's texel count is not the light's
    const F h0 = SampleHeightLanes<L>(tex, u0, v0, hit, texels);
    Assign(hit, fetches, fetches + F(1.0f));
    if (s.kind == ShadowKind::Hard || s.kind == ShadowKind::Cone) {
        // The hard shadow's samples; the cone shadow reads n_z with each depth and keeps
        // the smallest penumbra estimate of the samples it passes.
        using I = typename L::I;
        const bool cone = s.kind == ShadowKind::Cone;
        const F step = h0 * F(s.stepInv);
        M on = hit;
        for (int i = 1; i < s.steps && Any(on); ++i) {
            const F rise = F(float(i)) * step;
            const F t = h0 - rise;
            const F u = u0 + rise * F(s.lu), v = v0 + rise * F(s.lv);
            F nz(0.0f);
            const F h = cone ? SampleHeightConeLanes<L>(tex, u, v, I(0), on, texels, nz)
                             : SampleHeightLanes<L>(tex, u, v, on, texels);
            Assign(on, fetches, fetches + F(1.0f));
            const F above = h - t;
            const M blocked = on && (cone ? above < F(0.0f) : h < t);
            Assign(blocked, vis, F(0.0f));
            on = on && !blocked;
            if (cone) {
                // (A hit at the top, h0 = 0, rises by 0: no estimate, nothing above it.)
                const F estimate =
                    (F(s.penumbra) * (above * nz)) / (rise * F(s.rayLength));
                Assign(on && (rise > F(0.0f)), vis, MinSse(vis, estimate));
            }
        }
        return vis;
    }
    F occlusion(0.0f);
    for (size_t k = 0; k < kSoftShadowFraction.size(); ++k) {
        const F f(kSoftShadowFraction[k]);
        const F t = h0 - f;
        const F u = u0 + f * F(s.lu), v = v0 + f * F(s.lv);
        const F h = SampleHeightLanes<L>(tex, u, v, hit, texels);
        occlusion = MaxSse(occlusion, (t - h) * F(kSoftShadowWeight[k] * s.softening));
    }
    Assign(hit, fetches, fetches + F(float(kSoftShadowFraction.size())));
    Assign(hit, vis, MaxSse(F(1.0f) - occlusion, F(0.0f)));
    return vis;
}

/// The ambient occlusion factor in [0, 1] at each lane's hit (u0, v0) where `hit` and
/// s.ao is on (one fetch of the cone map there, counted into `fetches`); 1 elsewhere.
template <class L>
RS_INLINE typename L::F AmbientOcclusion(const LaneTextures& tex, const ShadowJob& s,
                                         const typename L::F& u0, const typename L::F& v0,
                                         const typename L::M& hit,
                                         typename L::F& fetches) {
    using F = typename L::F;
    using I = typename L::I;
    F ao(1.0f);
    if (s.ao == AoKind::None || !Any(hit)) return ao;
    F texels(0.0f), cone(0.0f);
    SampleHeightConeLanes<L>(tex, u0, v0, I(0), hit, texels, cone);
    Assign(hit, fetches, fetches + F(1.0f));
    const F c2 = cone * cone;
    Assign(hit, ao, s.aoFromNz ? c2 : c2 / (F(1.0f) + c2));
    return ao;
}

}  // namespace reliefsim
