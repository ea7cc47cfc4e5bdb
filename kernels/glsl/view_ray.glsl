// GLSL twin of render/view_ray.h PixelToRay: pixel -> texture-space view ray, the same float
// operations in the same order (no fma: llvmpipe lowers ffma to mul + add; DESIGN.md "The
// GLSL twin"). Row 0 is the top of the image: the caller flips gl_FragCoord.y.

uniform vec3 uEye;      // camera position, world
uniform vec3 uForward;  // unit view direction, world
uniform vec3 uRight;    // camera right * tan(fovX/2), world
uniform vec3 uUp;       // camera up * tan(fovY/2), world
uniform float uWidth, uHeight;  // framebuffer size in pixels
uniform float uTiling;          // uv repeats across the plane
uniform float uDepthScale;      // relief depth in plane units
uniform int uOrtho;             // 1: the orthographic texture-space view
uniform vec2 uOrthoDirUv;       // its ray's uv per unit depth
uniform float uOrthoViewZ;      // its |view.z| of the unit view direction

struct MarchInput {
    vec2 uvEntry;  // uv where the ray enters the relief (tiling included)
    vec2 dirUv;    // uv travelled per unit depth
    float viewZ;   // |view.z| of the unit view direction
};

MarchInput PixelToRay(int px, int py) {
    precise float fx = float(px) + 0.5;
    precise float fy = float(py) + 0.5;
    if (uOrtho != 0) {
        MarchInput o;
        precise float ou = fx / uWidth;
        precise float ov = fy / uHeight;
        o.uvEntry = vec2(ou, ov);
        o.dirUv = uOrthoDirUv;
        o.viewZ = uOrthoViewZ;
        return o;
    }
    precise float ndcX = (fx * 2.0) / uWidth - 1.0;
    precise float ndcY = 1.0 - (fy * 2.0) / uHeight;
    precise float dx = (uForward.x + uRight.x * ndcX) + uUp.x * ndcY;
    precise float dy = (uForward.y + uRight.y * ndcX) + uUp.y * ndcY;
    precise float dz = (uForward.z + uRight.z * ndcX) + uUp.z * ndcY;
    dz = dz < -1e-6 ? dz : -1e-6;
    precise float tPlane = -uEye.z / dz;
    precise float hitX = uEye.x + dx * tPlane;
    precise float hitY = uEye.y + dy * tPlane;
    precise float k = uDepthScale * uTiling;
    MarchInput r;
    precise float u0 = (hitX + 0.5) * uTiling;
    precise float v0 = (0.5 - hitY) * uTiling;
    precise float du = -(dx / dz) * k;
    precise float dv = (dy / dz) * k;
    r.uvEntry = vec2(u0, v0);
    r.dirUv = vec2(du, dv);
    precise float len = sqrt((dx * dx + dy * dy) + dz * dz);
    precise float vz = -dz / len;
    r.viewZ = vz;
    return r;
}
