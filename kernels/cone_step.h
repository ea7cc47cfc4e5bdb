// Cone step mapping (Dummer 2006; dissertation 004 Alg. 4, §2.4; ACM paper 000 §II-A)
// and relaxed cone stepping with its binary search (Policarpo & Oliveira, GPU Gems 3
// ch. 18, Listing 18-3). Two methods, one source: ConeStep<kRelaxed>.
//
// Conventions (DESIGN.md): p(t) = (uvEntry + t * dirUv, t), t the ray's depth; a cone
// ratio r is the cone's radius in uv per unit of depth, so the ray moves |dirUv| uv per
// unit depth whatever the depth scale or tiling.
//
// The step. At the ray point of depth t over surface depth D with ratio r, the cone's
// apex sits on the surface at (uv, D) and opens upward; the ray meets its side after a
// depth advance d with d |dirUv| = r (D - t - d):
//   d = r (D - t) / (|dirUv| + r)              (Listing 18-3; 000 eq. (3): gamma
//                                               = xi / (xi + |Vxy|) with xi = r)
// Alg. 4 writes the same step along the unit direction rd = (dirUv, 1) / |(dirUv, 1)|:
//   s = (D - t) / (|rd_xy| / r + rd_z),  t += s rd_z
// (its iz = sqrt(1 - rd_z^2) is |rd_xy|). The two are equal in exact arithmetic and round
// differently; `cone_step` picks one (0: Listing 18-3, the default; 1: Alg. 4).
//
// Each trip fetches the depth and the ratio at the ray point in ONE fetch: the papers
// store both in one texture (Listing 18-3: depth in A, ratio in B; Dummer likewise), so a
// step is one texture() call and one footprint of texels. The driver hands the kernel the
// decoded ratio (texture/lane_sampler.h SampleHeightConeLanes: squared for the
// dissertation's sqrt encoding, as Alg. 4's GETCONERATIO(p)^2).
//
// csm (Alg. 4): at most cone_steps trips; a trip whose point is inside (t >= D) ends the
// search there (early_exit = 1) or, in fixed loops (early_exit = 0), keeps fetching at
// the latched point as Listing 18-3's saturate() does (d = 0 once inside). The result
// is the ray point where the search stopped; `hit` says whether it is inside.
//
// rcs (Listing 18-3): cone_steps relaxed steps with d from saturate(D - t) (the relaxed
// cone may pierce the surface; a point inside stays where it is), then refine_steps
// binary steps between the half-way point H and the stopping point K: range = tK / 2,
// tb = tK / 2; per step fetch D(tb), halve range, tb += range if tb < D (outside) else
// tb -= range. The result is tb after the last move. Fixed loops by default, as the
// listing: a pixel costs exactly cone_steps + refine_steps fetches. early_exit = 1 ends
// the relaxed loop at the first point inside (the binary search then starts there).
// `hit` is whether the relaxed loop reached a point inside.
//
// Refinement (`--set refine=none|binary|interval|secant|pom`, kernels/refine.h; default
// none, binary for rcs and rcns). The cone loop keeps the bracket: the last point it
// sampled outside (tAbove, hAbove) and the first it sampled inside (tBelow, hBelow),
// else K, the point where it ended. binary: rcs and rcns run Listing 18-3's search
// between H = tK / 2 and K (above), whether or not K is inside; the other cone kernels
// run Alg. 2 back from K over the last cone step (the dissertation adds binary steps
// after CSM, 004 §4.3.1, Tables 4.9-4.13). interval, secant, pom need the depth at both
// bracket ends: a loop that ended outside fetches K once more (as the linear search
// fetches the bottom) and refines only if K is inside; else K is the answer. A hit at
// the first sample is exact (no refinement), except in rcs's listing search.
//
// qcsm, acm4, acm8 (directional cones: QDCSM in 001 §18.1 and 004 §4.3.2; ACM in 000
// §II-B): csm's step with the ratio "indexed by the viewing direction" (000 §II-B). The
// maps hold one ratio per direction class (maps/cone_map.h: quad = the half planes +x,
// -x, +y, -y; acm4 / acm8 = closed 90° / 45° sectors counter-clockwise from +u, in uv
// space). Every ray point after the current one lies along dirUv from it, so a cone that
// is empty over the direction class containing dirUv bounds the step. The class is
// picked per ray in Begin by exact sign comparisons of (du, dv) (no atan2: the GLSL twin
// makes the same choice bit for bit), and the kernel reads that layer of a layered map
// (render/kernel_maps.cpp KernelConeLayers):
//   acm4 / acm8: the lowest-numbered closed sector containing dirUv (layer = sector).
//   qcsm: the open half planes containing dirUv: both of a quadrant when du, dv != 0
//     (layers 0..3 hold max(+x, +y), max(-x, +y), max(-x, -y), max(+x, -y): either
//     half-plane cone is empty along the ray, so the wider one bounds it), one when the
//     ray is axis-aligned (layers 4..7: +x, +y, -x, -y). A vertical ray (dirUv = 0)
//     reads layer 4; its step is D - t for any ratio > 0.
// One fetch per trip returns the depth and the ray's ratio, as for csm (one layered
// texture of (depth, ratio) pairs, texture(sampler2DArray, (uv, layer)) on the twin).
// The papers' storage (000 §II-D: ratios in RGBA, acm8 as two RGBA halves, the depth
// elsewhere) costs two (acm8: three) texture calls per trip; docs/methods/acm4.md says
// how to convert.
//
// cns, rcns (cone normal stepping, 004 ch. 3): csm and rcs with the cone stored as the
// z component n_z of the unit normal of its side (§3.1; maps --kind cone-normal, n_z =
// r / sqrt(1 + r^2), so n_z = 1 is a cone of 180°, which csm's ratio cannot store). The
// step is eq. 3.2, t = -h n_z / (n . d): the side's plane passes through the apex, the
// ray point lies h = D - t above it, n = (-sqrt(1 - n_z^2) s, n_z) with s the unit
// horizontal direction of the ray, and d the ray direction. With d = (dirUv, -1) per
// unit of depth (z up) that is
//   d = (D - t) n_z / (sqrt(1 - n_z^2) |dirUv| + n_z)        (cone_step = 0)
// and along the unit direction rd as Alg. 4 (cone_step = 1)
//   s = (D - t) n_z / (sqrt(1 - n_z^2) |rd_xy| + n_z rd_z),  d = s rd_z.
// In exact arithmetic this is csm's step with r = n_z / sqrt(1 - n_z^2); the stored
// value, its quantisation and its rounding differ. rcns reads the relaxed cones' n_z
// (maps
// --kind cone-normal --relaxed) and keeps rcs's binary search. The distance estimate
// h n_z of eq. 3.1 is what the cone-normal soft shadows and AO read (not here: view rays
// only).
//
// mcns (multiple cone normal stepping, 004 §3.4 method 1, Table 4.13): cns with K = 4
// cones stacked over each texel (maps --kind stacked --normal): cone k has its apex at
// depth a_k = D (K - k) / K (k = 0: the surface point, cns's cone) and stores n_z of
// its side. "The cone that will lead to the largest step" is taken: each cone whose
// apex lies below the ray point (t < a_k) gives eq. 3.2's step with h = a_k - t, and
// the largest is kept. One fetch per trip returns the depth and all K values (the twin
// reads the K layers of the (depth, n_z) array: K texture calls per trip).
#pragma once

