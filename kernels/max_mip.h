// The hierarchical tracers over the cell pyramid (texture/cell_pyramid.h): maximum-mipmap
// traversal with an exact ray/bilinear-patch hit (Tevs, Ihrke & Seidel 2008, "Maximum
// Mipmaps for Fast, Accurate, and Scalable Dynamic Height Field Rendering") and quadtree
// displacement mapping (Drobot 2009, "Quadtree Displacement Mapping with Height
// Blending", GPU Pro). Two methods, one source: MaxMip<kExact>. docs/methods/maxmip.md
// and docs/methods/qdm.md.
//
// Cell space: x = u W - 0.5, y = v H - 0.5, so cell (i, j) = [i, i+1) x [j, j+1) lies
// between four texel centres and the bilinear surface over it interpolates its corners.
// The ray is X(t) = x0 + ax t, Y(t) = y0 + ay t with x0 = uEntry W - 0.5, ax = du W (and
// so for y), t its depth; in a cell the patch test takes the ray's offsets from the
// cell's corner as (uEntry W - (cell + 0.5)) + ax t, which keeps their rounding at the
// scale of the travel, not of the map coordinate. The state holds the ray depth t, the
// level k with its node size s = 2^k, and the level-0 cell (cx, cy) in [0, W) x [0, H) of
// the tile whose origin is (tileX, tileY) in cell units (tiles repeat: the pyramid is
// built for --wrap repeat). The current node is the level-k node holding (cx, cy): cells
// [nx, ex) with nx = floor(cx / s) s, ex = min(nx + s, W), and likewise in y.
//
// One trip = one fetch = one iteration:
//   fetch the node's least depth d; the ray leaves the node's column at
//     tExit = min over the axes of (boundary - x0) / ax   (the boundary ahead: tileX + ex
//     when ax > 0, tileX + nx when ax < 0; none when ax = 0)
//   tTop = max(t, d): where the ray reaches the node's top (the surface in the node is no
//     shallower than d, so nothing before tTop is hit).
//   tTop <= tExit, k > 0: descend: t = tTop, k = k - 1, (cx, cy) = the cell under the ray
//     point, never behind the current cell along the ray's motion (Ahead: a point on a
//     border, or rounded back across one, takes the cell ahead, so the traversal never
//     returns to a node it left), clamped into the node (the child lies inside the
//     parent);
//   tTop <= tExit, k = 0: the cell's box is entered:
//     maxmip fetches the cell's four corners instead of its pyramid value (one fetch,
//       four texels; d = their minimum) and intersects the ray with the bilinear patch
//       on [tTop, tExit]: S(a, b) = c00 + g a + h b + k' a b, a, b the ray's offsets in
//       the cell, g = c10 - c00, h = c01 - c00, k' = c00 - c10 - c01 + c11. With
//       s = t - tTop, S - t = alpha s^2 + beta s + gamma (alpha = k' ax ay,
//       beta = g ax + h ay + k' (a0 ay + b0 ax) - 1, gamma = S(a0, b0) - tTop): the
//       least root s in [0, tExit - tTop] (gamma <= 0: s = 0; alpha = 0: -gamma / beta;
//       else the stable quadratic roots q = -(beta + sign(beta) sqrt(disc)) / 2,
//       q / alpha and gamma / q) is the first hit, exact up to float rounding. No root:
//       cross.
//     qdm stops at the box's top, t = tTop (Drobot's descent ends on the finest level;
//       the point lies on or above the bilinear surface, at most one cell's relief
//       above it);
//   otherwise cross: t = tExit, (cx, cy) = the first cell of the neighbour node across
//     the boundary the ray leaves by (x first on a tie; wrapping to the next tile), the
//     other index the cell under the ray point (Ahead) clamped into the node, and
//     k = min(k + 1, top) (Tevs: up one level after every crossing, so the traversal
//     climbs back over empty space).
// The search starts at the top node (one node over the tile) at t = 0 and ends at the
// hit, at t >= 1 (no hit: cannot happen on exact values, kept for rounding) or after
// max_steps trips. Every point it visits lies above the bilinear surface until the hit
// (the node boxes bound it), so a lane stopped early answers a conservative point
// (kAnswersAtStop). Fixed loops (early_exit = 0): a finished lane keeps fetching its last
// node up to max_steps trips, result latched.
//
// qdm's refinement (`refine`, kernels/refine.h) runs inside the finest box: two height
// fetches (Fetch::level -2, the height sampler) at A = the box top and B = where the ray
// leaves the cell (at most the bottom) bracket it. A inside: A is the hit. B inside: the
// refinement runs on [A, B] (binary from B back over B - A). B outside (the surface is
// not crossed in this cell): the descent resumes past the cell while trips remain, else
// A stays the answer. The bracket fetches are fetches, not iterations.
//
// Cell indices and levels are small integers kept exactly in float lanes (lanes.h); all
// comparisons are exact, and the GLSL twin (kernels/glsl/max_mip.glsl) computes the same
// float operations in the same order.
#pragma once

