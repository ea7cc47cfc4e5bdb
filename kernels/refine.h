// The refinement searches that follow a coarse search, shared by every kernel that has
// one (the linear search, the cone kernels): `--set
// refine=none|binary|interval|secant|pom` with `refine_steps` and `secant_tolerance`.
// kernels/glsl/refine.glsl is the same code.
//
// A coarse search hands over a bracket: (t1, h1) the last point it sampled outside the
// relief (t < h), (t2, h2) the first it sampled inside (t >= h), and `step`, the length
// of the ray segment the binary search halves from t2 backwards.
//  * binary (dissertation 004 Alg. 2; Policarpo relief mapping): s = step / 2,
//    t = t2 - s; per iteration fetch h(t), s /= 2, t -= s inside or t += s outside (the
//    step applied as a magnitude, as Policarpo's shader does). With step = t2 it is GPU
//    Gems 3 Listing 18-3's search between H = t2 / 2 and K = t2 exactly (range = tK / 2,
//    tb = tK / 2, the same halvings and the same comparisons).
//  * interval (004 Alg. 3): the ray meets the chord of the two bracket samples at
//    t = SecantPoint(); fetch there and replace the bracket end on the sample's side.
//  * secant (Risser et al. 2007 listing): interval's iteration, stopping once
//    |h - t| <= secant_tolerance (with early_exit); the answer is the last sampled depth.
//  * pom (Tatarchuk 2006): one chord intersection of the bracket, no fetch.
// Every refinement iteration is one fetch and one refine iteration; pom counts one
// iteration and no fetch.
#pragma once

#include <array>
#include <string_view>

#include "kernels/kernel.h"

namespace reliefsim {

/// The refinements, in the order of the `refine` parameter's values (and the twin's
/// kRefine* constants).
enum class Refinement { None, Binary, Interval, Secant, Pom };

inline constexpr std::array<std::string_view, 5> kRefinementChoices = {
    "none", "binary", "interval", "secant", "pom"};

/// The `refine` parameter with the kernel's default refinement.
inline constexpr ParamSpec RefineParam(Refinement def) {
    return {"refine",
            double(int(def)),
            0,
            4,
            true,
            "refinement after the coarse search: none, binary (Alg. 2), interval "
            "(Alg. 3), secant (Risser), pom (one chord step, no fetch)",
            "uRefinement",
            kRefinementChoices};
}
inline constexpr ParamSpec RefineSteps(double def, std::string_view help) {
    return {"refine_steps", def, 0, 64, true, help, "uRefineSteps"};
}
inline constexpr ParamSpec kSecantTolerance = {
    "secant_tolerance",
    0.01,
    0,
    1,
    false,
    "refine=secant stops when |sampled depth - ray depth| <= this",
    "uSecantTolerance"};

/// Per-lane state of a refinement search, and its three moments: Start (the coarse
/// search hands over its bracket), Consume (a refinement sample arrived), Next (the top
/// of the refinement loop: the answer if the lane stops here, and the next fetch).
template <class L>
struct Refiner {
    using F = typename L::F;
    using M = typename L::M;
    F s, tb;           // binary search
    F t1, h1, t2, h2;  // interval / secant bracket
    F tInt, best;      // interval and secant points
    M converged;       // secant stop test met

    void Clear() {
        s = tb = t1 = h1 = t2 = h2 = tInt = best = F(0.0f);
        converged = M(false);
    }

    /// Where the ray meets the line through the two surface samples (t1, h1) above and
    /// (t2, h2) below: t1 + f (t2 - t1), f = (h1 - t1) / ((t2 - t1) - (h2 - h1)) (Alg. 3;
    /// Risser eq. 6-7 in ray parameters). f is clamped to [0,1] against rounding.
    static F SecantPoint(const F& t1, const F& h1, const F& t2, const F& h2) {
        const F denom = (t2 - t1) - (h2 - h1);
        F f = Select(denom > F(0.0f), (h1 - t1) / denom, F(1.0f));
        f = Select(f < F(0.0f), F(0.0f), Select(f > F(1.0f), F(1.0f), f));
        return f * (t2 - t1) + t1;
    }

    /// Starts the refinement on lanes m. Returns the lanes whose refinement loop follows
    /// (every lane of m except for pom, which answers tResult at once with one
    /// iteration).
    M Start(Refinement r, const M& m, const F& ta, const F& ha, const F& tc, const F& hc,
            const F& step, F& tResult, F& nRefine) {
        if (r == Refinement::Binary) {
            Assign(m, s, step * F(0.5f));
            Assign(m, tb, tc - s);
            return m;
        }
        if (r == Refinement::Pom) {
            Assign(m, tResult, SecantPoint(ta, ha, tc, hc));
            Assign(m, nRefine, F(1.0f));
            return M(false);
        }
        Assign(m, t1, ta);
        Assign(m, h1, ha);
        Assign(m, t2, tc);
        Assign(m, h2, hc);
        Assign(m, tInt, t2);
        Assign(m, best, t2);
        converged = converged && !m;
        return m;
    }

    /// Consumes on lanes m the sample h taken at the refinement point.
    void Consume(Refinement r, const M& m, const F& h, float tolerance) {
        if (r == Refinement::Binary) {
            Assign(m, s, s * F(0.5f));
            Assign(m, tb, Select(tb >= h, tb - s, tb + s));
        } else if (r == Refinement::Interval) {
            Narrow(m, tInt, h);
        } else if (r == Refinement::Secant) {
            const M open = m && !converged;
            Narrow(open, tInt, h);
            Assign(open, best, h);
            converged = converged || (open && (stdx::abs(h - tInt) <= F(tolerance)));
        }
    }

    /// The top of the refinement loop on lanes m, after nRefine iterations: sets the
    /// answer if the lane stops here and returns the lanes that fetch at tq next.
    M Next(Refinement r, const M& m, const F& nRefine, int steps, bool earlyExit,
           F& tResult, F& tq) {
        M go = m && (nRefine < F(float(steps)));
        if (r == Refinement::Binary) {
            Assign(m, tResult, tb);
            Assign(go, tq, tb);
        } else if (r == Refinement::Interval) {
            Assign(m, tResult, tInt);
            Assign(go, tInt, SecantPoint(t1, h1, t2, h2));
            Assign(go, tResult, tInt);
            Assign(go, tq, tInt);
        } else {  // Secant
            Assign(m, tResult, best);
            if (earlyExit) go = go && !converged;
            Assign(go, tInt, SecantPoint(t1, h1, t2, h2));
            Assign(go, tq, tInt);
        }
        return go;
    }

  private:
    // Replaces the bracket end on the same side of the surface as the sample (t, h).
    void Narrow(const M& m, const F& t, const F& h) {
        const M below = m && (t >= h), above = m && !(t >= h);
        Assign(below, t2, t);
        Assign(below, h2, h);
        Assign(above, t1, t);
        Assign(above, h1, h);
    }
};

}  // namespace reliefsim
