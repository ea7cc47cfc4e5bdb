// GLSL twin of texture/sampler.h Sample(): one fetch of the height texture. The GL sampler
// object carries filter (GL_LINEAR, GL_NEAREST, or GL_LINEAR with the GL_MIN reduction for
// min4), wrap (GL_REPEAT / GL_CLAMP_TO_EDGE) and format (R32F: llvmpipe's float SoA path;
// R8: its 8.8 fixed-point AoS path). The texture has one level and the lod is explicit, so no
// derivative or lod arithmetic enters (research/llvmpipe.md §2.5).

uniform sampler2D uHeights;  // depth in [0,1], texel (i, j) centred at ((i+0.5)/W, (j+0.5)/H)

float SampleHeight(vec2 uv) { return textureLod(uHeights, uv, 0.0).r; }

// One fetch of the combined depth + cone-ratio texture of the cone kernels (RG32F, or RG8
// with the ratio's 8-bit code): depth in .r, the stored ratio in .g, decoded as
// texture/lane_sampler.h SampleHeightConeLanes does (squared for the sqrt encoding).
uniform int uConeSquared;  // 1: the ratio is stored as sqrt(r) (Dummer; 004 Alg. 4)
// cone_filter other than --filter: the same textures through a sampler object with the
// cone filter (units 2 and 3); the ratio is then a second texture call.
uniform int uConeSeparate;
uniform int uConeFilter;  // the cone_filter parameter; the sampler objects apply it
uniform sampler2D uConeFiltered;
uniform sampler2DArray uConeLayersFiltered;

vec2 SampleHeightCone(vec2 uv) {
    vec4 x = textureLod(uHeights, uv, 0.0);
    precise float r = x.g;
    if (uConeSeparate != 0) r = textureLod(uConeFiltered, uv, 0.0).g;
    if (uConeSquared != 0) r = r * r;
    return vec2(x.r, r);
}

// The directional cone kernels' layered map: layer k holds (depth, ratio of direction
// class k), one RG texture array sampled like uHeights (SampleHeightConeLanes' layer).
uniform sampler2DArray uConeLayers;

vec2 SampleHeightConeLayer(vec2 uv, int layer) {
    vec4 x = textureLod(uConeLayers, vec3(uv, float(layer)), 0.0);
    precise float r = x.g;
    if (uConeSeparate != 0) r = textureLod(uConeLayersFiltered, vec3(uv, float(layer)), 0.0).g;
    if (uConeSquared != 0) r = r * r;
    return vec2(x.r, r);
}
