// The lane search's engine, compiled once per instruction set (cone_search_*.cpp): a
// 4x4 tile of apexes is 16 vector lanes (GCC vector extensions, lowered to one AVX-512,
// two AVX2 or four SSE registers), and one depth-first traversal of the min-depth
// pyramid (or, for acm4 and acm8, of rip-maps) serves them all. See maps/cone_search.h.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "maps/cone_search_lanes.h"

#if defined(__SSE4_1__)
#include <immintrin.h>
#endif

namespace reliefsim::detail {

// Internal linkage: every unit compiles its own copy for its instruction set, and none
// may stand in for another's at link time (so -Wpsabi's warning about 64-byte vectors
// passed by value below AVX-512 does not apply; maps/CMakeLists.txt turns it off).
namespace lanes {
namespace {

// A unit's lanes: RS_CONE_SEARCH_LANES (16, 8 or 4) before the include, one native
// register of its instruction set (wider generic vectors than the ISA's registers spill
// heavily: 16 lanes on AVX2 took ~5x the time of 8). The tile is kTileW x kTileH apexes,
// kTileW = kLaneTile; the tile rows of RunConeSearch's bands (kLaneTile texels high) are
// searched kTileH rows at a time.
#ifndef RS_CONE_SEARCH_LANES
#define RS_CONE_SEARCH_LANES 16
#endif
constexpr int kLanes = RS_CONE_SEARCH_LANES;
constexpr int kTileW = kLaneTile;
constexpr int kTileH = kLanes / kLaneTile;
static_assert(kTileH >= 1 && kTileW * kTileH == kLanes && kLaneTile % kTileH == 0);
typedef int32_t VI __attribute__((vector_size(4 * kLanes)));
typedef float VF __attribute__((vector_size(4 * kLanes)));

/// Bit k set where lane k of a comparison result (0 or -1) is set.
RS_INLINE uint32_t Bits(const VI& m) {
#if defined(__AVX512DQ__) && RS_CONE_SEARCH_LANES == 16
    __m512i v;
    static_assert(sizeof(v) == sizeof(m));
    __builtin_memcpy(&v, &m, sizeof(v));
    return _mm512_movepi32_mask(v);
#elif defined(__AVX2__) && RS_CONE_SEARCH_LANES == 8
    __m256 h;
    static_assert(sizeof(h) == sizeof(m));
    __builtin_memcpy(&h, &m, sizeof(h));
    return uint32_t(_mm256_movemask_ps(h));
#elif defined(__SSE4_1__) && RS_CONE_SEARCH_LANES == 4
    __m128 q;
    static_assert(sizeof(q) == sizeof(m));
    __builtin_memcpy(&q, &m, sizeof(q));
    return uint32_t(_mm_movemask_ps(q));
#else
    uint32_t b = 0;
    for (int k = 0; k < kLanes; ++k) b |= uint32_t(m[k] != 0) << k;
    return b;
#endif
}

/// Lane-wise square root (correctly rounded, as std::sqrt).
RS_INLINE VF Sqrt(const VF& v) {
#if defined(__AVX512F__) && RS_CONE_SEARCH_LANES == 16
    __m512 x;
    __builtin_memcpy(&x, &v, sizeof(x));
    x = _mm512_maskz_sqrt_ps(__mmask16(0xFFFF), x);  // (the unmasked form warns)
    VF r;
    __builtin_memcpy(&r, &x, sizeof(r));
    return r;
#elif defined(__AVX__) && RS_CONE_SEARCH_LANES == 8
    __m256 x;
    __builtin_memcpy(&x, &v, sizeof(x));
    x = _mm256_sqrt_ps(x);
    VF r;
    __builtin_memcpy(&r, &x, sizeof(r));
    return r;
#elif defined(__SSE4_1__) && RS_CONE_SEARCH_LANES == 4
    __m128 x;
    __builtin_memcpy(&x, &v, sizeof(x));
    x = _mm_sqrt_ps(x);
    VF r;
    __builtin_memcpy(&r, &x, sizeof(r));
    return r;
#else
    VF r;
    for (int k = 0; k < kLanes; ++k) r[k] = std::sqrt(v[k]);
    return r;
#endif
}

RS_INLINE VI Max(const VI& a, const VI& b) { return a > b ? a : b; }
RS_INLINE VI Min(const VI& a, const VI& b) { return a < b ? a : b; }
RS_INLINE VF Max(const VF& a, const VF& b) { return a > b ? a : b; }
RS_INLINE VF Min(const VF& a, const VF& b) { return a < b ? a : b; }
RS_INLINE VF ToFloat(const VI& v) { return __builtin_convertvector(v, VF); }

/// A float test passes every candidate whose exact q (CandidateQ, double) is below a
/// lane's best: thresholds are float(best) * (1 + 2^-16), far above the float rounding
/// of the test (a few 2^-24); depth differences below kTiny (whose squares could lose
/// precision) always pass. docs/cone_maps.md, "The lane search".
constexpr float kThresholdScale = 1.0f + 0x1p-16f;
constexpr float kTiny = 0x1p-40f;
/// The first-order cell bound skips a lane only where its lower bound exceeds the apex
/// by this much relative to the magnitudes summed (the float error of the bound's
/// evaluation is a few 2^-24 of them).
constexpr float kFirstOrderSlack = 0x1p-16f;

/// Whether the box of offsets [lo1, hi1] x [lo2, hi2] meets the closed quadrant of signs
/// (s1, s2) (0: either sign), a rip-map sector in its sheared coordinates: a bool for
/// ints, a lane mask for vectors (a point: lo = hi).
template <class T>
RS_INLINE auto MeetsQuadrant(int s1, int s2, const T& lo1, const T& hi1, const T& lo2,
                             const T& hi2) {
    auto ok = (T{} + 0) == 0;  // true: bool, or every lane set
    if (s1 > 0) ok = ok & (hi1 >= 0);
    if (s1 < 0) ok = ok & (lo1 <= 0);
    if (s2 > 0) ok = ok & (hi2 >= 0);
    if (s2 < 0) ok = ok & (lo2 <= 0);
    return ok;
}

/// Per lane, the box [lo1, hi1] x [lo2, hi2] clipped to the closed quadrant of signs
/// (s1, s2) about the lane's point (p1, p2).
RS_INLINE void ClipToQuadrant(int s1, int s2, const VF& p1, const VF& p2, VF& lo1,
                              VF& hi1, VF& lo2, VF& hi2) {
    if (s1 > 0) lo1 = Max(lo1, p1);
    if (s1 < 0) hi1 = Min(hi1, p1);
    if (s2 > 0) lo2 = Max(lo2, p2);
    if (s2 < 0) hi2 = Min(hi2, p2);
}

/// 0, 1, ..., kLanes - 1.
const VI kIota = [] {
    VI v{};
    for (int k = 0; k < kLanes; ++k) v[k] = k;
    return v;
}();

struct Node {
    int8_t level, tx, ty;  ///< pyramid level; wrap image (-1, 0, 1) in x and y
    uint16_t lanes;        ///< lanes still searching here
    int32_t cx, cy;        ///< cell at the level
};

/// A 4x4 tile of apexes and their running minima.
struct Tile {
    VI pi, pj;  ///< apex texel per lane
    VF a;       ///< apex depth per lane
    VF thr[kMaxSectors];
    VF rinv[kMaxSectors];  ///< 1 / sqrt(thr), rounded (0 while thr is +inf)
    double best[kMaxSectors][kLanes];
    int32_t argX[kMaxSectors][kLanes], argY[kMaxSectors][kLanes];  ///< unwrapped
    uint32_t valid = 0;  ///< lanes with an apex that can have blockers
    int x0 = 0, y0 = 0;
};

class Engine {
  public:
    explicit Engine(const ConeSearchData& d)
        : d_(d), g_(d.g), wx_(float(d.g.wx)), wy_(float(d.g.wy)) {}