#include <array>
#include <cmath>

#include "kernels/kernel.h"
#include "kernels/refine.h"

namespace reliefsim {

namespace detail {

inline constexpr ParamSpec ConeSteps(double def) {
    return {"cone_steps", def, 1, 1024, true, "cone steps (coarse iterations)",
            "uConeSteps"};
}
inline constexpr ParamSpec kConeStepForm = {
    "cone_step",
    0,
    0,
    1,
    true,
    "step formula: 0 = r (D - t) / (|dirUv| + r) (Listing 18-3); 1 = Alg. 4's unit-ray "
    "form",
    "uConeStepForm"};
inline constexpr std::array<std::string_view, 3> kMinStepChoices = {"none", "texel",
                                                                    "cell"};
inline constexpr ParamSpec kMinStepParam = {
    "min_step",
    0,
    0,
    2,
    true,
    "least cone step: none; texel (Dummer: 1/width along the unit ray); cell (Ban et al. "
    "2024: to the next bilinear cell border)",
    "uMinStep",
    kMinStepChoices};
inline constexpr std::array<std::string_view, 1> kConeMaps = {"cone"};
// The dissertation follows its cone searches with 5 binary steps (004 Tables 4.9-4.13).
inline constexpr std::array<ParamSpec, 9> kConeParams = {
    ConeSteps(15),
    RefineParam(Refinement::None),
    RefineSteps(5, "refinement iterations after the cone steps"),
    kSecantTolerance,
    kConeStepForm,
    kConeFilterParam,
    kMinStepParam,
    kEarlyExitParam,
    kBudgetParam};
inline constexpr std::array<std::string_view, 1> kRelaxedMaps = {"relaxed"};

/// The cone kernels of one source: the step is csm's, the map and its reading differ.
enum class ConeFamily {
    Conservative,
    Relaxed,
    Quad,
    Acm4,
    Acm8,
    ConeNormal,
    RelaxedNormal,
    StackedNormal
};

template <ConeFamily kF>
struct ConeStepPreset;
template <>
struct ConeStepPreset<ConeFamily::Conservative> {
    static constexpr std::string_view kName = "csm", kTitle = "cone step mapping",
                                      kSource =
                                          "Burger 2018 (004) Alg. 4; Dummer 2006; Chen & "
                                          "Chuang 2009 (000) §II-A";
    static constexpr auto& kParams = kConeParams;
    static constexpr auto& kMaps = kConeMaps;
    static constexpr std::string_view kEncoding = "u8sqrt";  // Dummer; 004 §2.4
};
inline constexpr ParamSpec kEarlyExitFixed = {
    "early_exit",
    0,
    0,
    1,
    true,
    "1: leave the cone loop at the first point inside; 0: fixed loops as Listing 18-3",
    "uEarlyExit"};
template <>
struct ConeStepPreset<ConeFamily::Relaxed> {
    static constexpr std::string_view
        kName = "rcs",
        kTitle = "relaxed cone stepping + binary search",
        kSource = "Policarpo & Oliveira, GPU Gems 3 ch. 18 (001) Listing 18-3";
    static constexpr std::array<ParamSpec, 9> kParams = {
        ConeSteps(15),
        RefineParam(Refinement::Binary),
        RefineSteps(6, "refinement iterations (Listing 18-3: binary_steps = 6)"),
        kSecantTolerance,
        kConeStepForm,
        kConeFilterParam,
        kMinStepParam,
        kEarlyExitFixed,
        kBudgetParam};
    static constexpr auto& kMaps = kRelaxedMaps;
    static constexpr std::string_view kEncoding = "u8";  // GPU Gems 3: ratio in B, 8 bit
};
inline constexpr std::array<std::string_view, 1> kQuadMaps = {"quad"};
inline constexpr std::array<std::string_view, 1> kAcm4Maps = {"acm4"};
inline constexpr std::array<std::string_view, 1> kAcm8Maps = {"acm8"};
inline constexpr auto& kDirectionalParams = kConeParams;
template <>
struct ConeStepPreset<ConeFamily::Quad> {
    static constexpr std::string_view
        kName = "qcsm",
        kTitle = "quad-directional cone step mapping",
        kSource = "Policarpo & Oliveira (001) §18.1 QDCSM; Burger 2018 (004) §4.3.2";
    static constexpr auto& kParams = kDirectionalParams;
    static constexpr auto& kMaps = kQuadMaps;
    // 004 measures QCSM next to its CSM (Table 4.8), whose ratios are sqrt-encoded.
    static constexpr std::string_view kEncoding = "u8sqrt";
};
template <>
struct ConeStepPreset<ConeFamily::Acm4> {
    static constexpr std::string_view kName = "acm4",
                                      kTitle = "anisotropic cone mapping, 4 sectors",
                                      kSource = "Chen & Chuang 2009 (000) §II-B, §II-D";
    static constexpr auto& kParams = kDirectionalParams;
    static constexpr auto& kMaps = kAcm4Maps;
    static constexpr std::string_view kEncoding = "u8";  // 000 §II-D: an RGBA texture
};
template <>
struct ConeStepPreset<ConeFamily::Acm8> {
    static constexpr std::string_view kName = "acm8",
                                      kTitle = "anisotropic cone mapping, 8 sectors",
                                      kSource = "Chen & Chuang 2009 (000) §II-B, §II-D";
    static constexpr auto& kParams = kDirectionalParams;
    static constexpr auto& kMaps = kAcm8Maps;
    static constexpr std::string_view kEncoding = "u8";  // 000 §II-D: two RGBA halves
};

inline constexpr std::array<std::string_view, 1> kConeNormalMaps = {"cone-normal"};
inline constexpr std::array<std::string_view, 1> kRelaxedNormalMaps = {
    "cone-normal --relaxed"};
template <>
struct ConeStepPreset<ConeFamily::ConeNormal> {
    static constexpr std::string_view kName = "cns", kTitle = "cone normal stepping",
                                      kSource = "Burger 2018 (004) §3.1-3.3, eq. 3.2";
    static constexpr auto& kParams = kDirectionalParams;
    static constexpr auto& kMaps = kConeNormalMaps;
    // 004 does not say how n_z is stored; n_z is in [0, 1], stored linearly in 8 bits.
    static constexpr std::string_view kEncoding = "u8";
};
template <>
struct ConeStepPreset<ConeFamily::RelaxedNormal> {
    static constexpr std::string_view
        kName = "rcns",
        kTitle = "relaxed cone normal stepping + binary search",
        kSource = "Burger 2018 (004) §3.3 eq. 3.2, §4.3.4; GPU Gems 3 (001) Listing 18-3";
    static constexpr auto& kParams = ConeStepPreset<ConeFamily::Relaxed>::kParams;
    static constexpr auto& kMaps = kRelaxedNormalMaps;
    static constexpr std::string_view kEncoding = "u8";
};

inline constexpr std::array<std::string_view, 1> kStackedNormalMaps = {
    "stacked --normal"};
template <>
struct ConeStepPreset<ConeFamily::StackedNormal> {
    static constexpr std::string_view
        kName = "mcns",
        kTitle = "multiple cone normal stepping (4 stacked cones)",
        kSource = "Burger 2018 (004) §3.4 method 1, eq. 3.2, Table 4.13";
    static constexpr auto& kParams = kDirectionalParams;
    static constexpr auto& kMaps = kStackedNormalMaps;
    static constexpr std::string_view kEncoding = "u8";  // as cns
};

/// Layers of the family's map as the kernel reads it.
constexpr int ConeFamilyLayers(ConeFamily f) {
    return f == ConeFamily::Quad            ? 8
           : f == ConeFamily::Acm4          ? 4
           : f == ConeFamily::Acm8          ? 8
           : f == ConeFamily::StackedNormal ? kMaxStackedCones
                                            : 1;
}

/// The layer a ray with direction (du, dv) reads (see the file comment). Exact
/// comparisons only, in the order the twin makes them (kernels/glsl/cone_step.glsl).
template <ConeFamily kF, class F>
RS_INLINE F ConeLayerOf(const F& du, const F& dv) {
    const F zero(0.0f);
    auto pick = [](const auto& cond, float k, const F& rest) {
        return Select(cond, F(k), rest);
    };
    if constexpr (kF == ConeFamily::Acm4) {
        // Closed quadrant k holds dirUv when cross(a_k, v) >= 0 and cross(v, a_k+1) >= 0.
        F layer(3.0f);
        layer = pick((du <= zero) && (dv <= zero), 2.0f, layer);
        layer = pick((du <= zero) && (dv >= zero), 1.0f, layer);
        return pick((du >= zero) && (dv >= zero), 0.0f, layer);
    } else if constexpr (kF == ConeFamily::Acm8) {
        // Closed 45° sectors bounded by (1,0), (1,1), (0,1), (-1,1), ... (uv space).
        F layer(7.0f);  // dv >= -du, dv <= 0
        layer = pick((du >= zero) && (dv <= -du), 6.0f, layer);
        layer = pick((du <= zero) && (du >= dv), 5.0f, layer);
        layer = pick((dv <= zero) && (dv >= du), 4.0f, layer);
        layer = pick((dv >= zero) && (-du >= dv), 3.0f, layer);
        layer = pick((du <= zero) && (dv >= -du), 2.0f, layer);
        layer = pick((du >= zero) && (dv >= du), 1.0f, layer);
        return pick((dv >= zero) && (du >= dv), 0.0f, layer);
    } else if constexpr (kF == ConeFamily::Quad) {
        F layer(4.0f);  // +x, and the vertical ray
        layer = pick((du == zero) && (dv < zero), 7.0f, layer);
        layer = pick((du < zero) && (dv == zero), 6.0f, layer);
        layer = pick((du == zero) && (dv > zero), 5.0f, layer);
        layer = pick((du > zero) && (dv < zero), 3.0f, layer);
        layer = pick((du < zero) && (dv < zero), 2.0f, layer);
        layer = pick((du < zero) && (dv > zero), 1.0f, layer);
        return pick((du > zero) && (dv > zero), 0.0f, layer);
    } else {
        return zero;
    }
}

}  // namespace detail

template <detail::ConeFamily kFamily>
struct ConeStep {
    using Preset = detail::ConeStepPreset<kFamily>;
    static constexpr bool kRelaxed = kFamily == detail::ConeFamily::Relaxed ||
                                     kFamily == detail::ConeFamily::RelaxedNormal;
    /// The map stores n_z of the cone side's normal (cns, rcns), not the ratio.
    static constexpr bool kNormal = kFamily == detail::ConeFamily::ConeNormal ||
                                    kFamily == detail::ConeFamily::RelaxedNormal ||
                                    kFamily == detail::ConeFamily::StackedNormal;
    /// Every fetch reads all stacked cones (mcns).
    static constexpr bool kReadsAllLayers = kFamily == detail::ConeFamily::StackedNormal;
    static constexpr bool kReadsRatio = true;
    /// A march that stopped above the surface answers its last point
    /// (KernelAnswersAtStop; `hit` stays false and the record flags it kFlagNoHit).
    static constexpr bool kAnswersAtStop = true;
    static constexpr int kConeLayers = detail::ConeFamilyLayers(kFamily);
    static constexpr std::array<GlslConstant, 2> kGlslConstants = {
        GlslConstant{"uRelaxed", kRelaxed ? 1 : 0},
        GlslConstant{"uConeFamily", int(kFamily)}};

