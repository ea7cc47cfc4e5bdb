// The pieces every kernel twin shares (included before the kernel's file): the runner's
// hooks, the parameters every kernel has, the result, the fetch budget and the ray point.
// RS_ON_TRIP() and RS_ON_SAMPLE() are the runner's hooks (lane measurement, one-pixel
// trace); they are empty by default.

#ifndef RS_ON_TRIP
#define RS_ON_TRIP()
#endif
#ifndef RS_ON_SAMPLE
#define RS_ON_SAMPLE(t, uv, h)
#endif

uniform bool uEarlyExit;  // break out of loops (false: fixed loops, result latched)
uniform uint uBudget;     // fetches per fragment, 0 = unlimited

struct MarchResult {
    vec2 uvHit;
    float depthHit;
    int nCoarse, nRefine, nFetches;
    bool hit, budgetExhausted;
};

// The fetch budget (kernels/kernel.h FetchBudget::Take).
uint gUsed = 0u;
bool gExhausted = false;
bool Take() {
    if (uBudget != 0u && gUsed >= uBudget) {
        gExhausted = true;
        return false;
    }
    gUsed = gUsed + 1u;
    return true;
}

vec2 At(MarchInput ray, float t) {
    precise vec2 uv = ray.uvEntry + ray.dirUv * t;
    return uv;
}

