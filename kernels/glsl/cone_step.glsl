// GLSL twin of kernels/cone_step.h: cone step mapping (004 Alg. 4) and, with uRelaxed,
// relaxed cone stepping with its binary search (001 Listing 18-3). One fetch per trip of
// the combined texture (depth in .r, cone ratio in .g; sampler.glsl SampleHeightCone),
// the same float operations in the same order as the C++ kernel. Families 5 and 6 (cns,
// rcns) read n_z of the cone side's normal and step by 004 eq. 3.2; family 7 (mcns) reads
// the four stacked cones' n_z from the layers of the (depth, n_z) array and keeps the
// largest step. After the cone loop, the refinement of refine.glsl (uRefinement).

uniform int uConeSteps;     // cone steps
uniform int uConeStepForm;  // 0: Listing 18-3's step; 1: Alg. 4's unit-ray form
uniform int uMinStep;       // 0 none, 1 texel (1/W along the unit ray), 2 cell border
uniform vec2 uMapSize;      // the height map's size in texels
uniform int uRelaxed;       // 1: rcs
uniform int uConeFamily;    // kernels/cone_step.h ConeFamily: 2 qcsm, 3 acm4, 4 acm8,
                            // 5 cns, 6 rcns, 7 mcns

const int kFamilyQuad = 2, kFamilyAcm4 = 3, kFamilyAcm8 = 4, kFamilyConeNormal = 5,
          kFamilyStacked = 7;
const int kStackedCones = 4;  // kernels/kernel.h kMaxStackedCones
// A march that stopped above the surface answers its last point (kernels/kernel.h
// KernelAnswersAtStop): record_main.glsl lights it.
#define RS_ANSWERS_AT_STOP 1

// The cone step's depth advance (ConeStep::Advance): csm's from the ratio r, or eq. 3.2
// from n_z (normalForm).
float Advance(float t, float h, float r, float rayRatio, float rdXy, float rdZ,
              bool normalForm) {
    precise float d;
    if (normalForm) {
        precise float nXy = sqrt(1.0 - r * r);
        if (uConeStepForm != 0) {
            precise float s = ((h - t) * r) / (nXy * rdXy + r * rdZ);
            d = s * rdZ;
        } else {
            d = ((h - t) * r) / (nXy * rayRatio + r);
        }
    } else if (uConeStepForm != 0) {
        precise float s = (h - t) / (rdXy / r + rdZ);
        d = s * rdZ;
    } else {
        d = (r * (h - t)) / (rayRatio + r);
    }
    return d;
}

// ConeStep::LeastStep: the least cone step from the ray point at t (min_step).
float LeastStep(MarchInput ray, float t, float rdZ) {
    precise float least;
    if (uMinStep == 1) {
        least = rdZ / uMapSize.x;
    } else {
        vec2 p = At(ray, t);
        precise float x = p.x * uMapSize.x - 0.5;
        precise float y = p.y * uMapSize.y - 0.5;
        precise float fx = floor(x), fy = floor(y);
        precise float wx = ray.dirUv.x > 0.0 ? fx + 1.0 : fx;
        precise float wy = ray.dirUv.y > 0.0 ? fy + 1.0 : fy;
        const float none = 3.0e38;
        precise float tx = none, ty = none;
        if (ray.dirUv.x != 0.0) tx = (wx - x) / (ray.dirUv.x * uMapSize.x);
        if (ray.dirUv.y != 0.0) ty = (wy - y) / (ray.dirUv.y * uMapSize.y);
        precise float cell = tx < ty ? tx : ty;
        least = cell < none ? cell + 1e-5 * rdZ : 0.0;
    }
    precise float room = 1.0 - t;
    return least > room ? room : least;
}

// ConeLayerOf: the direction class of dirUv, by the same exact comparisons.
int ConeLayerOf(float du, float dv) {
    if (uConeFamily == kFamilyAcm4) {
        if (du >= 0.0 && dv >= 0.0) return 0;
        if (du <= 0.0 && dv >= 0.0) return 1;
        if (du <= 0.0 && dv <= 0.0) return 2;
        return 3;
    }
    if (uConeFamily == kFamilyAcm8) {
        if (dv >= 0.0 && du >= dv) return 0;
        if (du >= 0.0 && dv >= du) return 1;
        if (du <= 0.0 && dv >= -du) return 2;
        if (dv >= 0.0 && -du >= dv) return 3;
        if (dv <= 0.0 && dv >= du) return 4;
        if (du <= 0.0 && du >= dv) return 5;
        if (du >= 0.0 && dv <= -du) return 6;
        return 7;
    }
    if (uConeFamily == kFamilyQuad) {
        if (du > 0.0 && dv > 0.0) return 0;
        if (du < 0.0 && dv > 0.0) return 1;
        if (du < 0.0 && dv < 0.0) return 2;
        if (du > 0.0 && dv < 0.0) return 3;
        if (du == 0.0 && dv > 0.0) return 5;
        if (du < 0.0 && dv == 0.0) return 6;
        if (du == 0.0 && dv < 0.0) return 7;
        return 4;
    }
    return 0;
}