    static const KernelInfo& Info() {
        static const KernelInfo info{Preset::kName,   Preset::kTitle,    Preset::kSource,
                                     Preset::kParams, Preset::kMaps,     "cone_step.glsl",
                                     kGlslConstants,  Preset::kEncoding, kConeLayers,
                                     kAnswersAtStop};
        return info;
    }

    struct Params {
        int coneSteps = 15;
        Refinement refine = Refinement::None;
        int refineSteps = 0;
        float secantTolerance = 0.01f;
        int minStep = 0;  ///< 0 none, 1 texel, 2 cell (kMinStepChoices)
        bool unitRayForm = false;
        bool earlyExit = true;
    };
    static Params FromValues(const ParamValues& v) {
        auto get = [&](std::string_view name) {
            return ParamValue(v, Preset::kParams, name);
        };
        Params p;
        p.coneSteps = int(get("cone_steps"));
        p.refine = Refinement(int(get("refine")));
        p.refineSteps = int(get("refine_steps"));
        p.secantTolerance = float(get("secant_tolerance"));
        p.minStep = int(get("min_step"));
        p.unitRayForm = get("cone_step") != 0.0;
        p.earlyExit = get("early_exit") != 0.0;
        return p;
    }

    enum Phase { kCone = 0, kBottom = 1, kRefine = 2, kDone = 3 };

