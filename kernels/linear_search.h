// Linear search (dissertation Alg. 1) followed by a refinement: none, binary (Alg. 2,
// Policarpo relief mapping), interval (Alg. 3), iterated secant (Risser et al. 2007,
// listing), or one secant step without a fetch (Tatarchuk's parallax occlusion mapping).
//
// Conventions (DESIGN.md): p(t) = (uvEntry + t * dirUv, t); the ray is inside the relief
// where t >= depth(uv). Every fetch goes through the sampler and is charged to the
// FetchBudget.
//
// Where the papers are ambiguous, this file decides (docs/kernels.md explains each):
//  * Alg. 2 as printed flips the sign of s twice when two consecutive points are below
//  the
//    surface; the step is applied as a magnitude: t -= |s|/2 when below, t += |s|/2 when
//    above (what Policarpo's shader does).
//  * Alg. 3 as printed assigns a point below the surface to p1, the point "before" the
//    intersection; here the new point replaces the bracket end on its own side.
//  * Refinements reuse the two samples the linear search already took around the crossing
//    (as the POM and secant listings do); only when the linear search found no hit is the
//    bracket's lower end (t = 1, the bottom) fetched.
//  * A hit at the very first sample (t = 0) is exact (the surface is at the top there),
//  so no
//    refinement runs.
//  * early_exit = false runs every loop for its full count, as a GPU with uniform control
//  flow
//    would, with the result latched at the point where the break would have happened.
#pragma once

#include <cmath>
#include <cstdint>
#include <string_view>

#include "kernels/kernel.h"

namespace reliefsim {

enum class Refinement { None, Binary, Interval, Secant, Pom };

struct LinearSearchKernel {
    struct Params {
        int linearSteps = 32;  ///< coarse steps over t in [0,1]; step = 1/linearSteps
        int refineSteps = 6;   ///< refinement iterations (ignored by None and Pom)
        Refinement refinement = Refinement::Binary;
        bool earlyExit = true;  ///< break out of loops (false: GPU-style fixed loops)
        uint32_t budget = 0;    ///< fetches per fragment, 0 = unlimited
        float secantTolerance = 0.01f;  ///< Risser's |h - z| stop test (listing: 0.01)
    };
    Params params;

    static glm::vec2 At(const MarchInput& in, float t) {
        return in.uvEntry + in.dirUv * t;
    }

    template <HeightSampler S>
    MarchResult March(const MarchInput& in, S& heights) const {
        MarchResult r;
        FetchBudget budget(params.budget);
        const float stepSize = 1.0f / float(params.linearSteps);

        // Coarse: Alg. 1.
        float t = 0.0f;
        float tAbove = 0.0f, hAbove = 0.0f;  // last sample above the surface
        float tBelow = 0.0f, hBelow = 0.0f;  // first sample below it
        bool haveAbove = false, found = false;
        for (int i = 0; i < params.linearSteps; ++i) {
            if (!budget.Take()) break;
            ++r.nCoarse;
            float h = heights.Sample(At(in, t));
            if (!found) {
                if (t >= h) {
                    found = true;
                    tBelow = t;
                    hBelow = h;
                    if (params.earlyExit) break;
                } else {
                    tAbove = t;
                    hAbove = h;
                    haveAbove = true;
                }
            }
            t = t + stepSize;
        }
        r.hit = found;
        if (budget.Exhausted()) return Finish(r, in, found ? tBelow : t, budget);
        bool haveBelowSample = found;
        if (!found) tBelow = t;  // the bottom, reached after linearSteps steps

        float tResult = tBelow;
        if (haveAbove && params.refinement != Refinement::None) {
            if (!haveBelowSample && params.refinement != Refinement::Binary) {
                if (!budget.Take()) return Finish(r, in, tBelow, budget);
                hBelow = heights.Sample(At(in, tBelow));
            }
            switch (params.refinement) {
                case Refinement::Binary:
                    tResult = Binary(in, heights, stepSize, tBelow, budget, r);
                    break;
                case Refinement::Interval:
                    tResult =
                        Interval(in, heights, tAbove, hAbove, tBelow, hBelow, budget, r);
                    break;
                case Refinement::Secant:
                    tResult =
                        Secant(in, heights, tAbove, hAbove, tBelow, hBelow, budget, r);
                    break;
                case Refinement::Pom:
                    tResult = SecantPoint(tAbove, hAbove, tBelow, hBelow);
                    r.nRefine = 1;
                    break;
                case Refinement::None:
                    break;
            }
        }
        return Finish(r, in, tResult, budget);
    }