    /// Searches every tile of tile rows [r0, r1).
    void Band(int r0, int r1) {
        const int tilesX = (d_.W + kTileW - 1) / kTileW;
        seedUp_.assign(size_t(tilesX) * kTileW * size_t(d_.nChannels), {kNoSeed, 0});
        for (int r = r0; r < r1; ++r) {
            for (int y = r * kLaneTile; y < std::min((r + 1) * kLaneTile, d_.H);
                 y += kTileH)
                Row(y, tilesX, y > r0 * kLaneTile);
            if (d_.progress) d_.progress->Add(1);
        }
    }

  private:
    /// The tiles of the kTileH texel rows from y; `up`: the row above was searched
    /// (its seeds are in seedUp_).
    void Row(int y, int tilesX, bool up) {
        for (int t = 0; t < tilesX; ++t) {
            Tile& tile = tile_;
            Begin(tile, t * kTileW, y);
            SeedFromNeighbours(tile, t, t > 0, up);
            if (tile.valid) {
                if (d_.rips.empty())
                    Traverse(tile);
                else
                    TraverseRipPass(tile, d_.rips[size_t(d_.ripPass)]);
            }
            Finish(tile, t);
        }
    }

    static constexpr int32_t kNoSeed = INT32_MIN;
    struct Seed {
        int32_t x, y;
    };

    void Begin(Tile& t, int x0, int y0) {
        t.x0 = x0;
        t.y0 = y0;
        t.valid = 0;
        for (int k = 0; k < kLanes; ++k) {
            const int i = x0 + k % kTileW, j = y0 + k / kTileW;
            const bool in = i < d_.W && j < d_.H;
            t.pi[k] = in ? i : x0;
            t.pj[k] = in ? j : y0;
            const float a = in ? d_.apex[size_t(j) * size_t(d_.W) + size_t(i)] : 0.0f;
            t.a[k] = a;
            if (in && a > d_.dmin) t.valid |= 1u << k;
        }
        for (int c = 0; c < d_.nChannels; ++c) {
            for (int k = 0; k < kLanes; ++k) {
                t.thr[c][k] = INFINITY;
                t.rinv[c][k] = 0.0f;
                t.best[c][k] = kInfQ;
                t.argX[c][k] = kNoSeed;
            }
        }
    }

    float DepthAt(int X, int Y) const {
        return d_.field
            ->depth[size_t(Wrap(Y, d_.H)) * size_t(d_.W) + size_t(Wrap(X, d_.W))];
    }
    uint8_t FlagsAt(int X, int Y) const {
        return d_.flags[size_t(Wrap(Y, d_.H)) * size_t(d_.W) + size_t(Wrap(X, d_.W))];
    }

    /// Lanes for which a texel with limiting flags `flags` is limiting in the direction
    /// class of the offset (dx, dy) (IsLimiting).
    VI LimitingLanes(const VI& dx, const VI& dy, uint8_t flags) const {
        const VI ax = Max(dx, -dx), ay = Max(dy, -dy);
        const VI m = Max(ax, ay);
        // (comparisons give -1 for true)
        const VI sgx = (dx < 0) - (dx > 0), sgy = (dy < 0) - (dy > 0);
        const VI sx = (2 * ax >= m) & sgx, sy = (2 * ay >= m) & sgy;
        const VI i9 = (sy + 1) * 3 + (sx + 1);
        const VI bit = i9 + (i9 > 4);
        return ((VI{} + int32_t(flags)) >> bit & 1) != 0;
    }

    /// Per channel, the lanes whose offset (dx, dy) lies in its sector (SectorMask).
    void Members(const VI& dx, const VI& dy, VI* member) const {
        switch (d_.sectors) {
            case ConeKind::Cone:
                member[0] = VI{} - 1;
                break;
            case ConeKind::Quad:
                member[0] = dx > 0;
                member[1] = dx < 0;
                member[2] = dy > 0;
                member[3] = dy < 0;
                break;
            case ConeKind::Acm4:
                member[0] = (dx >= 0) & (dy >= 0);
                member[1] = (dx <= 0) & (dy >= 0);
                member[2] = (dx <= 0) & (dy <= 0);
                member[3] = (dx >= 0) & (dy <= 0);
                break;
            default: {  // Acm8: closed 45-degree sectors in uv space
                const VI vx = dx * g_.h, vy = dy * g_.w;
                member[0] = (vy >= 0) & (vx >= vy);
                member[1] = (vx >= 0) & (vy >= vx);
                member[2] = (vx <= 0) & (vy >= -vx);
                member[3] = (vy >= 0) & (-vx >= vy);
                member[4] = (vy <= 0) & (-vx >= -vy);
                member[5] = (vx <= 0) & (-vy >= -vx);
                member[6] = (vx >= 0) & (-vy >= vx);
                member[7] = (vy <= 0) & (vx >= -vy);
                break;
            }
        }
    }

