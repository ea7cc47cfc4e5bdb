// Linear search (dissertation Alg. 1) followed by a refinement (kernels/refine.h): none,
// binary (Alg. 2, Policarpo relief mapping), interval (Alg. 3), iterated secant (Risser
// et al. 2007, listing), or one secant step without a fetch (Tatarchuk's parallax
// occlusion mapping). Five methods, one source: LinearSearch<R> is the preset whose
// default `refine` is R; every preset takes every refinement (`--set refine=...`).
//
// Conventions (DESIGN.md): p(t) = (uvEntry + t * dirUv, t); the ray is inside the relief
// where t >= depth(uv).
//
// Shape (kernels/kernel.h): one fetch per trip; Step consumes the sample and decides the
// next fetch, a state machine coarse -> bottom fetch -> refine, written over lanes with
// masks. kernels/glsl/linear_search.glsl is the same step, line for line.
//
// Where the papers are ambiguous, this file decides (docs/kernels.md explains each):
//  * Alg. 2 as printed flips the sign of s twice when two consecutive points are below
//    the surface; the step is applied as a magnitude: t -= |s|/2 when below, t += |s|/2
//    when above (what Policarpo's shader does). Its step is the linear step.
//  * Alg. 3 as printed assigns a point below the surface to p1, the point "before" the
//    intersection; here the new point replaces the bracket end on its own side.
//  * Refinements reuse the two samples the linear search already took around the
//    crossing (as the POM and secant listings do); only when the linear search found no
//    hit is the bracket's lower end (t = 1, the bottom) fetched.
//  * A hit at the very first sample (t = 0) is exact (the surface is at the top there),
//    so no refinement runs.
//  * early_exit = false runs every loop for its full count, as a GPU with uniform control
//    flow would, with the result latched at the point where the break would have
//    happened.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "kernels/kernel.h"
#include "kernels/refine.h"

namespace reliefsim {

namespace detail {

inline constexpr ParamSpec kLinearSteps = {
    "linear_steps", 32, 1, 1024, true, "linear-search steps over the full depth",
    "uLinearSteps"};

/// The catalogue entries of the five presets (name, title, source, default refinement).
/// Every preset takes every refinement (`refine`); they differ in their defaults.
template <Refinement R>
struct LinearSearchPreset;
template <>
struct LinearSearchPreset<Refinement::None> {
    static constexpr std::string_view kName = "linear",
                                      kTitle = "linear search (steep parallax mapping)",
                                      kSource = "Burger 2018 (004) Alg. 1; McGuire 2005";
    static constexpr double kRefineSteps = 6;
};
template <>
struct LinearSearchPreset<Refinement::Binary> {
    static constexpr std::string_view
        kName = "relief",
        kTitle = "linear search + binary search (relief mapping)",
        kSource = "Burger 2018 (004) Alg. 1 + Alg. 2; Policarpo & Oliveira (001)";
    static constexpr double kRefineSteps = 6;
};
template <>
struct LinearSearchPreset<Refinement::Secant> {
    static constexpr std::string_view
        kName = "secant",
        kTitle = "linear search + iterated secant",
        kSource = "Risser, Shah & Pattanaik 2007 (003) section 3 and listing";
    static constexpr double kRefineSteps = 10;
};
template <>
struct LinearSearchPreset<Refinement::Interval> {
    static constexpr std::string_view
        kName = "interval",
        kTitle = "linear search + interval search",
        kSource = "Burger 2018 (004) Alg. 1 + Alg. 3; Risser et al. interval mapping";
    static constexpr double kRefineSteps = 6;
};
template <>
struct LinearSearchPreset<Refinement::Pom> {
    static constexpr std::string_view
        kName = "pom",
        kTitle = "linear search + one secant step (parallax occlusion mapping)",
        kSource = "Tatarchuk 2006, as described in Risser et al. 2007 (003) section 2";
    static constexpr double kRefineSteps = 6;
};

template <Refinement R>
inline constexpr std::array<ParamSpec, 6> kLinearSearchParams = {
    kLinearSteps,
    RefineParam(R),
    RefineSteps(LinearSearchPreset<R>::kRefineSteps,
                "refinement iterations (secant: at most; pom: none)"),
    kSecantTolerance,
    kEarlyExitParam,
    kBudgetParam};

}  // namespace detail

template <Refinement R>
struct LinearSearch {
    using Preset = detail::LinearSearchPreset<R>;
    static constexpr auto& kParams = detail::kLinearSearchParams<R>;

    static const KernelInfo& Info() {
        static const KernelInfo info{Preset::kName,
                                     Preset::kTitle,
                                     Preset::kSource,
                                     kParams,
                                     {},
                                     "linear_search.glsl",
                                     {},
                                     ""};
        return info;
    }

    struct Params {
        int linearSteps = 32;   ///< coarse steps over t in [0,1]; step = 1/linearSteps
        Refinement refine = R;  ///< the refinement after the linear search
        int refineSteps = 0;    ///< refinement iterations (ignored by None and Pom)
        bool earlyExit = true;  ///< break out of loops (false: GPU-style fixed loops)
        float secantTolerance = 0.01f;  ///< Risser's |h - z| stop test (listing: 0.01)
    };
    static Params FromValues(const ParamValues& v) {
        Params p;
        auto get = [&](std::string_view name) { return ParamValue(v, kParams, name); };
        p.linearSteps = int(get("linear_steps"));
        p.refine = Refinement(int(get("refine")));
        p.refineSteps = int(get("refine_steps"));
        p.earlyExit = get("early_exit") != 0.0;
        p.secantTolerance = float(get("secant_tolerance"));
        return p;
    }

