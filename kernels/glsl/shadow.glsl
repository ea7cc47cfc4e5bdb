// The light-ray kernels: the twin of kernels/shadow.h LightVisibility (the equations are
// there and in docs/methods/shadows.md). The same float operations in the same order.

uniform int uShadow;             // ShadowKind: 0 none, 1 hard, 2 soft, 3 cone
uniform int uShadowSteps;        // hard: steps from the surface to the top
uniform float uShadowStepInv;    // 1.0f / uShadowSteps, computed on the CPU
uniform float uShadowSoftening;  // soft: Tatarchuk's softening
uniform vec2 uLightStep;         // uv per unit of rise along the light ray
uniform float uShadowPenumbra;   // cone: the penumbra factor k
uniform float uShadowRayLength;  // cone: |(lu, lv, 1)|, computed on the CPU
uniform int uAo;                 // AoKind and map: 0 none, 1 cone ratio r, 2 cone normal n_z

const float kSoftShadowFraction[7] = float[7](0.88, 0.77, 0.66, 0.55, 0.44, 0.33, 0.22);
const float kSoftShadowWeight[7] = float[7](1.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0);

// The light's visibility at the hit (x) and the light ray's fetches (y).
vec2 LightVisibility(vec2 uv0, bool hit) {
    if (uShadow == 0 || !hit) return vec2(1.0, 0.0);
    float h0 = SampleHeight(uv0);
    float fetches = 1.0;
    if (uShadow == 1 || uShadow == 3) {
        // The hard shadow's samples; the cone shadow reads n_z with each depth.
        bool cone = uShadow == 3;
        float vis = 1.0;
        float stepDepth = h0 * uShadowStepInv;
        for (int i = 1; i < uShadowSteps; ++i) {
            float rise = float(i) * stepDepth;
            float t = h0 - rise;
            vec2 uv = vec2(uv0.x + rise * uLightStep.x, uv0.y + rise * uLightStep.y);
            vec2 hc = cone ? SampleHeightCone(uv) : vec2(SampleHeight(uv), 0.0);
            fetches += 1.0;
            float above = hc.x - t;
            if (cone ? above < 0.0 : hc.x < t) return vec2(0.0, fetches);
            if (cone) {
                float estimate =
                    (uShadowPenumbra * (above * hc.y)) / (rise * uShadowRayLength);
                if (rise > 0.0) vis = min(vis, estimate);
            }
        }
        return vec2(vis, fetches);
    }
    float occlusion = 0.0;
    for (int k = 0; k < 7; ++k) {
        float f = kSoftShadowFraction[k];
        float t = h0 - f;
        vec2 uv = vec2(uv0.x + f * uLightStep.x, uv0.y + f * uLightStep.y);
        float h = SampleHeight(uv);
        occlusion = max(occlusion, (t - h) * (kSoftShadowWeight[k] * uShadowSoftening));
    }
    return vec2(max(1.0 - occlusion, 0.0), 8.0);
}

// The ambient occlusion factor at the hit (twin of kernels/shadow.h AmbientOcclusion):
// n_z² of the cone normal, or r² / (1 + r²) of the cone ratio; 1 without.
float AmbientOcclusion(vec2 uv0, bool hit) {
    if (uAo == 0 || !hit) return 1.0;
    float c = SampleHeightCone(uv0).y;
    float c2 = c * c;
    return uAo == 2 ? c2 : c2 / (1.0 + c2);
}