    /// Lanes whose window holds the texel at unwrapped (X, Y) of depth b and for which
    /// it can lower a channel's minimum (a superset: Exact decides).
    uint32_t TexelLanes(const Tile& t, int X, int Y, float b, uint8_t flags) const {
        const VI dx = X - t.pi, dy = Y - t.pj;
        const VI inWindow = (dx >= -g_.halfX) & (dx <= g_.halfX) & (dy >= -g_.halfY) &
                            (dy <= g_.halfY) & (t.a > b);
        if (!Bits(inWindow)) return 0;
        const VF fx = ToFloat(dx), fy = ToFloat(dy);
        const VF s = fx * fx * wx_ + fy * fy * wy_;
        const VF dd = t.a - b;
        const VF d2 = dd * dd;
        const VI tiny = dd < kTiny;
        VI base = inWindow;
        if (d_.limiting) base &= LimitingLanes(dx, dy, flags);
        VI member[kMaxSectors];
        Members(dx, dy, member);
        VI any{};
        for (int c = 0; c < d_.nChannels; ++c)
            any |= member[c] & (tiny | ~(s >= t.thr[c] * d2));
        return Bits(base & any);
    }

    /// The exact candidate of the texel at unwrapped (X, Y) for lane k.
    void Exact(Tile& t, int k, int X, int Y, float b) {
        const int dx = X - t.pi[k], dy = Y - t.pj[k];
        if (d_.limiting) {
            int sx, sy;
            OffsetClass(dx, dy, sx, sy);
            if (!(FlagsAt(X, Y) >> ClassBit(sx, sy) & 1u)) return;
        }
        ExactIn(t, k, X, Y, b,
                d_.sectors == ConeKind::Cone ? 1u : SectorMask(d_.sectors, g_, dx, dy));
    }

    /// Exact for a texel whose sectors are known: `mask` (the rip-map's leaves pass the
    /// quadrants of its (c1, c2) offset, which are the closed sectors themselves; the
    /// other passes' sectors are not needed).
    void ExactIn(Tile& t, int k, int X, int Y, float b, unsigned mask) {
        const int dx = X - t.pi[k], dy = Y - t.pj[k];
        const float a = t.a[k];
        if (!(b < a) || dx < -g_.halfX || dx > g_.halfX || dy < -g_.halfY ||
            dy > g_.halfY || (dx == 0 && dy == 0))
            return;
        Update(t, k, X, Y, CandidateQ(g_.S(dx, dy), a, b), mask);
    }

    /// Lowers lane k's minimum of the channels in `mask` to q where q is below it.
    void Update(Tile& t, int k, int X, int Y, double q, unsigned mask) {
        for (; mask; mask &= mask - 1) {
            const int c = std::countr_zero(mask);
            if (q < t.best[c][k]) {
                t.best[c][k] = q;
                t.thr[c][k] = float(q) * kThresholdScale;
                t.rinv[c][k] = 1.0f / std::sqrt(t.thr[c][k]);
                t.argX[c][k] = X;
                t.argY[c][k] = Y;
            }
        }
    }

    /// Seeds: the blockers found by the neighbour tiles' nearest lanes. Each lane and
    /// channel takes the candidate with the smallest q in float, evaluated exactly once
    /// (any candidate is a valid first minimum; a good one prunes the traversal early).
    void TakeSeeds(Tile& t, const Seed* seeds, int n) {
        if (!n) return;
        VF bestF[kMaxSectors];
        VI bestIdx[kMaxSectors];
        const uint32_t pass = d_.passChannels;
        for (int c = 0; c < d_.nChannels; ++c) {
            bestF[c] = VF{} + INFINITY;
            bestIdx[c] = VI{} - 1;
        }
        for (int i = 0; i < n; ++i) {
            const int X = seeds[i].x, Y = seeds[i].y;
            const float b = DepthAt(X, Y);
            const VI dx = X - t.pi, dy = Y - t.pj;
            VI ok = (dx >= -g_.halfX) & (dx <= g_.halfX) & (dy >= -g_.halfY) &
                    (dy <= g_.halfY) & (t.a > b);
            if (d_.limiting) ok &= LimitingLanes(dx, dy, FlagsAt(X, Y));
            if (!Bits(ok)) continue;
            const VF fx = ToFloat(dx), fy = ToFloat(dy);
            const VF dd = t.a - b;
            const VF q = (fx * fx * wx_ + fy * fy * wy_) / (dd * dd);
            VI member[kMaxSectors];
            Members(dx, dy, member);
            for (uint32_t cs = pass; cs; cs &= cs - 1) {
                const int c = std::countr_zero(cs);
                const VI better = ok & member[c] & (q < bestF[c]);
                bestF[c] = better ? q : bestF[c];
                bestIdx[c] = better ? (VI{} + i) : bestIdx[c];
            }
        }
        for (uint32_t lanes = t.valid; lanes; lanes &= lanes - 1) {
            const int k = std::countr_zero(lanes);
            int last = -1;
            for (uint32_t cs = pass; cs; cs &= cs - 1) {
                const int c = std::countr_zero(cs);
                const int i = bestIdx[c][k];
                if (i < 0 || i == last) continue;
                last = i;
                Exact(t, k, seeds[i].x, seeds[i].y, DepthAt(seeds[i].x, seeds[i].y));
            }
        }
    }

    void SeedFromNeighbours(Tile& t, int tileX, bool left, bool up) {
        Seed seeds[(kTileW + kTileH) * kMaxSectors];
        int n = 0;
        const int C = d_.nChannels;
        if (left)
            for (int i = 0; i < kTileH * C; ++i)
                if (seedLeft_[size_t(i)].x != kNoSeed) seeds[n++] = seedLeft_[size_t(i)];
        if (up)
            for (int i = 0; i < kTileW * C; ++i) {
                const Seed e = seedUp_[size_t(tileX) * kTileW * size_t(C) + size_t(i)];
                if (e.x != kNoSeed) seeds[n++] = e;
            }
        TakeSeeds(t, seeds, n);
    }