const int kConePhaseCone = 0, kConePhaseBottom = 1, kConePhaseRefine = 2,
          kConePhaseDone = 3;

MarchResult March(MarchInput ray) {
    precise float sq = ray.dirUv.x * ray.dirUv.x + ray.dirUv.y * ray.dirUv.y;
    precise float rayRatio = sqrt(sq);
    precise float len = sqrt(sq + 1.0);
    precise float rdXy = rayRatio / len;
    precise float rdZ = 1.0 / len;
    precise float t = 0.0, tq = 0.0, tResult = 0.0;
    precise float tAbove = 0.0, hAbove = 0.0, tBelow = 0.0, hBelow = 0.0;
    int nCoarse = 0, nRefine = 0;
    bool inside = false, haveAbove = false;
    Refiner q = RefinerClear();
    int phase = kConePhaseCone;
    int layer = ConeLayerOf(ray.dirUv.x, ray.dirUv.y);
    bool stacked = uConeFamily == kFamilyStacked;
    bool layered = (uConeFamily >= kFamilyQuad && uConeFamily <= kFamilyAcm8) || stacked;
    bool normalForm = uConeFamily >= kFamilyConeNormal;

    gUsed = 0u;
    gExhausted = false;
    Take();  // the first fetch (a budget, when set, is >= 1)
    do {
        RS_ON_TRIP();
        vec2 x = layered ? SampleHeightConeLayer(At(ray, tq), layer)
                         : SampleHeightCone(At(ray, tq));
        precise float h = x.x;
        precise float r = x.y;
        precise float stack[kStackedCones];
        stack[0] = r;
        if (stacked) {  // the other stacked cones at the same point: K - 1 more calls
            for (int k = 1; k < kStackedCones; ++k)
                stack[k] = SampleHeightConeLayer(At(ray, tq), k).y;
        }
        RS_ON_SAMPLE(tq, At(ray, tq), h);
        bool want = false, startRefine = false, refineNext = false;
        precise float segment = 0.0;
        if (phase == kConePhaseCone) {
            nCoarse = nCoarse + 1;
            bool isIn = t >= h;
            if (isIn && !inside) {
                tBelow = t;
                hBelow = h;
            }
            inside = inside || isIn;
            if (!isIn) {
                tAbove = t;
                hAbove = h;
                haveAbove = true;
            }
            precise float d = Advance(t, h, r, rayRatio, rdXy, rdZ, normalForm);
            if (stacked) {
                for (int k = 1; k < kStackedCones; ++k) {
                    precise float apex =
                        h * (float(kStackedCones - k) / float(kStackedCones));
                    precise float dk = Advance(t, apex, stack[k], rayRatio, rdXy, rdZ, true);
                    if (t < apex && dk > d) d = dk;
                }
            }
            if (uMinStep != 0) {
                precise float least = LeastStep(ray, t, rdZ);
                if (d < least) d = least;
            }
            if (!isIn && d > 0.0) t = t + d;
            bool stop = (uEarlyExit && isIn) || nCoarse >= uConeSteps;
            if (!stop) {
                tq = t;
                want = true;
            } else {
                if (!inside) tBelow = t;
                tResult = t;
                phase = kConePhaseDone;
                if (uRefinement == kRefineBinary) {
                    startRefine = uRelaxed != 0 || haveAbove;
                    segment = uRelaxed != 0 ? tBelow : tBelow - tAbove;
                } else if (uRefinement != kRefineNone) {
                    startRefine = inside && haveAbove;
                    if (!inside) {
                        tq = t;
                        phase = kConePhaseBottom;
                        want = true;
                    }
                }
            }
        } else if (phase == kConePhaseBottom) {
            phase = kConePhaseDone;
            if (t >= h) {
                hBelow = h;
                startRefine = true;
            }
        } else {  // kConePhaseRefine: consume the refinement sample
            nRefine = nRefine + 1;
            RefineConsume(q, h);
            refineNext = true;
        }
        if (startRefine) {
            refineNext =
                RefineStart(q, tAbove, hAbove, tBelow, hBelow, segment, tResult, nRefine);
        }
        if (refineNext) {  // the top of the refinement loop
            phase = kConePhaseDone;
            if (RefineNext(q, nRefine, tResult, tq)) {
                phase = kConePhaseRefine;
                want = true;
            }
        }
        if (want && !Take()) want = false;
        if (!want) break;
    } while (true);

    if (phase == kConePhaseCone) tResult = t;
    MarchResult m;
    m.uvHit = At(ray, tResult);
    m.depthHit = tResult;
    m.nCoarse = nCoarse;
    m.nRefine = nRefine;
    m.nFetches = int(gUsed);
    m.hit = inside;
    m.budgetExhausted = gExhausted;
    return m;
}