#include <array>

#include "kernels/kernel.h"
#include "kernels/refine.h"

namespace reliefsim {

namespace detail {

template <bool kExact>
struct MaxMipPreset;
inline constexpr ParamSpec kMaxStepsParam = {
    "max_steps", 512, 1, 65535, true, "most traversal iterations (one fetch each)",
    "uMaxSteps"};

template <>
struct MaxMipPreset<true> {
    static constexpr std::array<ParamSpec, 3> kParams = {kMaxStepsParam, kEarlyExitParam,
                                                         kBudgetParam};
    static constexpr std::string_view
        kName = "maxmip",
        kTitle = "maximum-mipmap traversal with an exact bilinear-patch hit",
        kSource = "Tevs, Ihrke & Seidel 2008 (I3D), maximum mipmaps";
};
template <>
struct MaxMipPreset<false> {
    static constexpr std::array<ParamSpec, 6> kParams = {
        kMaxStepsParam,
        RefineParam(Refinement::None),
        RefineSteps(5, "refinement iterations in the finest box's bracket"),
        kSecantTolerance,
        kEarlyExitParam,
        kBudgetParam};
    static constexpr std::string_view kName = "qdm",
                                      kTitle = "quadtree displacement mapping",
                                      kSource =
                                          "Drobot 2009 (GPU Pro), quadtree "
                                          "displacement mapping";
};

}  // namespace detail

template <bool kExact>
struct MaxMip {
    using Preset = detail::MaxMipPreset<kExact>;
    static constexpr bool kReadsPyramid = true;
    static constexpr bool kAnswersAtStop = true;
    static constexpr auto& kParams = Preset::kParams;
    static constexpr std::array<GlslConstant, 1> kGlslConstants = {
        GlslConstant{"uExactPatch", kExact ? 1 : 0}};

    static const KernelInfo& Info() {
        static const KernelInfo info{Preset::kName,
                                     Preset::kTitle,
                                     Preset::kSource,
                                     kParams,
                                     {},
                                     "max_mip.glsl",
                                     kGlslConstants,
                                     "",
                                     1,
                                     kAnswersAtStop,
                                     kReadsPyramid};
        return info;
    }

    struct Params {
        int maxSteps = 512;
        bool earlyExit = true;
        Refinement refine = Refinement::None;  ///< qdm only
        int refineSteps = 0;
        float secantTolerance = 0.01f;
    };
    static Params FromValues(const ParamValues& v) {
        auto get = [&](std::string_view name) { return ParamValue(v, kParams, name); };
        Params p;
        p.maxSteps = int(get("max_steps"));
        p.earlyExit = get("early_exit") != 0.0;
        p.refine = Refinement(int(get("refine")));
        p.refineSteps = int(get("refine_steps"));
        p.secantTolerance = float(get("secant_tolerance"));
        return p;
    }

    /// The top level of a W x H cell pyramid (texture/cell_pyramid.h: halving with
    /// ceil until 1x1).
    static int TopLevel(int w, int h) {
        int k = 0;
        while (w > 1 || h > 1) w = (w + 1) / 2, h = (h + 1) / 2, ++k;
        return k;
    }

    /// The phases of a lane: the traversal, qdm's two bracket fetches (the box top A
    /// and the cell's exit B) and its refinement.
    enum Phase { kTraverse = 0, kAbove = 1, kBelow = 2, kRefine = 3, kDone = 4 };