    template <class L>
    struct State {
        using F = typename L::F;
        F t;                 // the cone loop's ray depth
        F rayRatio;          // |dirUv| (Listing 18-3's ray_ratio)
        F rdXy, rdZ;         // Alg. 4's |rd_xy| and rd_z
        F nCoarse, nRefine;  // the loops' counters
        F tAbove, hAbove;    // the last point sampled outside
        F tBelow, hBelow;    // the first point sampled inside (or where the loop ended)
        Refiner<L> q;
        F tResult;  // the point returned if the lane stops now (after the cone loop)
        F phase;
        typename L::M inside;     // the cone loop reached a point inside
        typename L::M haveAbove;  // it sampled a point outside
    };

    template <class L>
    static void Begin(const Params&, const LaneRay<L>& ray, State<L>& s,
                      Fetch<L>& first) {
        using F = typename L::F;
        const F zero(0.0f);
        s.t = s.nCoarse = s.nRefine = zero;
        s.tAbove = s.hAbove = s.tBelow = s.hBelow = s.tResult = zero;
        s.q.Clear();
        s.haveAbove = typename L::M(false);
        const F sq = ray.du * ray.du + ray.dv * ray.dv;
        s.rayRatio = stdx::sqrt(sq);
        const F len = stdx::sqrt(sq + F(1.0f));
        s.rdXy = s.rayRatio / len;
        s.rdZ = F(1.0f) / len;
        s.phase = F(float(kCone));
        s.inside = typename L::M(false);
        first.t = zero;
        first.u = ray.U(zero);
        first.v = ray.V(zero);
        if constexpr (kConeLayers > 1 && !kReadsAllLayers)
            first.layer = stdx::static_simd_cast<typename L::I>(
                detail::ConeLayerOf<kFamily>(ray.du, ray.dv));
    }

