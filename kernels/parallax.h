// Parallax mapping (Kaneko et al. 2001; dissertation 004 eq. 2.3-2.5) and parallax
// mapping with offset limiting (Welsh 2004; 004 eq. 2.6): one fetch at the entry point,
// no search.
//
// In the ray parameters of DESIGN.md (p(t) = uvEntry + t * dirUv, t the ray's depth) the
// paper's t = h_sb / d_z (eq. 2.3) is the ray depth t = D(uvEntry): the point where the
// ray meets the plane parallel to the polygon at the fetched depth, so eq. 2.5 is
//   uv = uvEntry + D * dirUv.
// Eq. 2.6 drops the division by d_z of the unit view direction d: the offset is
// h_sb * d_xy = D * dirUv * |d_z|, the ray point at t = D * |d_z| (MarchInput::viewZ).
// At normal incidence both equal the fetched depth; at grazing angles the offset-limited
// point stays within D * depthScale of the entry (in plane units).
//
// Counting: one fetch and one coarse iteration (the single evaluation); no refinement.
// `hit` is always true: the method assumes the plane it intersects. The GLSL twin is
// kernels/glsl/parallax.glsl.
#pragma once

#include <array>

#include "kernels/kernel.h"

namespace reliefsim {

namespace detail {

template <bool kLimit>
struct ParallaxPreset;
template <>
struct ParallaxPreset<false> {
    static constexpr std::string_view kName = "parallax",
                                      kTitle = "parallax mapping (one fetch, no search)",
                                      kSource =
                                          "Burger 2018 (004) eq. 2.3-2.5; Kaneko et al. "
                                          "2001";
};
template <>
struct ParallaxPreset<true> {
    static constexpr std::string_view kName = "offset-limit",
                                      kTitle = "parallax mapping with offset limiting",
                                      kSource = "Burger 2018 (004) eq. 2.6; Welsh 2004";
};

}  // namespace detail

template <bool kLimit>
struct Parallax {
    using Preset = detail::ParallaxPreset<kLimit>;
    // early_exit is accepted for symmetry with every kernel (a single fetch has nothing
    // to break out of); budget >= 1 always allows the one fetch.
    static constexpr std::array<ParamSpec, 2> kParams = {kEarlyExitParam, kBudgetParam};
    static constexpr std::array<GlslConstant, 1> kGlslConstants = {
        GlslConstant{"uOffsetLimit", kLimit ? 1 : 0}};

    static const KernelInfo& Info() {
        static const KernelInfo info{Preset::kName,
                                     Preset::kTitle,
                                     Preset::kSource,
                                     kParams,
                                     {},
                                     "parallax.glsl",
                                     kGlslConstants,
                                     ""};
        return info;
    }

    struct Params {};
    static Params FromValues(const ParamValues&) { return {}; }

    template <class L>
    struct State {
        typename L::F tResult;
    };

    template <class L>
    static void Begin(const Params&, const LaneRay<L>& ray, State<L>& s,
                      Fetch<L>& first) {
        using F = typename L::F;
        s.tResult = F(0.0f);
        first.t = F(0.0f);
        first.u = ray.U(F(0.0f));
        first.v = ray.V(F(0.0f));
    }

    template <class L>
    RS_INLINE static typename L::M Step(const Params&, const LaneRay<L>& ray, State<L>& s,
                                        const Sample<L>& x, const typename L::M& active,
                                        Fetch<L>&) {
        const typename L::F& h = x.h;
        if constexpr (kLimit)
            Assign(active, s.tResult, h * ray.viewZ);  // eq. 2.6
        else
            Assign(active, s.tResult, h);  // eq. 2.3
        return typename L::M(false);
    }

    template <class L>
    static void End(const Params&, const LaneRay<L>& ray, const State<L>& s,
                    LaneOutcome<L>& out) {
        using F = typename L::F;
        out.u = ray.U(s.tResult);
        out.v = ray.V(s.tResult);
        out.depth = s.tResult;
        out.nCoarse = F(1.0f);
        out.nRefine = F(0.0f);
        out.hit = typename L::M(true);
    }
};

using ParallaxKernel = Parallax<false>;
using OffsetLimitKernel = Parallax<true>;

}  // namespace reliefsim