    /// Lanes for which a node's cells (unwrapped box, min depth m) can hold a blocker
    /// below one of the channels' minima in `channels`.
    uint32_t NodeLanes(const Tile& t, int X0, int X1, int Y0, int Y1, float m,
                       uint32_t channels) const {
        return Bits(BoundLanes(t, X0, X1, Y0, Y1, m, Threshold(t, channels)));
    }

    /// The largest threshold of `channels` per lane.
    static VF Threshold(const Tile& t, uint32_t channels) {
        return FoldChannels(t.thr, channels, [](VF r, VF o) { return Max(r, o); });
    }

    /// The smallest 1 / sqrt(threshold) of `channels` per lane.
    static VF Rinv(const Tile& t, uint32_t channels) {
        return FoldChannels(t.rinv, channels, [](VF r, VF o) { return Min(o, r); });
    }

    /// v[c] folded lane-wise with `op` over the (non-empty) set `channels`.
    template <class Op>
    static VF FoldChannels(const VF* v, uint32_t channels, Op op) {
        VF r = v[std::countr_zero(channels)];
        for (uint32_t c = channels & (channels - 1); c; c &= c - 1)
            r = op(r, v[std::countr_zero(c)]);
        return r;
    }

    /// The first-order cell bound (docs/cone_maps.md, "The first-order cell bound"): the
    /// lanes for which a cell may hold a texel t with |t - s| < R (a - d_t), R = 1 / rinv
    /// >= sqrt(q) (rinv is 1 / sqrt(thr) rounded, and thr exceeds q by 2^-16). The cell
    /// is a box [c1 - h1, c1 + h1] x [c2 - h2, c2 + h2] in coordinates (c1, c2) whose
    /// real offsets are (c1 + Alpha c2, c2 + Beta c1) (the quadtree: Alpha = Beta = 0; a
    /// rip cell: its shear), with real centre (cx, cy) and lower plane `p` in (c1, c2).
    /// With v = c - s and the map's metric, Cauchy-Schwarz gives |t - s| >= <t - s, v> /
    /// |v|, and the plane gives d_t >= q0 + g (t - c); so over the cell, d_t + |t - s| /
    /// R is at least q0 + |v| / R - sum_i |g_i + <e_i, w v> / (|v| R)| h_i (e_i: the real
    /// offset of a unit step in c_i). Multiplied by |v| (no division), a lane is skipped
    /// where that is >= a by more than 2^-16 of the terms' magnitudes before any
    /// cancellation, and only where |v| > 0.
    template <int Alpha, int Beta>
    VI FirstOrderLanes(const Tile& t, const ConeSearchData::LowerPlane& p, float cx,
                       float cy, float h1, float h2, const VF& rinv) const {
        return FirstOrderLanes<Alpha, Beta>(t, VF{} + p.q0, VF{} + std::abs(p.q0), p.gx,
                                            p.gy, VF{} + cx, VF{} + cy, VF{} + h1,
                                            VF{} + h2, rinv);
    }

    /// The same per lane, over a box of its own (centre (cx, cy), half extents h1, h2;
    /// q0 the plane's value at its centre, q0mag the magnitude of the terms it was
    /// summed from).
    template <int Alpha, int Beta>
    VI FirstOrderLanes(const Tile& t, const VF& q0, const VF& q0mag, float g1, float g2,
                       const VF& cx, const VF& cy, const VF& h1, const VF& h2,
                       const VF& rinv) const {
        // Half-integers below 2^23: exact, as are the differences.
        const VF vx = cx - ToFloat(t.pi), vy = cy - ToFloat(t.pj);
        const VF wvx = vx * wx_, wvy = vy * wy_;
        const VF n2 = vx * wvx + vy * wvy;
        const VF norm = Sqrt(n2);
        const VF u1 = Beta == 0 ? wvx : wvx + float(Beta) * wvy;
        const VF u2 = Alpha == 0 ? wvy : float(Alpha) * wvx + wvy;
        const VF s1 = g1 * norm + u1 * rinv, s2 = g2 * norm + u2 * rinv;
        const VF a1 = Max(s1, -s1) * h1, a2 = Max(s2, -s2) * h2;
        const VF reach = n2 * rinv;
        const VF lower = q0 * norm + reach - a1 - a2;
        const VF an = t.a * norm;
        // Magnitudes of the slope terms before cancellation.
        const VF awx = Max(wvx, -wvx), awy = Max(wvy, -wvy);
        const VF m1 = (Beta == 0 ? awx : awx + awy) * rinv + std::abs(g1) * norm;
        const VF m2 = (Alpha == 0 ? awy : awx + awy) * rinv + std::abs(g2) * norm;
        const VF mag = (q0mag + t.a) * norm + reach + m1 * h1 + m2 * h2;
        return ~((norm > 0.0f) & (lower - an >= mag * kFirstOrderSlack));
    }

    /// The lanes whose lower bound over the box (nearest offset in the lane's window,
    /// depth m) lies below their threshold `thr`.
    VI BoundLanes(const Tile& t, int X0, int X1, int Y0, int Y1, float m,
                  const VF& thr) const {
        const VI lo = Max(X0 - t.pi, VI{} - g_.halfX),
                 hi = Min(X1 - t.pi, VI{} + g_.halfX);
        const VI loy = Max(Y0 - t.pj, VI{} - g_.halfY),
                 hiy = Min(Y1 - t.pj, VI{} + g_.halfY);
        const VF fx = ToFloat(Min(Max(VI{}, lo), hi)),
                 fy = ToFloat(Min(Max(VI{}, loy), hiy));
        const VF s = fx * fx * wx_ + fy * fy * wy_;
        const VF dd = t.a - m;
        return (lo <= hi) & (loy <= hiy) & (t.a > m) &
               ((dd < kTiny) | ~(s >= thr * (dd * dd)));
    }