    template <class L>
    struct State {
        using F = typename L::F;
        F xr, yr;          // uEntry W, vEntry H
        F x0, y0, ax, ay;  // the ray in cell space
        F t;               // its depth
        F level, size;     // the current node's level and 2^level
        F cx, cy;          // the level-0 cell in the tile
        F tileX, tileY;    // the tile's origin in cells
        F nCoarse, nRefine;
        F phase;
        F tA, hA, tB, hB;  // qdm's bracket: the box top and the cell's exit
        F tResult;         // the answer once the traversal has ended
        Refiner<L> q;
        float top = 0.0f;  // the top level
        typename L::M hit;
        typename L::M boxFound;  // the traversal reached its finest box (latched)
    };

    /// The fetch of the state's current node (maxmip: the corners at level 0).
    template <class L>
    RS_INLINE static void NodeFetch(const LaneRay<L>& ray, const State<L>& s,
                                    Fetch<L>& f) {
        using F = typename L::F;
        using I = typename L::I;
        f.t = s.t;
        f.u = ray.U(s.t);
        f.v = ray.V(s.t);
        F level = s.level;
        if constexpr (kExact) level = Select(s.level == F(0.0f), F(-1.0f), s.level);
        f.level = stdx::static_simd_cast<I>(level);
        f.cx = stdx::static_simd_cast<I>(s.cx);
        f.cy = stdx::static_simd_cast<I>(s.cy);
    }

    /// A height fetch (Fetch::level -2: the height sampler, --filter) at ray depth t.
    template <class L>
    RS_INLINE static void HeightFetch(const LaneRay<L>& ray, const typename L::M& m,
                                      const typename L::F& t, Fetch<L>& f) {
        using F = typename L::F;
        using I = typename L::I;
        Assign(m, f.t, t);
        Assign(m, f.u, ray.U(t));
        Assign(m, f.v, ray.V(t));
        const I level = f.level;
        f.level = stdx::static_simd_cast<I>(
            Select(m, F(-2.0f), stdx::static_simd_cast<F>(level)));
    }

    /// The first cell index and tile origin of cell coordinate x in a tile of n cells.
    template <class F>
    RS_INLINE static void CellOf(const F& x, float n, F& cell, F& tile) {
        const F fx = stdx::floor(x);
        tile = stdx::floor(fx / F(n)) * F(n);
        cell = fx - tile;
        cell = Select(cell > F(n - 1.0f), F(n - 1.0f), cell);
        cell = Select(cell < F(0.0f), F(0.0f), cell);
    }

    template <class L>
    static void Begin(const Params&, const LaneRay<L>& ray, State<L>& s,
                      Fetch<L>& first) {
        using F = typename L::F;
        const F zero(0.0f);
        const float W = ray.mapW, H = ray.mapH;
        s.xr = ray.uEntry * F(W);
        s.yr = ray.vEntry * F(H);
        s.x0 = s.xr - F(0.5f);
        s.y0 = s.yr - F(0.5f);
        s.ax = ray.du * F(W);
        s.ay = ray.dv * F(H);
        s.t = zero;
        const int top = TopLevel(int(W), int(H));
        s.top = float(top);
        s.level = F(s.top);
        s.size = F(float(1 << top));
        CellOf(s.x0, W, s.cx, s.tileX);
        CellOf(s.y0, H, s.cy, s.tileY);
        s.nCoarse = s.nRefine = zero;
        s.phase = F(float(kTraverse));
        s.tA = s.hA = s.tB = s.hB = s.tResult = zero;
        s.q.Clear();
        s.hit = s.boxFound = typename L::M(false);
        NodeFetch(ray, s, first);
    }

    /// c clamped to [lo, hi].
    template <class F>
    RS_INLINE static F Clamp(const F& c, const F& lo, const F& hi) {
        return Select(c < lo, lo, Select(c > hi, hi, c));
    }

    /// The cell under the ray point p on an axis the ray moves along by a, never behind
    /// the state's cell c: the ray's cell index only grows (a > 0) or shrinks (a < 0),
    /// so a point on a cell border, or rounded back across one, takes the cell ahead.
    template <class F>
    RS_INLINE static F Ahead(const F& p, const F& c, const F& a) {
        const F zero(0.0f);
        return Select(a > zero, MaxSse(p, c), Select(a < zero, MinSse(p, c), p));
    }

