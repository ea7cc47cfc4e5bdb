// One-pixel trace (included before the kernel for `glcompare --trace-pixel`): records every
// fetch of the traced pixel as (u, v, sampled depth, ray t).

layout(std430, binding = 1) buffer Trace {
    uint gTraceCount;
    uint gTracePad[3];
    vec4 gTrace[];
};
uniform ivec2 uTracePixel;  // (x, row from the top)
bool gTracing;

#define RS_ON_SAMPLE(t, uv, h)                               \
    if (gTracing) {                                          \
        uint n = gTraceCount;                                \
        if (n < uint(gTrace.length())) gTrace[n] = vec4((uv), (h), (t)); \
        gTraceCount = n + 1u;                                \
    }
