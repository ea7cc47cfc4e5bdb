// GLSL twin of kernels/max_mip.h: maximum-mipmap traversal with an exact bilinear-patch
// hit (Tevs et al. 2008; uExactPatch = 1, maxmip) and quadtree displacement mapping
// (Drobot 2009; uExactPatch = 0, qdm) over the cell pyramid (texture/cell_pyramid.h), one
// R32F atlas read with texelFetch. One fetch per trip: a node of the pyramid, or (maxmip,
// level 0) the four corner texels of a cell with texelFetch on the height texture. The
// same float operations in the same order as the C++ kernel; cell indices and levels are
// small integers held exactly in floats.

uniform int uExactPatch;        // 1: maxmip's bilinear patch at level 0; 0: qdm
uniform int uMaxSteps;          // most iterations
uniform vec2 uMapSize;          // the height map's size in texels
uniform sampler2D uPyramid;     // the atlas (unit 4)
uniform int uPyramidTop;        // the top level
uniform int uPyramidOffset[16]; // per level: its first atlas column (kMaxPyramidLevels)

// A cell's corners as the C++ sampler reads them (SamplePyramidLanes): c00, c10, c01, c11.
vec4 Corners(int i, int j) {
    int W = int(uMapSize.x), H = int(uMapSize.y);
    int i1 = i + 1 == W ? 0 : i + 1, j1 = j + 1 == H ? 0 : j + 1;
    return vec4(texelFetch(uHeights, ivec2(i, j), 0).r, texelFetch(uHeights, ivec2(i1, j), 0).r,
                texelFetch(uHeights, ivec2(i, j1), 0).r, texelFetch(uHeights, ivec2(i1, j1), 0).r);
}

float ClampCell(float c, float lo, float hi) { return c < lo ? lo : (c > hi ? hi : c); }

// MaxMip::Ahead: the cell under the ray point, never behind the current cell c.
float Ahead(float p, float c, float a) {
    return a > 0.0 ? (p > c ? p : c) : (a < 0.0 ? (p < c ? p : c) : p);
}