    /// The lanes of `n.lanes` for which quadtree cell n can hold a blocker below one of
    /// its channels' minima; a leaf (2x2 texels) that passes is searched here, texel by
    /// texel (and 0 returned).
    RS_INLINE uint32_t NodeTest(Tile& t, const Node& n, int xMax, int yMax) {
        const int W = d_.W, H = d_.H;
        const int l = n.level;
        const int ox = n.tx * W, oy = n.ty * H;
        const int X0 = ox + (n.cx << l), X1 = ox + std::min((n.cx + 1) << l, W) - 1;
        const int Y0 = oy + (n.cy << l), Y1 = oy + std::min((n.cy + 1) << l, H) - 1;
        const size_t cell = d_.levelOff[size_t(l)] +
                            size_t(n.cy) * size_t(d_.levelW[size_t(l)]) + size_t(n.cx);
        const uint32_t channels =
            d_.nChannels == 1
                ? 1u
                : ChannelsOfRect(d_, X0 - xMax, X1 - t.x0, Y0 - yMax, Y1 - t.y0);
        if (!channels) return 0;
        // The cell's lower plane and least depth share a cache line (levels >= 1).
        const ConeSearchData::LowerPlane* plane =
            l >= 1 && !d_.planes.empty() ? &d_.planes[cell - d_.levelOff[1]] : nullptr;
        float m;
        if (plane) {
            m = plane->least;
        } else if (d_.limiting) {
            uint32_t cls = ClassesOfRect(X0 - xMax, X1 - t.x0, Y0 - yMax, Y1 - t.y0);
            m = INFINITY;
            for (; cls; cls &= cls - 1)
                m = std::min(
                    m,
                    d_.pyramids[size_t(std::countr_zero(cls)) * d_.pyramidSize + cell]);
        } else {
            m = d_.field->depth[cell];  // level 0 (a 1x1 map's root): the texel
        }
        uint32_t lanes = NodeLanes(t, X0, X1, Y0, Y1, m, channels) & n.lanes;
        if (lanes && plane)
            lanes &= Bits(FirstOrderLanes<0, 0>(
                t, *plane, 0.5f * float(X0 + X1), 0.5f * float(Y0 + Y1),
                0.5f * float(X1 - X0), 0.5f * float(Y1 - Y0), Rinv(t, channels)));
        if (!lanes || l > kLeafLevel) return lanes;
        for (int Y = Y0; Y <= Y1; ++Y)
            for (int X = X0; X <= X1; ++X) {
                const size_t at = size_t(Y - oy) * size_t(W) + size_t(X - ox);
                const float b = d_.field->depth[at];
                uint32_t pass =
                    TexelLanes(t, X, Y, b, d_.limiting ? d_.flags[at] : 0) & lanes;
                for (; pass; pass &= pass - 1) Exact(t, std::countr_zero(pass), X, Y, b);
            }
        return 0;
    }

    /// The quadtree's traversal: a cell's four children are tested together when it is
    /// opened, and those that pass are pushed, the nearest to the tile's centre last
    /// (searched first).
    void Traverse(Tile& t) {
        const int W = d_.W, H = d_.H;
        // The offsets of the tile's lanes to a box span [X0 - xMax, X1 - x0] (superset).
        const int xMax = std::min(t.x0 + kTileW, W) - 1;
        const int yMax = std::min(t.y0 + kTileH, H) - 1;
        const int cx = t.x0 + kTileW / 2, cy = t.y0 + kTileH / 2;
        Node stack[kStack];
        int sp = 0;
        // The nine wrap images of the root, the one holding the tile searched first.
        for (int ty = -1; ty <= 1; ++ty)
            for (int tx = -1; tx <= 1; ++tx) {
                if (tx == 0 && ty == 0) continue;
                Node r{int8_t(d_.top), int8_t(tx), int8_t(ty), uint16_t(t.valid), 0, 0};
                r.lanes = uint16_t(NodeTest(t, r, xMax, yMax));
                if (r.lanes) stack[sp++] = r;
            }
        {
            Node r{int8_t(d_.top), 0, 0, uint16_t(t.valid), 0, 0};
            r.lanes = uint16_t(NodeTest(t, r, xMax, yMax));
            if (r.lanes) stack[sp++] = r;
        }
        while (sp) {
            const Node n = stack[--sp];
            const int ox = n.tx * W, oy = n.ty * H;
            // Children, nearest to the tile's centre first.
            const int cl = n.level - 1;
            const int mx = ox + ((2 * n.cx + 1) << cl), my = oy + ((2 * n.cy + 1) << cl);
            const int qx = cx < mx ? 0 : 1, qy = cy < my ? 0 : 1;
            const int order[4][2] = {
                {qx, qy}, {1 - qx, qy}, {qx, 1 - qy}, {1 - qx, 1 - qy}};
            Node child[4];
            int nc = 0;
            for (const auto& o : order) {
                const int ccx = 2 * n.cx + o[0], ccy = 2 * n.cy + o[1];
                if (ccx >= d_.levelW[size_t(cl)] || ccy >= d_.levelH[size_t(cl)])
                    continue;
                Node c{int8_t(cl), n.tx, n.ty, n.lanes, ccx, ccy};
                c.lanes = uint16_t(NodeTest(t, c, xMax, yMax));
                if (c.lanes) child[nc++] = c;
            }
            while (nc) stack[sp++] = child[--nc];
        }
    }

    struct RipNode {
        int8_t lx, ly, t1, t2;  ///< levels; image in c1 and c2
        uint16_t lanes;
        int32_t cx, cy;
    };

    /// The pass's traversal, compiled for its rip-map's layout.
    void TraverseRipPass(Tile& t, const ConeSearchData::RipMap& rip) {
        [&]<int... L>(std::integer_sequence<int, L...>) {
            ((rip.layout == L ? (TraverseRip<L>(t, rip), 0) : 0), ...);
        }
        (std::make_integer_sequence<int, kNumRipLayouts>{});
    }

