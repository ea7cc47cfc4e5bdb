// The record fragment shader's main: pixel -> ray (view_ray.glsl), the kernel twin, and the
// per-pixel record into three RGBA32F targets.

layout(location = 0) out vec4 oHit;     // hit u, hit v, hit depth, flags (core/record.h)
layout(location = 1) out vec4 oCounts;  // coarse, refine, fetches, gl_PrimitiveID + 1
layout(location = 2) out vec4 oShadow;  // light visibility, light-ray fetches, ambient
                                        // occlusion (shadow.glsl)

void main() {
    // gl_FragCoord.xy is the pixel centre (x + 0.5, y + 0.5) with y up; our row 0 is the top.
    int px = int(gl_FragCoord.x);
    int py = int(uHeight) - 1 - int(gl_FragCoord.y);
#ifdef RS_MEASURE_LANES
    LaneProbeBegin(px, py);
#endif
#ifdef RS_TRACE
    gTracing = px == uTracePixel.x && py == uTracePixel.y;
#endif
    MarchResult m = March(PixelToRay(px, py));
    float flags = 1.0;                        // kFlagCovered
    if (m.budgetExhausted) flags += 4.0;      // kFlagBudgetExhausted
    if (!m.hit) flags += 8.0;                 // kFlagNoHit
    oHit = vec4(m.uvHit, m.depthHit, flags);
    oCounts = vec4(float(m.nCoarse), float(m.nRefine), float(m.nFetches),
                   float(gl_PrimitiveID + 1));
    // The pixels with an answer to light: those that hit, and for a kernel that answers
    // where it stopped (the cone family), all (render/lane_driver.h EndPack).
#ifdef RS_ANSWERS_AT_STOP
    bool answered = true;
#else
    bool answered = m.hit;
#endif
    vec2 light = LightVisibility(m.uvHit, answered);
    if (uAo != 0 && answered) light.y += 1.0;  // the AO fetch counts with the light rays'
    oShadow = vec4(light, AmbientOcclusion(m.uvHit, answered), 0.0);
}
