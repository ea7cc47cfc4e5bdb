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

// The traversal's state (MaxMip::State), shared by the helpers below.
const int kMmTraverse = 0, kMmAbove = 1, kMmBelow = 2, kMmRefine = 3, kMmDone = 4;
precise float gX0, gY0, gAx, gAy, gT, gLevel, gSize, gCx, gCy, gTileX, gTileY, gTop;

// MaxMip::CurrentNode: the node's cells [nx, ex) x [ny, ey) and the exits tx, ty.
void CurrentNode(out float nx, out float ny, out float ex, out float ey, out float tx,
                 out float ty) {
    const float big = 3.0e38;
    precise float W = uMapSize.x, H = uMapSize.y;
    precise float pnx = floor(gCx / gSize) * gSize;
    precise float pny = floor(gCy / gSize) * gSize;
    precise float exs = pnx + gSize, eys = pny + gSize;
    precise float pex = exs < W ? exs : W;
    precise float pey = eys < H ? eys : H;
    precise float bx = gAx > 0.0 ? gTileX + pex : gTileX + pnx;
    precise float by = gAy > 0.0 ? gTileY + pey : gTileY + pny;
    precise float ptx = big, pty = big;
    if (gAx != 0.0) ptx = (bx - gX0) / gAx;
    if (gAy != 0.0) pty = (by - gY0) / gAy;
    nx = pnx;
    ny = pny;
    ex = pex;
    ey = pey;
    tx = ptx;
    ty = pty;
}

// MaxMip::NextCell: the neighbour node's first cell on one axis, wrapped into [0, n).
float NextCell(float a, float nx, float ex, float n, inout float tile) {
    precise float c = a > 0.0 ? ex : nx - 1.0;
    if (c > n - 1.0) {
        c = c - n;
        tile = tile + n;
    } else if (c < 0.0) {
        c = c + n;
        tile = tile - n;
    }
    return c;
}

// MaxMip::Cross: across the boundary the ray leaves node (nx..ey) by, at depth tExit.
void Cross(float nx, float ny, float ex, float ey, float tx, float ty, float tExit) {
    precise float W = uMapSize.x, H = uMapSize.y;
    bool xFirst = tx <= ty;
    gT = gT > tExit ? gT : tExit;
    precise float px = Ahead(floor(gX0 + gAx * gT) - gTileX, gCx, gAx);
    precise float py = Ahead(floor(gY0 + gAy * gT) - gTileY, gCy, gAy);
    if (xFirst) {
        gCx = NextCell(gAx, nx, ex, W, gTileX);
        gCy = ClampCell(py, ny, ey - 1.0);
    } else {
        gCy = NextCell(gAy, ny, ey, H, gTileY);
        gCx = ClampCell(px, nx, ex - 1.0);
    }
    if (gLevel < gTop) {
        gLevel = gLevel + 1.0;
        gSize = gSize * 2.0;
    }
}