MarchResult March(MarchInput ray) {
    const float big = 3.0e38;
    precise float W = uMapSize.x, H = uMapSize.y;
    precise float xr = ray.uvEntry.x * W;
    precise float yr = ray.uvEntry.y * H;
    precise float x0 = xr - 0.5;
    precise float y0 = yr - 0.5;
    precise float ax = ray.dirUv.x * W;
    precise float ay = ray.dirUv.y * H;
    precise float t = 0.0;
    float top = float(uPyramidTop);
    precise float level = top;
    precise float size = float(1 << uPyramidTop);
    // MaxMip::CellOf
    precise float fx = floor(x0);
    precise float tileX = floor(fx / W) * W;
    precise float cx = fx - tileX;
    cx = cx > W - 1.0 ? W - 1.0 : cx;
    cx = cx < 0.0 ? 0.0 : cx;
    precise float fy = floor(y0);
    precise float tileY = floor(fy / H) * H;
    precise float cy = fy - tileY;
    cy = cy > H - 1.0 ? H - 1.0 : cy;
    cy = cy < 0.0 ? 0.0 : cy;
    int nCoarse = 0;
    bool hit = false, done = false, more = true;

    gUsed = 0u;
    gExhausted = false;
    Take();  // the first fetch (a budget, when set, is >= 1)
    do {
        RS_ON_TRIP();
        // The fetch of the current node (MaxMip::NodeFetch).
        int l = int(level), i = int(cx), j = int(cy);
        vec4 c = vec4(0.0);
        precise float d;
        if (uExactPatch != 0 && l == 0) {
            c = Corners(i, j);
            precise float m0 = c.x < c.y ? c.x : c.y;
            precise float m1 = c.z < c.w ? c.z : c.w;
            d = m0 < m1 ? m0 : m1;
        } else {
            d = texelFetch(uPyramid, ivec2(uPyramidOffset[l] + (i >> l), j >> l), 0).r;
        }
        RS_ON_SAMPLE(t, At(ray, t), d);
        nCoarse = nCoarse + 1;
        if (!done) {
            precise float nx = floor(cx / size) * size;
            precise float ny = floor(cy / size) * size;
            precise float exs = nx + size, eys = ny + size;
            precise float ex = exs < W ? exs : W;
            precise float ey = eys < H ? eys : H;
            precise float bx = ax > 0.0 ? tileX + ex : tileX + nx;
            precise float by = ay > 0.0 ? tileY + ey : tileY + ny;
            precise float tx = big, ty = big;
            if (ax != 0.0) tx = (bx - x0) / ax;
            if (ay != 0.0) ty = (by - y0) / ay;
            bool xFirst = tx <= ty;
            precise float tExit = xFirst ? tx : ty;
            precise float tTop = t > d ? t : d;
            bool into = tTop <= tExit;
            bool found = level == 0.0 && into;
            precise float tHit = tTop;
            if (uExactPatch != 0 && found) {
                precise float a0 = (xr - ((tileX + cx) + 0.5)) + ax * tTop;
                precise float b0 = (yr - ((tileY + cy) + 0.5)) + ay * tTop;
                precise float g = c.y - c.x, h = c.z - c.x;
                precise float k = (c.x - c.y) - (c.z - c.w);
                precise float alpha = (k * ax) * ay;
                precise float beta = ((g * ax + h * ay) + k * (a0 * ay + b0 * ax)) - 1.0;
                precise float gamma = ((c.x + g * a0) + (h * b0 + (k * a0) * b0)) - tTop;
                precise float sEnd = tExit - tTop;
                precise float lin = big;
                if (beta < 0.0) lin = -gamma / beta;
                precise float disc = beta * beta - (4.0 * alpha) * gamma;
                precise float root = sqrt(disc > 0.0 ? disc : 0.0);
                precise float q = -0.5 * (beta + (beta >= 0.0 ? root : -root));
                precise float r1 = big, r2 = big;
                if (q != 0.0) {
                    r1 = q / alpha;
                    r2 = gamma / q;
                }
                precise float s1 = r1 >= 0.0 ? r1 : big;
                precise float s2 = r2 >= 0.0 ? r2 : big;
                precise float quad = big;
                if (disc >= 0.0) quad = s1 < s2 ? s1 : s2;
                precise float sHit = gamma <= 0.0 ? 0.0 : (alpha == 0.0 ? lin : quad);
                found = sHit <= sEnd;
                tHit = tTop + sHit;
            }
            bool descend = into && level > 0.0;
            if (found) {
                t = tHit;
                hit = true;
                done = true;
            } else if (descend) {
                t = tTop;
                level = level - 1.0;
                size = size * 0.5;
                precise float px = Ahead(floor(x0 + ax * t) - tileX, cx, ax);
                precise float py = Ahead(floor(y0 + ay * t) - tileY, cy, ay);
                cx = ClampCell(px, nx, ex - 1.0);
                cy = ClampCell(py, ny, ey - 1.0);
            } else {  // cross into the neighbour node
                t = t > tExit ? t : tExit;
                precise float px = Ahead(floor(x0 + ax * t) - tileX, cx, ax);
                precise float py = Ahead(floor(y0 + ay * t) - tileY, cy, ay);
                if (xFirst) {
                    precise float n = ax > 0.0 ? ex : nx - 1.0;
                    if (n > W - 1.0) {
                        n = n - W;
                        tileX = tileX + W;
                    } else if (n < 0.0) {
                        n = n + W;
                        tileX = tileX - W;
                    }
                    cx = n;
                    cy = ClampCell(py, ny, ey - 1.0);
                } else {
                    precise float n = ay > 0.0 ? ey : ny - 1.0;
                    if (n > H - 1.0) {
                        n = n - H;
                        tileY = tileY + H;
                    } else if (n < 0.0) {
                        n = n + H;
                        tileY = tileY - H;
                    }
                    cy = n;
                    cx = ClampCell(px, nx, ex - 1.0);
                }
                if (level < top) {
                    level = level + 1.0;
                    size = size * 2.0;
                }
                if (t >= 1.0) done = true;
            }
        }
        if (nCoarse >= uMaxSteps) done = true;
        more = uEarlyExit ? !done : nCoarse < uMaxSteps;
        if (more && !Take()) more = false;
    } while (more);

    precise float tr = t < 1.0 ? t : 1.0;
    MarchResult r;
    r.uvHit = At(ray, tr);
    r.depthHit = tr;
    r.nCoarse = nCoarse;
    r.nRefine = 0;
    r.nFetches = int(gUsed);
    r.hit = hit;
    r.budgetExhausted = gExhausted;
    return r;
}

#define RS_ANSWERS_AT_STOP 1