    /// A rip cell's ranges of sheared coordinates [A0, A1] x [B0, B1] (clipped at the
    /// edge), in the wrap image at (o1, o2).
    struct RipBox {
        int o1, o2, A0, A1, B0, B1;
    };
    RS_INLINE RipBox BoxOf(const RipNode& n) const {
        const int W = d_.W, H = d_.H;
        RipBox r;
        r.o1 = n.t1 * W;
        r.o2 = n.t2 * H;
        r.A0 = r.o1 + (n.cx << n.lx);
        r.A1 = r.o1 + std::min((n.cx + 1) << n.lx, W) - 1;
        r.B0 = r.o2 + (n.cy << n.ly);
        r.B1 = r.o2 + std::min((n.cy + 1) << n.ly, H) - 1;
        return r;
    }

    /// A tile's coordinates in a rip-map's sheared frame.
    struct RipFrame {
        int p1min, p1max, p2min, p2max;  ///< the valid lanes' range in (c1, c2)
        VI lc1, lc2;                     ///< each lane's (c1, c2)
    };

    /// The lanes of `n.lanes` for which rip cell n can hold a blocker below the minimum
    /// of a sector it meets from that lane's apex.
    template <int L>
    RS_INLINE uint32_t RipTest(Tile& t, const ConeSearchData::RipMap& rip,
                               const RipFrame& f, const RipNode& n) {
        constexpr const RipLayout& cfg = kRipLayouts[L];
        const int a = cfg.alpha, bt = cfg.beta;
        const RipBox box = BoxOf(n);
        const int A0 = box.A0, A1 = box.A1, B0 = box.B0, B1 = box.B1;
        // Sectors the cell can hold for some lane: quadrants of (c1, c2) offsets.
        const int lo1 = A0 - f.p1max, hi1 = A1 - f.p1min, lo2 = B0 - f.p2max,
                  hi2 = B1 - f.p2min;
        uint32_t channels = 0;
        for (int i = 0; i < cfg.n; ++i) {
            const int k = cfg.ch[i];
            // Quadrant of channel k in (c1, c2): signs from the table of the kind.
            if (MeetsQuadrant(cfg.s1[i], cfg.s2[i], lo1, hi1, lo2, hi2))
                channels |= 1u << k;
        }
        if (!channels) return 0;
        // The real bounding box of the cell.
        const int X0 = A0 + std::min(a * B0, a * B1), X1 = A1 + std::max(a * B0, a * B1);
        const int Y0 = B0 + std::min(bt * A0, bt * A1),
                  Y1 = B1 + std::max(bt * A0, bt * A1);
        // The cell's lower plane and least depth share a cache line (large cells of
        // the traversal's chain).
        const ConeSearchData::LowerPlane* plane = rip.PlaneAt(n.lx, n.ly, n.cx, n.cy);
        const float m = plane ? plane->least : rip.At(n.lx, n.ly, n.cx, n.cy);
        // Per lane, the largest threshold of the channels whose quadrant the cell
        // meets (the same sign test as above, with the lane's own offsets), and for
        // each sector the lanes that meet it.
        const VI lo1v = A0 - f.lc1, hi1v = A1 - f.lc1, lo2v = B0 - f.lc2,
                 hi2v = B1 - f.lc2;
        VF thr = VF{} - INFINITY;
        VI meets{}, okOf[kMaxSectors];
        for (int i = 0; i < cfg.n; ++i) {
            const int k = cfg.ch[i];
            okOf[i] = VI{};
            if (!(channels >> k & 1u)) continue;
            const VI ok = MeetsQuadrant(cfg.s1[i], cfg.s2[i], lo1v, hi1v, lo2v, hi2v);
            thr = ok ? Max(thr, t.thr[k]) : thr;
            meets |= ok;
            okOf[i] = ok;
        }
        uint32_t lanes = Bits(meets & BoundLanes(t, X0, X1, Y0, Y1, m, thr)) & n.lanes;
        if (lanes && plane) {
            // Per sector, the first-order bound over the part of the cell in its
            // quadrant from each lane's apex (a box: the cell clipped at the lane's
            // c1 or c2), with that sector's ratio; a lane is kept where one part passes.
            const float c1 = 0.5f * float(A0 + A1), c2 = 0.5f * float(B0 + B1);
            const VF p1 = ToFloat(f.lc1), p2 = ToFloat(f.lc2);
            VI keep{};
            for (int i = 0; i < cfg.n; ++i) {
                if (!(Bits(okOf[i]) & lanes)) continue;
                VF lo1 = VF{} + float(A0), hi1 = VF{} + float(A1);
                VF lo2 = VF{} + float(B0), hi2 = VF{} + float(B1);
                ClipToQuadrant(cfg.s1[i], cfg.s2[i], p1, p2, lo1, hi1, lo2, hi2);
                // Centres and half extents: half-integers, exact in float.
                const VF mid1 = 0.5f * (lo1 + hi1), mid2 = 0.5f * (lo2 + hi2);
                const VF d1 = (mid1 - c1) * plane->gx, d2 = (mid2 - c2) * plane->gy;
                const VF q0 = plane->q0 + d1 + d2;
                const VF q0mag = std::abs(plane->q0) + Max(d1, -d1) + Max(d2, -d2);
                keep |= okOf[i] & FirstOrderLanes<cfg.alpha, cfg.beta>(
                                      t, q0, q0mag, plane->gx, plane->gy,
                                      mid1 + float(a) * mid2, mid2 + float(bt) * mid1,
                                      0.5f * (hi1 - lo1), 0.5f * (hi2 - lo2),
                                      t.rinv[cfg.ch[i]]);
            }
            lanes &= Bits(keep);
        }
        return lanes;
    }