    /// The current node's cells [nx, ex) x [ny, ey) and where the ray leaves its
    /// column: tx, ty per axis (3e38 when it does not move along it).
    template <class F>
    struct Node {
        F nx, ny, ex, ey, tx, ty;
    };
    template <class L>
    RS_INLINE static Node<typename L::F> CurrentNode(const LaneRay<L>& ray,
                                                     const State<L>& s) {
        using F = typename L::F;
        const F zero(0.0f), big(3.0e38f);
        Node<F> n;
        n.nx = stdx::floor(s.cx / s.size) * s.size;
        n.ny = stdx::floor(s.cy / s.size) * s.size;
        n.ex = MinSse(n.nx + s.size, F(ray.mapW));
        n.ey = MinSse(n.ny + s.size, F(ray.mapH));
        const F bx = Select(s.ax > zero, s.tileX + n.ex, s.tileX + n.nx);
        const F by = Select(s.ay > zero, s.tileY + n.ey, s.tileY + n.ny);
        n.tx = Select(s.ax != zero, (bx - s.x0) / s.ax, big);
        n.ty = Select(s.ay != zero, (by - s.y0) / s.ay, big);
        return n;
    }

    /// On one axis the ray moves along by a, the neighbour node's first cell across the
    /// boundary of node cells [nx, ex): ex ahead (a > 0), nx - 1 behind, wrapped into
    /// [0, n) with the tile's origin moved by n on lanes m.
    template <class F, class M>
    RS_INLINE static F NextCell(const M& m, const F& a, const F& nx, const F& ex,
                                const F& n, F& tile) {
        const F zero(0.0f), one(1.0f);
        F c = Select(a > zero, ex, nx - one);
        const M up = m && (c > n - one), down = m && (c < zero);
        Assign(up, c, c - n);
        Assign(up, tile, tile + n);
        Assign(down, c, c + n);
        Assign(down, tile, tile - n);
        return c;
    }

    /// Moves lanes m across the boundary of node n the ray leaves by, at depth tExit,
    /// into the neighbour node's first cell, one level up (see the file comment).
    template <class L>
    RS_INLINE static void Cross(const LaneRay<L>& ray, State<L>& s,
                                const typename L::M& m, const Node<typename L::F>& n,
                                const typename L::F& tExit) {
        using F = typename L::F;
        using M = typename L::M;
        const F one(1.0f), W(ray.mapW), H(ray.mapH);
        const M xFirst = n.tx <= n.ty;
        Assign(m, s.t, MaxSse(s.t, tExit));
        const F px = Ahead(stdx::floor(s.x0 + s.ax * s.t) - s.tileX, s.cx, s.ax);
        const F py = Ahead(stdx::floor(s.y0 + s.ay * s.t) - s.tileY, s.cy, s.ay);
        const M acrossX = m && xFirst, acrossY = m && !xFirst;
        const F cx = NextCell(acrossX, s.ax, n.nx, n.ex, W, s.tileX);
        const F cy = NextCell(acrossY, s.ay, n.ny, n.ey, H, s.tileY);
        Assign(acrossX, s.cx, cx);
        Assign(acrossX, s.cy, Clamp(py, n.ny, n.ey - one));
        Assign(acrossY, s.cy, cy);
        Assign(acrossY, s.cx, Clamp(px, n.nx, n.ex - one));
        const M up = m && (s.level < F(s.top));
        Assign(up, s.level, s.level + one);
        Assign(up, s.size, s.size * F(2.0f));
    }

