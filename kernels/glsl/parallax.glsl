// GLSL twin of kernels/parallax.h: parallax mapping (004 eq. 2.3-2.5) and, with
// uOffsetLimit, offset limiting (004 eq. 2.6). One fetch at the entry point; the returned
// point is the ray point at t = D (parallax) or t = D * |view.z| (offset limiting).

uniform int uOffsetLimit;  // 1: eq. 2.6

MarchResult March(MarchInput ray) {
    gUsed = 0u;
    gExhausted = false;
    Take();  // the one fetch (a budget, when set, is >= 1)
    RS_ON_TRIP();
    precise float h = SampleHeight(At(ray, 0.0));
    RS_ON_SAMPLE(0.0, At(ray, 0.0), h);
    precise float t = h;
    if (uOffsetLimit != 0) t = h * ray.viewZ;
    MarchResult r;
    r.uvHit = At(ray, t);
    r.depthHit = t;
    r.nCoarse = 1;
    r.nRefine = 0;
    r.nFetches = int(gUsed);
    r.hit = true;
    r.budgetExhausted = gExhausted;
    return r;
}
