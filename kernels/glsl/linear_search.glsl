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

const int kPhaseCoarse = 0, kPhaseBottom = 1, kPhaseRefine = 2, kPhaseDone = 3;

uniform int uLinearSteps;  // coarse steps over t in [0,1]

MarchResult March(MarchInput ray) {
    precise float stepSize = 1.0 / float(uLinearSteps);
    precise float t = 0.0, tAbove = 0.0, hAbove = 0.0, tBelow = 0.0, hBelow = 0.0;
    bool haveAbove = false, found = false;
    int nCoarse = 0, nRefine = 0, i = 0;
    Refiner q = RefinerClear();
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
            phase = kPhaseDone;
            startRefine = true;
        } else {  // kPhaseRefine: consume the refinement sample
            nRefine = nRefine + 1;
            RefineConsume(q, h);
            refineNext = true;
        }
        if (startRefine) {
            refineNext = RefineStart(q, tAbove, hAbove, tBelow, hBelow, stepSize, tResult,
                                     nRefine);
        }
        if (refineNext) {  // the top of the refinement loop
            phase = kPhaseDone;
            if (RefineNext(q, nRefine, tResult, tq) && Take()) phase = kPhaseRefine;
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
