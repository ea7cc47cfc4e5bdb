// GLSL twin of kernels/linear_search.h LinearSearchKernel: linear search followed by none,
// binary, interval, secant or pom refinement. Per lane it computes exactly what the C++
// kernel computes (same float operations, same order, same fetches, same budget rule).
//
// Shape: one do-while loop with exactly one texture fetch per trip, a small state machine
// (coarse -> bottom fetch -> refine) deciding after each fetch what the next fetch is.
// On llvmpipe a loop runs until its last active lane leaves (research/llvmpipe.md §3), so a
// 4x2 lane group runs max(fetches of its lanes) trips and pays 8 lane-fetches per trip: the
// lane-cost model of metrics/summary.h holds exactly. The exit test sits at the END of the
// trip, so no trip ever starts with every lane finished (which would still execute the
// unmasked texture instruction).

const int kRefineNone = 0, kRefineBinary = 1, kRefineInterval = 2, kRefineSecant = 3,
          kRefinePom = 4;
const int kPhaseCoarse = 0, kPhaseBottom = 1, kPhaseRefine = 2, kPhaseDone = 3;

uniform int uLinearSteps;    // coarse steps over t in [0,1]
uniform int uRefineSteps;    // refinement iterations
uniform int uRefinement;     // kRefine*
uniform float uSecantTolerance;

// LinearSearchKernel::SecantPoint.
float SecantPoint(float t1, float h1, float t2, float h2) {
    precise float denom = (t2 - t1) - (h2 - h1);
    precise float f = denom > 0.0 ? (h1 - t1) / denom : 1.0;
    f = min(max(f, 0.0), 1.0);
    precise float r = f * (t2 - t1) + t1;
    return r;
}

// Replaces the bracket end on the same side of the surface as the sample (t, h)
// (LinearSearchKernel::Narrow); moves values only, no arithmetic.
void Narrow(float t, float h, inout float t1, inout float h1, inout float t2, inout float h2) {
    if (t >= h) {
        t2 = t;
        h2 = h;
    } else {
        t1 = t;
        h1 = h;
    }
}

MarchResult March(MarchInput ray) {
    precise float stepSize = 1.0 / float(uLinearSteps);
    precise float t = 0.0, tAbove = 0.0, hAbove = 0.0, tBelow = 0.0, hBelow = 0.0;
    bool haveAbove = false, found = false;
    int nCoarse = 0, nRefine = 0, i = 0, k = 0;
    // refinement state
    precise float s = 0.0, tb = 0.0, t1 = 0.0, h1 = 0.0, t2 = 0.0, h2 = 0.0, tInt = 0.0,
                  best = 0.0;
    bool converged = false;
    precise float tResult = 0.0;  // the returned point, valid in kPhaseDone
    precise float tq = 0.0;       // ray parameter of the next fetch

    gUsed = 0u;
    gExhausted = false;
    int phase = kPhaseCoarse;
    Take();  // the first coarse fetch (a budget, when set, is >= 1)
    do {
        RS_ON_TRIP();
        precise float h = SampleHeight(At(ray, tq));
        RS_ON_SAMPLE(tq, At(ray, tq), h);
        // What to fetch next: these flags carry the C++ control flow between phases.
        bool startRefine = false, refineNext = false;
        if (phase == kPhaseCoarse) {
            nCoarse = nCoarse + 1;
            bool stop = false;
            if (!found) {
                if (t >= h) {
                    found = true;
                    tBelow = t;
                    hBelow = h;
                    stop = uEarlyExit;
                } else {
                    tAbove = t;
                    hAbove = h;
                    haveAbove = true;
                }
            }
            if (!stop) {
                t = t + stepSize;
                i = i + 1;
                stop = i >= uLinearSteps;
                if (!stop) {
                    if (Take()) {
                        tq = t;
                    } else {
                        tResult = found ? tBelow : t;
                        phase = kPhaseDone;
                    }
                }
            }
            if (stop) {  // the coarse loop ended without exhausting the budget
                if (!found) tBelow = t;
                tResult = tBelow;
                phase = kPhaseDone;
                if (haveAbove && uRefinement != kRefineNone) {
                    if (!found && uRefinement != kRefineBinary) {
                        if (Take()) {
                            tq = tBelow;
                            phase = kPhaseBottom;
                        }
                    } else {
                        startRefine = true;
                    }
                }
            }
        } else if (phase == kPhaseBottom) {
            hBelow = h;
            startRefine = true;
        } else {  // kPhaseRefine: consume the refinement sample
            nRefine = nRefine + 1;
            if (uRefinement == kRefineBinary) {
                s = s * 0.5;
                tb = tb >= h ? tb - s : tb + s;
            } else if (uRefinement == kRefineInterval) {
                Narrow(tInt, h, t1, h1, t2, h2);
            } else if (!converged) {  // kRefineSecant
                Narrow(tInt, h, t1, h1, t2, h2);
                best = h;
                converged = abs(h - tInt) <= uSecantTolerance;
            }
            k = k + 1;
            refineNext = true;
        }
        if (startRefine) {
            k = 0;
            refineNext = true;
            if (uRefinement == kRefineBinary) {
                s = stepSize * 0.5;
                tb = tBelow - s;
            } else if (uRefinement == kRefinePom) {
                tResult = SecantPoint(tAbove, hAbove, tBelow, hBelow);
                nRefine = 1;
                phase = kPhaseDone;
                refineNext = false;
            } else {
                t1 = tAbove;
                h1 = hAbove;
                t2 = tBelow;
                h2 = hBelow;
                tInt = t2;
                best = t2;
                converged = false;
            }
        }
        if (refineNext) {  // the top of the refinement loop
            phase = kPhaseDone;
            if (uRefinement == kRefineBinary) {
                tResult = tb;
                if (k < uRefineSteps) {
                    if (Take()) {
                        tq = tb;
                        phase = kPhaseRefine;
                    }
                }
            } else if (uRefinement == kRefineInterval) {
                tResult = tInt;
                if (k < uRefineSteps) {
                    tInt = SecantPoint(t1, h1, t2, h2);
                    tResult = tInt;
                    if (Take()) {
                        tq = tInt;
                        phase = kPhaseRefine;
                    }
                }
            } else {  // kRefineSecant
                tResult = best;
                if (k < uRefineSteps && !(converged && uEarlyExit)) {
                    tInt = SecantPoint(t1, h1, t2, h2);
                    if (Take()) {
                        tq = tInt;
                        phase = kPhaseRefine;
                    }
                }
            }
        }
    } while (phase != kPhaseDone);

    MarchResult r;
    r.uvHit = At(ray, tResult);
    r.depthHit = tResult;
    r.nCoarse = nCoarse;
    r.nRefine = nRefine;
    r.nFetches = int(gUsed);
    r.hit = found;
    r.budgetExhausted = gExhausted;
    return r;
}