    /// The cone step's depth advance from t over depth h with ratio r, or n_z for the
    /// cone-normal kernels (>= 0 when t < h).
    template <class F>
    RS_INLINE static F Advance(const Params& p, const F& t, const F& h, const F& r,
                               const F& rayRatio, const F& rdXy, const F& rdZ) {
        if constexpr (kNormal) {  // eq. 3.2; r is n_z here
            const F nXy = stdx::sqrt(F(1.0f) - r * r);
            if (p.unitRayForm) {
                const F s = ((h - t) * r) / (nXy * rdXy + r * rdZ);
                return s * rdZ;
            }
            return ((h - t) * r) / (nXy * rayRatio + r);
        }
        if (p.unitRayForm) {
            const F s = (h - t) / (rdXy / r + rdZ);
            return s * rdZ;
        }
        return (r * (h - t)) / (rayRatio + r);
    }

    /// The least cone step (min_step), in depth, from the ray point at s.t, never past
    /// the bottom: texel, Dummer's 1/width along the unit ray (rd_z / W); cell, Ban et
    /// al. 2024's step to the next border of the bilinear cell (the grid through the
    /// texel centres) the ray crosses first, plus 1e-5 along the unit ray so the next
    /// fetch lies in the next cell. A vertical ray has no border to reach: no least step.
    template <class L>
    RS_INLINE static typename L::F LeastStep(const Params& p, const LaneRay<L>& ray,
                                             const State<L>& s) {
        using F = typename L::F;
        const F zero(0.0f), one(1.0f);
        F least;
        if (p.minStep == 1) {
            least = s.rdZ / F(ray.mapW);
        } else {
            const F x = ray.U(s.t) * F(ray.mapW) - F(0.5f);
            const F y = ray.V(s.t) * F(ray.mapH) - F(0.5f);
            const F fx = stdx::floor(x), fy = stdx::floor(y);
            const F wx = Select(ray.du > zero, fx + one, fx);
            const F wy = Select(ray.dv > zero, fy + one, fy);
            const F none(3.0e38f);
            const F tx = Select(ray.du != zero, (wx - x) / (ray.du * F(ray.mapW)), none);
            const F ty = Select(ray.dv != zero, (wy - y) / (ray.dv * F(ray.mapH)), none);
            const F cell = Select(tx < ty, tx, ty);
            least = Select(cell < none, cell + F(1e-5f) * s.rdZ, zero);
        }
        const F room = one - s.t;
        return Select(least > room, room, least);
    }

