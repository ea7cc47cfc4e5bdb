// GLSL twin of kernels/refine.h: the refinement searches after a coarse search (none,
// binary, interval, secant, pom), shared by linear_search.glsl and cone_step.glsl. The
// same float operations in the same order as Refiner<L>; the caller owns the fetch
// (Take()) and the phase.

const int kRefineNone = 0, kRefineBinary = 1, kRefineInterval = 2, kRefineSecant = 3,
          kRefinePom = 4;

uniform int uRefinement;  // kRefine*
uniform int uRefineSteps;
uniform float uSecantTolerance;

struct Refiner {
    float s, tb;            // binary search
    float t1, h1, t2, h2;   // interval / secant bracket
    float tInt, best;       // interval and secant points
    bool converged;         // secant stop test met
};

Refiner RefinerClear() {
    Refiner q;
    q.s = 0.0;
    q.tb = 0.0;
    q.t1 = 0.0;
    q.h1 = 0.0;
    q.t2 = 0.0;
    q.h2 = 0.0;
    q.tInt = 0.0;
    q.best = 0.0;
    q.converged = false;
    return q;
}

// Refiner::SecantPoint.
float SecantPoint(float t1, float h1, float t2, float h2) {
    precise float denom = (t2 - t1) - (h2 - h1);
    precise float f = denom > 0.0 ? (h1 - t1) / denom : 1.0;
    f = min(max(f, 0.0), 1.0);
    precise float r = f * (t2 - t1) + t1;
    return r;
}

// Refiner::Narrow: replaces the bracket end on the same side of the surface as the sample
// (t, h); moves values only, no arithmetic.
void RefineNarrow(inout Refiner q, float t, float h) {
    if (t >= h) {
        q.t2 = t;
        q.h2 = h;
    } else {
        q.t1 = t;
        q.h1 = h;
    }
}

// Refiner::Start: returns whether the refinement loop follows (pom answers at once).
bool RefineStart(inout Refiner q, float ta, float ha, float tc, float hc, float step,
                 inout float tResult, inout int nRefine) {
    if (uRefinement == kRefineBinary) {
        precise float s = step * 0.5;
        precise float tb = tc - s;
        q.s = s;
        q.tb = tb;
        return true;
    }
    if (uRefinement == kRefinePom) {
        tResult = SecantPoint(ta, ha, tc, hc);
        nRefine = 1;
        return false;
    }
    q.t1 = ta;
    q.h1 = ha;
    q.t2 = tc;
    q.h2 = hc;
    q.tInt = q.t2;
    q.best = q.t2;
    q.converged = false;
    return true;
}

// Refiner::Consume: the sample h taken at the refinement point.
void RefineConsume(inout Refiner q, float h) {
    if (uRefinement == kRefineBinary) {
        precise float s = q.s * 0.5;
        precise float up = q.tb - s;
        precise float down = q.tb + s;
        q.s = s;
        q.tb = q.tb >= h ? up : down;
    } else if (uRefinement == kRefineInterval) {
        RefineNarrow(q, q.tInt, h);
    } else if (uRefinement == kRefineSecant && !q.converged) {
        RefineNarrow(q, q.tInt, h);
        q.best = h;
        precise float e = abs(h - q.tInt);
        q.converged = e <= uSecantTolerance;
    }
}

// Refiner::Next: the top of the refinement loop after nRefine iterations. Sets the answer
// if the lane stops here; returns whether it fetches at tq next (the caller asks Take()).
bool RefineNext(inout Refiner q, int nRefine, inout float tResult, inout float tq) {
    bool go = nRefine < uRefineSteps;
    if (uRefinement == kRefineBinary) {
        tResult = q.tb;
        if (go) tq = q.tb;
    } else if (uRefinement == kRefineInterval) {
        tResult = q.tInt;
        if (go) {
            q.tInt = SecantPoint(q.t1, q.h1, q.t2, q.h2);
            tResult = q.tInt;
            tq = q.tInt;
        }
    } else {  // kRefineSecant
        tResult = q.best;
        if (uEarlyExit && q.converged) go = false;
        if (go) {
            q.tInt = SecantPoint(q.t1, q.h1, q.t2, q.h2);
            tq = q.tInt;
        }
    }
    return go;
}