    /// Every texel of a small rip cell n (at most kLanes texels) that passed RipTest, for
    /// its lanes: the cell's texels are the vector's elements, and each lane in turn
    /// tests them all (its offsets, the sector of each of the pass's channels (a quadrant
    /// of (c1, c2) offsets), the float test); the texels that pass are evaluated exactly.
    RS_INLINE void RipLeaf(Tile& t, const ConeSearchData::RipMap& rip,
                           const RipLayout& cfg, const RipFrame& f, const RipNode& n) {
        const RipBox box = BoxOf(n);
        const int lx = n.lx, A0 = box.A0, B0 = box.B0;
        // Element v is texel (A0 + v % 2^lx, B0 + v / 2^lx) of the cell (clipped:
        // elements outside it have depth +inf, never a blocker).
        const int w = box.A1 - A0 + 1, h = box.B1 - B0 + 1;
        alignas(64) float depth[kLanes];
        for (int v = 0; v < kLanes; ++v) depth[v] = INFINITY;
        const float* row =
            rip.mins + size_t(B0 - box.o2) * size_t(d_.W) + size_t(A0 - box.o1);
        for (int j = 0; j < h; ++j, row += d_.W)
            for (int i = 0; i < w; ++i) depth[(j << lx) + i] = row[i];
        VF b;
        __builtin_memcpy(&b, depth, sizeof(b));
        const VI c1 = A0 + (kIota & ((1 << lx) - 1)), c2 = B0 + (kIota >> lx);
        const VI X = c1 + cfg.alpha * c2, Y = c2 + cfg.beta * c1;
        for (uint32_t lanes = n.lanes; lanes; lanes &= lanes - 1) {
            const int k = std::countr_zero(lanes);
            const float ak = t.a[k];
            const VI dx = X - t.pi[k], dy = Y - t.pj[k];
            const VI off1 = c1 - f.lc1[k], off2 = c2 - f.lc2[k];
            const VF fx = ToFloat(dx), fy = ToFloat(dy);
            const VF s = fx * fx * wx_ + fy * fy * wy_;
            const VF dd = ak - b;
            const VF d2 = dd * dd;
            const VI tiny = dd < kTiny;
            // Blockers in the lane's window (ExactIn's test, so that the least float q
            // below is taken over texels it evaluates).
            const VI blocker = (ak > b) & (dx >= -g_.halfX) & (dx <= g_.halfX) &
                               (dy >= -g_.halfY) & (dy <= g_.halfY);
            VI ok[kMaxSectors], any{};
            for (int i = 0; i < cfg.n; ++i) {
                const int ch = cfg.ch[i];
                ok[i] = (tiny | ~(s >= t.thr[ch][k] * d2)) & blocker &
                        MeetsQuadrant(cfg.s1[i], cfg.s2[i], off1, off1, off2, off2);
                any |= ok[i];
            }
            if (!Bits(any)) continue;
            VF q{};
            bool haveQ = false;
            for (int i = 0; i < cfg.n; ++i) {
                const int ch = cfg.ch[i];
                uint32_t pass = Bits(ok[i]);
                if (!pass) continue;
                if (pass & (pass - 1)) {
                    // Several: only those within rounding of the least float q can be
                    // the least exactly (and those of tiny depth difference, whose
                    // float q is not reliable).
                    if (!haveQ) {
                        q = s / d2;
                        haveQ = true;
                    }
                    float least = INFINITY;
                    for (uint32_t p = pass; p; p &= p - 1)
                        least = std::min(least, q[std::countr_zero(p)]);
                    pass &= Bits((q <= least * kThresholdScale) | tiny);
                }
                for (; pass; pass &= pass - 1) {
                    const int v = std::countr_zero(pass);
                    ExactIn(t, k, X[v], Y[v], b[v], 1u << ch);
                }
            }
        }
    }