    template <class L>
    RS_INLINE static typename L::M Step(const Params& p, const LaneRay<L>& ray,
                                        State<L>& s, const Sample<L>& x,
                                        const typename L::M& active, Fetch<L>& next) {
        using F = typename L::F;
        using M = typename L::M;
        const F one(1.0f), zero(0.0f);
        const Refinement rf = p.refine;
        M want(false), startRefine(false), refineNext(false);
        F tq = next.t, segment = zero;
        const M cone = active && (s.phase == F(float(kCone)));
        const M bottom = active && (s.phase == F(float(kBottom)));
        const M refine = active && (s.phase == F(float(kRefine)));
        if (Any(cone)) {
            Assign(cone, s.nCoarse, s.nCoarse + one);
            const M in = cone && (s.t >= x.h);
            const M firstIn = in && !s.inside;
            Assign(firstIn, s.tBelow, s.t);
            Assign(firstIn, s.hBelow, x.h);
            s.inside = s.inside || in;
            // Outside: step along the cone (r = 0 advances nothing: the ray stalls, as
            // the method does at a zero ratio). Inside: stay (saturate(D - t) = 0).
            const M out = cone && !in;
            Assign(out, s.tAbove, s.t);
            Assign(out, s.hAbove, x.h);
            s.haveAbove = s.haveAbove || out;
            // (x.h - t) > 0 where out; the advance is computed on every lane and kept
            // where out, so a lane inside never divides by a zero ratio's result.
            F d = Advance(p, s.t, x.h, x.ratio, s.rayRatio, s.rdXy, s.rdZ);
            if constexpr (kReadsAllLayers) {
                // The stacked cones above the surface: the largest step of those whose
                // apex a_k lies below the ray point (same order and tests as the twin).
                for (int k = 1; k < kConeLayers; ++k) {
                    const F apex = x.h * F(float(kConeLayers - k) / float(kConeLayers));
                    const F dk = Advance(p, s.t, apex, x.stack[size_t(k)], s.rayRatio,
                                         s.rdXy, s.rdZ);
                    Assign((s.t < apex) && (dk > d), d, dk);
                }
            }
            if (p.minStep != 0) {
                const F least = LeastStep(p, ray, s);
                Assign(d < least, d, least);
            }
            Assign(out && (d > zero), s.t, s.t + d);
            const M stopEarly = p.earlyExit ? in : M(false);
            const M last = cone && (s.nCoarse >= F(float(p.coneSteps)));
            const M stop = (cone && stopEarly) || last;
            const M more = cone && !stop;
            Assign(more, tq, s.t);
            want = want || more;
            if (Any(stop)) {
                // The bracket's inner end: the first point inside, else where the loop
                // ended (not sampled).
                Assign(stop && !s.inside, s.tBelow, s.t);
                Assign(stop, s.tResult, s.t);
                Assign(stop, s.phase, F(float(kDone)));
                if (rf == Refinement::Binary) {
                    // rcs: Listing 18-3's search between H = tK / 2 and K, run whether
                    // or not K is inside. The others: Alg. 2 back from K over the last
                    // cone step (a hit at the first sample is exact).
                    startRefine = kRelaxed ? stop : stop && s.haveAbove;
                    segment = kRelaxed ? s.tBelow : s.tBelow - s.tAbove;
                } else if (rf != Refinement::None) {
                    // The chord needs the depth at both ends: fetch K when the loop
                    // ended outside (a conservative search ends short of the surface).
                    startRefine = stop && s.inside && s.haveAbove;
                    const M fetchEnd = stop && !s.inside;
                    Assign(fetchEnd, tq, s.t);
                    Assign(fetchEnd, s.phase, F(float(kBottom)));
                    want = want || fetchEnd;
                }
            }
        }
        if (Any(bottom)) {  // K sampled: refine if it is inside, else K is the answer
            const M cross = bottom && (s.t >= x.h);
            Assign(cross, s.hBelow, x.h);
            Assign(bottom, s.phase, F(float(kDone)));
            startRefine = startRefine || cross;
        }
        if (Any(refine)) {  // consume a refinement sample
            Assign(refine, s.nRefine, s.nRefine + one);
            s.q.Consume(rf, refine, x.h, p.secantTolerance);
            refineNext = refine;
        }
        if (Any(startRefine)) {
            const M loop = s.q.Start(rf, startRefine, s.tAbove, s.hAbove, s.tBelow,
                                     s.hBelow, segment, s.tResult, s.nRefine);
            refineNext = refineNext || loop;
        }
        if (Any(refineNext)) {  // the top of the refinement loop
            Assign(refineNext, s.phase, F(float(kDone)));
            const M go = s.q.Next(rf, refineNext, s.nRefine, p.refineSteps, p.earlyExit,
                                  s.tResult, tq);
            Assign(go, s.phase, F(float(kRefine)));
            want = want || go;
        }
        next.t = tq;
        next.u = ray.U(tq);
        next.v = ray.V(tq);
        return want;
    }

    template <class L>
    static void End(const Params&, const LaneRay<L>& ray, const State<L>& s,
                    LaneOutcome<L>& out) {
        using F = typename L::F;
        // A lane the budget stopped in the cone loop answers its current point; after
        // it, the point the refinement (if any) answers.
        const F tResult = Select(s.phase == F(float(kCone)), s.t, s.tResult);
        out.u = ray.U(tResult);
        out.v = ray.V(tResult);
        out.depth = tResult;
        out.nCoarse = s.nCoarse;
        out.nRefine = s.nRefine;
        out.hit = s.inside;
    }
};

using CsmKernel = ConeStep<detail::ConeFamily::Conservative>;
using RcsKernel = ConeStep<detail::ConeFamily::Relaxed>;
using QcsmKernel = ConeStep<detail::ConeFamily::Quad>;
using Acm4Kernel = ConeStep<detail::ConeFamily::Acm4>;
using Acm8Kernel = ConeStep<detail::ConeFamily::Acm8>;
using CnsKernel = ConeStep<detail::ConeFamily::ConeNormal>;
using RcnsKernel = ConeStep<detail::ConeFamily::RelaxedNormal>;
using McnsKernel = ConeStep<detail::ConeFamily::StackedNormal>;

}  // namespace reliefsim