    template <class L>
    RS_INLINE static typename L::M Step(const Params& p, const LaneRay<L>& ray,
                                        State<L>& s, const Sample<L>& x,
                                        const typename L::M& active, Fetch<L>& next) {
        using F = typename L::F;
        using M = typename L::M;
        const F zero(0.0f), one(1.0f), big(3.0e38f);
        const Refinement rf = kExact ? Refinement::None : p.refine;
        // Each lane's phase as the trip began (a phase set below acts next trip).
        const M trav = active && (s.phase == F(float(kTraverse)));
        const M above = active && (s.phase == F(float(kAbove)));
        const M below = active && (s.phase == F(float(kBelow)));
        const M refine = active && (s.phase == F(float(kRefine)));
        Assign(trav, s.nCoarse, s.nCoarse + one);
        const M work = trav && !s.boxFound;
        M ended(false);  // below the bottom without a hit (rounding only)
        if (Any(work)) {
            const Node<F> n = CurrentNode(ray, s);
            const F tExit = MinSse(n.tx, n.ty);
            const F tTop = MaxSse(s.t, x.h);
            const M into = tTop <= tExit;
            M found = work && (s.level == zero) && into;
            F tHit = tTop;
            if constexpr (kExact) {
                if (Any(found)) {
                    // The bilinear patch over cell (cx, cy) against the ray on [tTop,
                    // tExit] (see the file comment; the twin's code is the same).
                    const F c00 = x.corners[0], c10 = x.corners[1];
                    const F c01 = x.corners[2], c11 = x.corners[3];
                    // The offsets in the cell, from the entry's offset to the cell's
                    // corner (exact for power-of-two sizes) plus the travel: rounded
                    // once at the travel's magnitude, not at the map coordinate's.
                    const F a0 = (s.xr - ((s.tileX + s.cx) + F(0.5f))) + s.ax * tTop;
                    const F b0 = (s.yr - ((s.tileY + s.cy) + F(0.5f))) + s.ay * tTop;
                    const F g = c10 - c00, h = c01 - c00;
                    const F k = (c00 - c10) - (c01 - c11);
                    const F alpha = (k * s.ax) * s.ay;
                    const F beta =
                        ((g * s.ax + h * s.ay) + k * (a0 * s.ay + b0 * s.ax)) - one;
                    const F gamma = ((c00 + g * a0) + (h * b0 + (k * a0) * b0)) - tTop;
                    const F sEnd = tExit - tTop;
                    // alpha = 0: the linear root where beta < 0.
                    const F lin = Select(beta < zero, -gamma / beta, big);
                    const F disc = beta * beta - (F(4.0f) * alpha) * gamma;
                    const F root = stdx::sqrt(MaxSse(disc, zero));
                    const F q = F(-0.5f) * (beta + Select(beta >= zero, root, -root));
                    const F r1 = Select(q != zero, q / alpha, big);
                    const F r2 = Select(q != zero, gamma / q, big);
                    const F s1 = Select(r1 >= zero, r1, big);
                    const F s2 = Select(r2 >= zero, r2, big);
                    const F quad = Select(disc >= zero, MinSse(s1, s2), big);
                    const F sHit =
                        Select(gamma <= zero, zero, Select(alpha == zero, lin, quad));
                    found = found && (sHit <= sEnd);
                    tHit = tTop + sHit;
                }
            }
            const M descend = work && into && (s.level > zero);
            const M cross = work && !descend && !found;
            Assign(found, s.t, tHit);
            s.boxFound = s.boxFound || found;
            // qdm's bracket end B: where the ray leaves the cell (at most the bottom).
            Assign(found, s.tB, MinSse(tExit, one));
            if (Any(descend)) {
                Assign(descend, s.t, tTop);
                Assign(descend, s.level, s.level - one);
                Assign(descend, s.size, s.size * F(0.5f));
                const F px = Ahead(stdx::floor(s.x0 + s.ax * s.t) - s.tileX, s.cx, s.ax);
                const F py = Ahead(stdx::floor(s.y0 + s.ay * s.t) - s.tileY, s.cy, s.ay);
                Assign(descend, s.cx, Clamp(px, n.nx, n.ex - one));
                Assign(descend, s.cy, Clamp(py, n.ny, n.ey - one));
            }
            if (Any(cross)) {
                Cross(ray, s, cross, n, tExit);
                ended = cross && (s.t >= one);
            }
        }
        // The end of the traversal: its box found (at once, or after max_steps trips in
        // fixed loops), below the bottom, or out of trips.
        const M outOfTrips = trav && (s.nCoarse >= F(float(p.maxSteps)));
        const M leave = (trav && s.boxFound && (p.earlyExit ? trav : outOfTrips)) ||
                        ended || (outOfTrips && !s.boxFound);
        M want = trav && !leave;
        F tq = s.t;
        M heightNext(false);
        if (Any(leave)) {
            Assign(leave, s.tResult, s.t);
            Assign(leave, s.phase, F(float(kDone)));
            s.hit = s.hit || (leave && s.boxFound);
            if (rf != Refinement::None) {  // qdm: fetch the box top A
                const M bracket = leave && s.boxFound;
                Assign(bracket, s.tA, s.t);
                Assign(bracket, s.phase, F(float(kAbove)));
                Assign(bracket, tq, s.t);
                heightNext = heightNext || bracket;
            }
        }
        if constexpr (!kExact) {
            if (rf != Refinement::None) {
                M startRefine(false), refineNext(false);
                if (Any(above)) {  // A sampled: inside already, else fetch B
                    Assign(above, s.hA, x.h);
                    const M inside = above && (s.tA >= x.h);
                    Assign(above, s.phase, F(float(kDone)));
                    const M toB = above && !inside;
                    Assign(toB, s.phase, F(float(kBelow)));
                    Assign(toB, tq, s.tB);
                    heightNext = heightNext || toB;
                }
                if (Any(below)) {  // B sampled: refine in [A, B], or go on past the cell
                    Assign(below, s.hB, x.h);
                    const M holds = below && (s.tB >= x.h);
                    Assign(below, s.phase, F(float(kDone)));
                    startRefine = holds;
                    // The surface is not crossed in the cell: resume the traversal
                    // beyond it while trips remain (else A stays the answer).
                    const M resume =
                        below && !holds && (s.nCoarse < F(float(p.maxSteps)));
                    if (Any(resume)) {
                        // The state is still the cell's (level 0, its box top t = A).
                        const Node<F> n = CurrentNode(ray, s);
                        Cross(ray, s, resume, n, MinSse(n.tx, n.ty));
                        s.boxFound = s.boxFound && !resume;
                        s.hit = s.hit && !resume;
                        Assign(resume, s.phase, F(float(kTraverse)));
                        const M over = resume && (s.t >= one);
                        Assign(over, s.phase, F(float(kDone)));
                        Assign(over, s.tResult, s.t);
                        want = want || (resume && !over);
                    }
                }
                if (Any(refine)) {  // consume a refinement sample
                    Assign(refine, s.nRefine, s.nRefine + one);
                    s.q.Consume(rf, refine, x.h, p.secantTolerance);
                    refineNext = refine;
                }
                if (Any(startRefine)) {
                    const M loop = s.q.Start(rf, startRefine, s.tA, s.hA, s.tB, s.hB,
                                             s.tB - s.tA, s.tResult, s.nRefine);
                    refineNext = refineNext || loop;
                }
                if (Any(refineNext)) {  // the top of the refinement loop
                    Assign(refineNext, s.phase, F(float(kDone)));
                    const M go = s.q.Next(rf, refineNext, s.nRefine, p.refineSteps,
                                          p.earlyExit, s.tResult, tq);
                    Assign(go, s.phase, F(float(kRefine)));
                    heightNext = heightNext || go;
                }
            }
        }
        NodeFetch(ray, s, next);
        HeightFetch(ray, heightNext, tq, next);
        return want || heightNext;
    }

    template <class L>
    static void End(const Params&, const LaneRay<L>& ray, const State<L>& s,
                    LaneOutcome<L>& out) {
        using F = typename L::F;
        // A lane stopped in the traversal or the bracket answers where the ray is (on
        // or above the surface); after it, the traversal's or the refinement's answer.
        const F t0 =
            Select(s.phase == F(float(kTraverse)) || s.phase == F(float(kAbove)) ||
                       s.phase == F(float(kBelow)),
                   s.t, s.tResult);
        const F t = MinSse(t0, F(1.0f));
        out.u = ray.U(t);
        out.v = ray.V(t);
        out.depth = t;
        out.nCoarse = s.nCoarse;
        out.nRefine = s.nRefine;
        out.hit = s.hit;
    }
};

using MaxMipKernel = MaxMip<true>;
using QdmKernel = MaxMip<false>;

}  // namespace reliefsim