    /// Where the ray meets the line through the two surface samples (t1, h1) above and
    /// (t2, h2) below: t1 + f (t2 - t1), f = (h1 - t1) / ((t2 - t1) - (h2 - h1)) (Alg. 3;
    /// Risser eq. 6-7 in ray parameters). f is clamped to [0,1] against rounding.
    static float SecantPoint(float t1, float h1, float t2, float h2) {
        float denom = (t2 - t1) - (h2 - h1);
        float f = denom > 0.0f ? (h1 - t1) / denom : 1.0f;
        f = f < 0.0f ? 0.0f : (f > 1.0f ? 1.0f : f);  // f is finite here; no libm call
        return f * (t2 - t1) + t1;
    }

  private:
    static MarchResult& Finish(MarchResult& r, const MarchInput& in, float t,
                               const FetchBudget& budget) {
        r.uvHit = At(in, t);
        r.depthHit = t;
        r.budgetExhausted = budget.Exhausted();
        return r;
    }

    // Alg. 2: bisection of [linearT - stepSize, linearT], returning the last (unsampled)
    // point.
    template <HeightSampler S>
    float Binary(const MarchInput& in, S& heights, float stepSize, float linearT,
                 FetchBudget& budget, MarchResult& r) const {
        float s = stepSize * 0.5f;
        float t = linearT - s;
        for (int k = 0; k < params.refineSteps; ++k) {
            if (!budget.Take()) break;
            ++r.nRefine;
            float h = heights.Sample(At(in, t));
            s = s * 0.5f;
            t = t >= h ? t - s : t + s;
        }
        return t;
    }

    // Replaces the bracket end on the same side of the surface as the sample (t, h).
    static void Narrow(float t, float h, float& t1, float& h1, float& t2, float& h2) {
        if (t >= h) {
            t2 = t;
            h2 = h;
        } else {
            t1 = t;
            h1 = h;
        }
    }

    // Alg. 3 with a bracket-preserving update; returns the last intersection point.
    template <HeightSampler S>
    float Interval(const MarchInput& in, S& heights, float t1, float h1, float t2,
                   float h2, FetchBudget& budget, MarchResult& r) const {
        float tInt = t2;
        for (int k = 0; k < params.refineSteps; ++k) {
            tInt = SecantPoint(t1, h1, t2, h2);
            if (!budget.Take()) break;
            ++r.nRefine;
            Narrow(tInt, heights.Sample(At(in, tInt)), t1, h1, t2, h2);
        }
        return tInt;
    }

    // Risser's listing: iterate the secant point until the sampled depth is within the
    // tolerance of the ray's depth there; the answer is the ray point at the depth
    // sampled last.
    template <HeightSampler S>
    float Secant(const MarchInput& in, S& heights, float t1, float h1, float t2, float h2,
                 FetchBudget& budget, MarchResult& r) const {
        float best = t2;
        bool converged = false;
        for (int k = 0; k < params.refineSteps; ++k) {
            if (converged && params.earlyExit) break;
            float tInt = SecantPoint(t1, h1, t2, h2);
            if (!budget.Take()) break;
            ++r.nRefine;
            float h = heights.Sample(At(in, tInt));
            if (converged) continue;
            Narrow(tInt, h, t1, h1, t2, h2);
            best = h;
            converged = std::fabs(h - tInt) <= params.secantTolerance;
        }
        return best;
    }
};

}  // namespace reliefsim