    enum Phase { kCoarse = 0, kBottom = 1, kRefine = 2, kDone = 3 };

    template <class L>
    struct State {
        using F = typename L::F;
        using M = typename L::M;
        F t, tAbove, hAbove, tBelow, hBelow;  // coarse search
        M haveAbove, found;
        // The loop counters of Alg. 1-3 are the iteration counts: the coarse loop's i
        // equals nCoarse whenever it is tested, the refinement loop's k equals nRefine.
        F nCoarse, nRefine;
        Refiner<L> q;
        F tResult;  // the point returned if the lane stops now
        F phase;
    };

    template <class L>
    static void Begin(const Params&, const LaneRay<L>& ray, State<L>& s,
                      Fetch<L>& first) {
        using F = typename L::F;
        using M = typename L::M;
        const F zero(0.0f);
        s.t = s.tAbove = s.hAbove = s.tBelow = s.hBelow = zero;
        s.haveAbove = s.found = M(false);
        s.nCoarse = s.nRefine = s.tResult = zero;
        s.q.Clear();
        s.phase = F(float(kCoarse));
        first.t = zero;
        first.u = ray.U(zero);
        first.v = ray.V(zero);
    }

    template <class L>
    RS_INLINE static typename L::M Step(const Params& p, const LaneRay<L>& ray,
                                        State<L>& s, const Sample<L>& x,
                                        const typename L::M& active, Fetch<L>& next) {
        using F = typename L::F;
        const F& h = x.h;
        using M = typename L::M;
        const F one(1.0f);
        const F stepSize = one / F(float(p.linearSteps));
        const Refinement r = p.refine;
        M startRefine(false), refineNext(false), want(false);
        F tq = next.t;
        // The phase each lane was in when it fetched (a lane changes phase at most once
        // per trip, below).
        const M coarse = active && (s.phase == F(float(kCoarse)));
        const M inBottom = active && (s.phase == F(float(kBottom)));
        const M inRefine = active && (s.phase == F(float(kRefine)));

        // Coarse: Alg. 1, one trip per sample.
        if (Any(coarse)) {
            Assign(coarse, s.nCoarse, s.nCoarse + one);
            const M open = coarse && !s.found;
            const M below = open && (s.t >= h);
            const M above = open && !(s.t >= h);
            Assign(below, s.tBelow, s.t);
            Assign(below, s.hBelow, h);
            s.found = s.found || below;
            Assign(above, s.tAbove, s.t);
            Assign(above, s.hAbove, h);
            s.haveAbove = s.haveAbove || above;
            const M stopEarly = p.earlyExit ? below : M(false);
            const M go = coarse && !stopEarly;
            Assign(go, s.t, s.t + stepSize);
            const M last = go && (s.nCoarse >= F(float(p.linearSteps)));
            const M more = go && !last;
            // A lane the budget refuses here answers the crossing found or where it is:
            // End() sets that for lanes still in kCoarse.
            Assign(more, tq, s.t);
            want = want || more;
            const M stop = (coarse && stopEarly) || last;
            if (Any(stop)) {
                Assign(stop && !s.found, s.tBelow,
                       s.t);  // the bottom, after linearSteps steps
                Assign(stop, s.tResult, s.tBelow);
                Assign(stop, s.phase, F(float(kDone)));
                if (r != Refinement::None) {
                    const M refine = stop && s.haveAbove;
                    if (r == Refinement::Binary) {
                        startRefine = refine;
                    } else {
                        const M bottom =
                            refine && !s.found;  // fetch the bracket's lower end
                        Assign(bottom, tq, s.tBelow);
                        Assign(bottom, s.phase, F(float(kBottom)));
                        want = want || bottom;
                        startRefine = refine && s.found;
                    }
                }
            }
        }
        if (Any(inBottom)) {  // never with none or binary
            Assign(inBottom, s.hBelow, h);
            startRefine = startRefine || inBottom;
        }
        if (Any(inRefine)) {  // consume a refinement sample
            Assign(inRefine, s.nRefine, s.nRefine + one);
            s.q.Consume(r, inRefine, h, p.secantTolerance);
            refineNext = inRefine;
        }
        if (Any(startRefine)) {
            const M loop = s.q.Start(r, startRefine, s.tAbove, s.hAbove, s.tBelow,
                                     s.hBelow, stepSize, s.tResult, s.nRefine);
            Assign(startRefine, s.phase, F(float(kDone)));
            refineNext = refineNext || loop;
        }
        if (Any(refineNext)) {  // the top of the refinement loop
            Assign(refineNext, s.phase, F(float(kDone)));
            const M go = s.q.Next(r, refineNext, s.nRefine, p.refineSteps, p.earlyExit,
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
        // A lane the budget stopped in the coarse search answers the crossing it found,
        // else where it is (the GLSL twin sets this when Take() refuses).
        const F tResult = Select(s.phase == F(float(kCoarse)),
                                 Select(s.found, s.tBelow, s.t), s.tResult);
        out.u = ray.U(tResult);
        out.v = ray.V(tResult);
        out.depth = tResult;
        out.nCoarse = s.nCoarse;
        out.nRefine = s.nRefine;
        out.hit = s.found;
    }
};

using LinearKernel = LinearSearch<Refinement::None>;
using ReliefKernel = LinearSearch<Refinement::Binary>;
using SecantKernel = LinearSearch<Refinement::Secant>;
using IntervalKernel = LinearSearch<Refinement::Interval>;
using PomKernel = LinearSearch<Refinement::Pom>;

}  // namespace reliefsim