MarchResult March(MarchInput ray) {
    const float big = 3.0e38;
    precise float W = uMapSize.x, H = uMapSize.y;
    precise float xr = ray.uvEntry.x * W;
    precise float yr = ray.uvEntry.y * H;
    gX0 = xr - 0.5;
    gY0 = yr - 0.5;
    gAx = ray.dirUv.x * W;
    gAy = ray.dirUv.y * H;
    gT = 0.0;
    gTop = float(uPyramidTop);
    gLevel = gTop;
    gSize = float(1 << uPyramidTop);
    // MaxMip::CellOf
    precise float fx = floor(gX0);
    gTileX = floor(fx / W) * W;
    precise float cx = fx - gTileX;
    cx = cx > W - 1.0 ? W - 1.0 : cx;
    gCx = cx < 0.0 ? 0.0 : cx;
    precise float fy = floor(gY0);
    gTileY = floor(fy / H) * H;
    precise float cy = fy - gTileY;
    cy = cy > H - 1.0 ? H - 1.0 : cy;
    gCy = cy < 0.0 ? 0.0 : cy;
    int nCoarse = 0, nRefine = 0;
    bool hit = false, boxFound = false, more = true;
    int phase = kMmTraverse;
    precise float tA = 0.0, hA = 0.0, tB = 0.0, hB = 0.0, tResult = 0.0, tq = 0.0;
    Refiner q = RefinerClear();
    int refinement = uExactPatch != 0 ? kRefineNone : uRefinement;

    gUsed = 0u;
    gExhausted = false;
    Take();  // the first fetch (a budget, when set, is >= 1)
    do {
        RS_ON_TRIP();
        int phase0 = phase;  // the phase as the trip began
        vec4 c = vec4(0.0);
        precise float d;
        if (phase0 == kMmTraverse) {
            // The fetch of the current node (MaxMip::NodeFetch).
            int l = int(gLevel), i = int(gCx), j = int(gCy);
            if (uExactPatch != 0 && l == 0) {
                c = Corners(i, j);
                precise float m0 = c.x < c.y ? c.x : c.y;
                precise float m1 = c.z < c.w ? c.z : c.w;
                d = m0 < m1 ? m0 : m1;
            } else {
                d = texelFetch(uPyramid, ivec2(uPyramidOffset[l] + (i >> l), j >> l), 0).r;
            }
            RS_ON_SAMPLE(gT, At(ray, gT), d);
        } else {  // a height fetch (level -2): the bracket and the refinement
            d = SampleHeight(At(ray, tq));
            RS_ON_SAMPLE(tq, At(ray, tq), d);
        }
        bool want = false, heightNext = false;
        if (phase0 == kMmTraverse) {
            nCoarse = nCoarse + 1;
            bool ended = false;
            if (!boxFound) {
                precise float nx, ny, ex, ey, tx, ty;
                CurrentNode(nx, ny, ex, ey, tx, ty);
                precise float tExit = tx < ty ? tx : ty;
                precise float tTop = gT > d ? gT : d;
                bool into = tTop <= tExit;
                bool found = gLevel == 0.0 && into;
                precise float tHit = tTop;
                if (uExactPatch != 0 && found) {
                    precise float a0 = (xr - ((gTileX + gCx) + 0.5)) + gAx * tTop;
                    precise float b0 = (yr - ((gTileY + gCy) + 0.5)) + gAy * tTop;
                    precise float g = c.y - c.x, h = c.z - c.x;
                    precise float k = (c.x - c.y) - (c.z - c.w);
                    precise float alpha = (k * gAx) * gAy;
                    precise float beta = ((g * gAx + h * gAy) + k * (a0 * gAy + b0 * gAx)) - 1.0;
                    precise float gamma = ((c.x + g * a0) + (h * b0 + (k * a0) * b0)) - tTop;
                    precise float sEnd = tExit - tTop;
                    precise float lin = big;
                    if (beta < 0.0) lin = -gamma / beta;
                    precise float disc = beta * beta - (4.0 * alpha) * gamma;
                    precise float root = sqrt(disc > 0.0 ? disc : 0.0);
                    precise float qq = -0.5 * (beta + (beta >= 0.0 ? root : -root));
                    precise float r1 = big, r2 = big;
                    if (qq != 0.0) {
                        r1 = qq / alpha;
                        r2 = gamma / qq;
                    }
                    precise float s1 = r1 >= 0.0 ? r1 : big;
                    precise float s2 = r2 >= 0.0 ? r2 : big;
                    precise float quad = big;
                    if (disc >= 0.0) quad = s1 < s2 ? s1 : s2;
                    precise float sHit = gamma <= 0.0 ? 0.0 : (alpha == 0.0 ? lin : quad);
                    found = sHit <= sEnd;
                    tHit = tTop + sHit;
                }
                bool descend = into && gLevel > 0.0;
                if (found) {
                    gT = tHit;
                    boxFound = true;
                    tB = tExit < 1.0 ? tExit : 1.0;
                } else if (descend) {
                    gT = tTop;
                    gLevel = gLevel - 1.0;
                    gSize = gSize * 0.5;
                    precise float px = Ahead(floor(gX0 + gAx * gT) - gTileX, gCx, gAx);
                    precise float py = Ahead(floor(gY0 + gAy * gT) - gTileY, gCy, gAy);
                    gCx = ClampCell(px, nx, ex - 1.0);
                    gCy = ClampCell(py, ny, ey - 1.0);
                } else {  // cross into the neighbour node
                    Cross(nx, ny, ex, ey, tx, ty, tExit);
                    ended = gT >= 1.0;
                }
            }
            bool outOfTrips = nCoarse >= uMaxSteps;
            bool leave = (boxFound && (uEarlyExit || outOfTrips)) || ended ||
                         (outOfTrips && !boxFound);
            want = !leave;
            if (leave) {
                tResult = gT;
                phase = kMmDone;
                if (boxFound) hit = true;
                if (refinement != kRefineNone && boxFound) {  // qdm: fetch the box top A
                    tA = gT;
                    phase = kMmAbove;
                    tq = gT;
                    heightNext = true;
                }
            }
        }
        bool startRefine = false, refineNext = false;
        if (phase0 == kMmAbove) {  // A sampled: inside already, else fetch B
            hA = d;
            phase = kMmDone;
            if (!(tA >= d)) {
                phase = kMmBelow;
                tq = tB;
                heightNext = true;
            }
        } else if (phase0 == kMmBelow) {  // B sampled: refine in [A, B], or go on
            hB = d;
            phase = kMmDone;
            bool holds = tB >= d;
            startRefine = holds;
            if (!holds && nCoarse < uMaxSteps) {
                precise float nx, ny, ex, ey, tx, ty;
                CurrentNode(nx, ny, ex, ey, tx, ty);
                Cross(nx, ny, ex, ey, tx, ty, tx < ty ? tx : ty);
                boxFound = false;
                hit = false;
                phase = kMmTraverse;
                if (gT >= 1.0) {
                    phase = kMmDone;
                    tResult = gT;
                } else {
                    want = true;
                }
            }
        } else if (phase0 == kMmRefine) {  // consume a refinement sample
            nRefine = nRefine + 1;
            RefineConsume(q, d);
            refineNext = true;
        }
        if (startRefine) {
            refineNext = RefineStart(q, tA, hA, tB, hB, tB - tA, tResult, nRefine);
        }
        if (refineNext) {  // the top of the refinement loop
            phase = kMmDone;
            if (RefineNext(q, nRefine, tResult, tq)) {
                phase = kMmRefine;
                heightNext = true;
            }
        }
        more = want || heightNext;
        if (more && !Take()) more = false;
    } while (more);

    precise float t0 = (phase == kMmTraverse || phase == kMmAbove || phase == kMmBelow)
                           ? gT : tResult;
    precise float tr = t0 < 1.0 ? t0 : 1.0;
    MarchResult r;
    r.uvHit = At(ray, tr);
    r.depthHit = tr;
    r.nCoarse = nCoarse;
    r.nRefine = nRefine;
    r.nFetches = int(gUsed);
    r.hit = hit;
    r.budgetExhausted = gExhausted;
    return r;
}

#define RS_ANSWERS_AT_STOP 1