    /// The sector kinds' traversal: binary splits (the longer side) of rip-map cells in
    /// sheared coordinates, where each sector the rip-map serves is a quadrant of
    /// (c1, c2) offsets; per lane, a cell is tested against the sectors it meets from
    /// that lane's apex only. A cell's two halves are tested together when it is split,
    /// and only those that pass are pushed.
    template <int L>
    void TraverseRip(Tile& t, const ConeSearchData::RipMap& rip) {
        constexpr const RipLayout& cfg = kRipLayouts[L];
        const int W = d_.W, H = d_.H;
        RipFrame f;
        const int a = cfg.alpha, bt = cfg.beta;
        // Lanes in sheared coordinates: c1 = X - alpha * c2 (beta = 0) or c1 = X (beta !=
        // 0, c2 = Y - beta * X); their range over the tile.
        f.p1min = INT32_MAX, f.p1max = INT32_MIN, f.p2min = INT32_MAX,
        f.p2max = INT32_MIN;
        for (int k = 0; k < kLanes; ++k) {
            if (!(t.valid >> k & 1u)) continue;
            const int X = t.pi[k], Y = t.pj[k];
            const int c1 = bt == 0 ? X - a * Y : X, c2 = bt == 0 ? Y : Y - bt * X;
            f.p1min = std::min(f.p1min, c1), f.p1max = std::max(f.p1max, c1);
            f.p2min = std::min(f.p2min, c2), f.p2max = std::max(f.p2max, c2);
        }
        // Each lane's own sheared coordinates: a cell's channels per lane (a subset of
        // the tile's) give each lane the threshold of the sectors it can meet there.
        f.lc1 = bt == 0 ? t.pi - a * t.pj : t.pi;
        f.lc2 = bt == 0 ? t.pj : t.pj - bt * t.pi;
        const int mid1 = (f.p1min + f.p1max) / 2, mid2 = (f.p2min + f.p2max) / 2;
        // Cells wait in bands of distance from the tile (bit width of the Chebyshev
        // distance between the cell's and the tile's boxes, in sheared coordinates): the
        // nearest band is searched first, depth-first inside it. A cell is never nearer
        // than its parent, so the bands are emptied in order. Each sector's minimum is
        // thus found before the farther cells are opened against a stale threshold: on
        // the growth benchmark's acm4 at 2048² this tested 0.71x the cells and 0.34x
        // the leaves per apex of a plain depth-first traversal, whose order visits the
        // whole of a near cell (its far corners too) before the next one.
        const auto bandOf = [&](const RipNode& r) {
            const RipBox bx = BoxOf(r);
            const int d1 = std::max({bx.A0 - f.p1max, f.p1min - bx.A1, 0});
            const int d2 = std::max({bx.B0 - f.p2max, f.p2min - bx.B1, 0});
            return int(std::bit_width(unsigned(std::max(d1, d2))));
        };
        int band = 0;
        const auto push = [&](const RipNode& r) {
            bands_[size_t(bandOf(r))].push_back(r);
        };
        // Images: the sheared fundamental domain repeats by W in c1 and H in c2; the
        // windows (|dx| <= W/2, |dy| <= H/2) need c1 within one W plus a shear of H.
        const int r1 = (a != 0) ? 2 : 1, r2 = (bt != 0) ? 2 : 1;
        for (int i2 = -r2; i2 <= r2; ++i2)
            for (int i1 = -r1; i1 <= r1; ++i1) {
                RipNode r{int8_t(rip.levelsX),
                          int8_t(rip.levelsY),
                          int8_t(i1),
                          int8_t(i2),
                          uint16_t(t.valid),
                          0,
                          0};
                r.lanes = uint16_t(RipTest<L>(t, rip, f, r));
                if (!r.lanes) continue;
                if (r.lx + r.ly <= kRipLeaf)
                    RipLeaf(t, rip, cfg, f, r);
                else
                    push(r);
            }
        RipNode n;
        bool have = false;
        for (;;) {
            if (!have) {
                while (band < kRipBands && bands_[size_t(band)].empty()) ++band;
                if (band == kRipBands) break;
                n = bands_[size_t(band)].back();
                bands_[size_t(band)].pop_back();
            }
            // Split the longer side. (Splitting across a lane's sector edge first, which
            // keeps the cells along the edges one texel wide, opened 10-15% more cells:
            // each lane's own sign test above already keeps a straddling cell from the
            // lanes and sectors it cannot meet.)
            const bool split1 = RipSplitsC1(n.lx, n.ly);
            RipNode c0 = n, c1 = n;
            bool has1, nearFirst0;
            if (split1) {
                c0.lx = c1.lx = int8_t(n.lx - 1);
                c0.cx = 2 * n.cx;
                c1.cx = 2 * n.cx + 1;
                has1 = c1.cx < rip.cellsX[size_t(n.lx - 1)];
                nearFirst0 = mid1 < n.t1 * W + (c1.cx << c1.lx);
            } else {
                c0.ly = c1.ly = int8_t(n.ly - 1);
                c0.cy = 2 * n.cy;
                c1.cy = 2 * n.cy + 1;
                has1 = c1.cy < rip.cellsY[size_t(n.ly - 1)];
                nearFirst0 = mid2 < n.t2 * H + (c1.cy << c1.ly);
            }
            // The half nearer the tile's lanes is searched first (the next node, unless
            // it lies in a farther band; the other is pushed).
            RipNode& nearC = nearFirst0 ? c0 : c1;
            RipNode& farC = nearFirst0 ? c1 : c0;
            if (!has1) c1.lanes = 0;
            nearC.lanes = nearC.lanes ? uint16_t(RipTest<L>(t, rip, f, nearC)) : 0;
            farC.lanes = farC.lanes ? uint16_t(RipTest<L>(t, rip, f, farC)) : 0;
            if (nearC.lx + nearC.ly <= kRipLeaf) {  // both halves are leaves
                if (nearC.lanes) RipLeaf(t, rip, cfg, f, nearC);
                if (farC.lanes) RipLeaf(t, rip, cfg, f, farC);
                have = false;
                continue;
            }
            if (farC.lanes) push(farC);
            have = false;
            if (nearC.lanes) {
                const int nb = bandOf(nearC);
                have = nb == band;
                if (have)
                    n = nearC;
                else
                    bands_[size_t(nb)].push_back(nearC);
            }
        }
    }

    void Finish(const Tile& t, int tileX) {
        const int C = d_.nChannels;
        for (int k = 0; k < kLanes; ++k) {
            const int i = t.x0 + k % kTileW, j = t.y0 + k / kTileW;
            if (i >= d_.W || j >= d_.H) continue;
            float* out = d_.out +
                         (size_t(j) * size_t(d_.W) + size_t(i)) * size_t(d_.outStride) +
                         size_t(d_.outBase);
            for (int c = 0; c < C; ++c) {
                if (!(d_.passChannels >> c & 1u)) continue;  // another pass's
                const double q = t.best[c][k];
                out[c] = d_.output == ConeSearchOutput::ConeNormal
                             ? ConeNormalFromRatio(std::sqrt(q) / g_.scale)
                             : RatioFromQ(q, g_.scale);
            }
        }
        // Seeds for the next tile to the right (this tile's right column) and below
        // (its bottom row).
        seedLeft_.resize(size_t(kTileH * C));
        for (int r = 0; r < kTileH; ++r)
            for (int c = 0; c < C; ++c) {
                const int k = r * kTileW + kTileW - 1;
                seedLeft_[size_t(r * C + c)] = {t.argX[c][k], t.argY[c][k]};
            }
        for (int s = 0; s < kTileW; ++s)
            for (int c = 0; c < C; ++c) {
                const int k = (kTileH - 1) * kTileW + s;
                seedUp_[(size_t(tileX) * kTileW + size_t(s)) * size_t(C) + size_t(c)] = {
                    t.argX[c][k], t.argY[c][k]};
            }
    }

    static constexpr int kLeafLevel = 1;
    /// Rip cells of at most kLanes = 2^kRipLeaf texels are tested whole (RipLeaf).
    static constexpr int kRipLeaf = std::countr_zero(unsigned(kLanes));
    /// Roots (9, or 15 for a sheared rip-map), then at most 3 more per quadtree level or
    /// 1 per rip-map split; levels < 32.
    static constexpr int kStack = 160;
    static_assert(kStack >= 15 + 2 * 31 && kStack >= 9 + 3 * 31 + 1);

    const ConeSearchData& d_;
    const Geometry& g_;
    const float wx_, wy_;
    Tile tile_;
    std::vector<Seed> seedLeft_, seedUp_;
    /// The rip traversal's cells waiting, by band of distance from the tile (bit widths
    /// of distances 0 .. 2^31 - 1).
    static constexpr int kRipBands = 32;
    std::vector<RipNode> bands_[kRipBands];
};

}  // namespace
}  // namespace lanes

/// Defines the band function of one instruction set's unit.
#define RS_DEFINE_CONE_SEARCH(suffix)                                      \
    namespace reliefsim::detail {                                          \
    void ConeSearchBand##suffix(const ConeSearchData& d, int r0, int r1) { \
        lanes::Engine e(d);                                                \
        e.Band(r0, r1);                                                    \
    }                                                                      \
    }

}  // namespace reliefsim::detail
