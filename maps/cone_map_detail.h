// Internals shared by the cone-map generators: geometry, exact candidate arithmetic, the
// tiled pruned search. Not part of the public API.
#pragma once

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <vector>

#include "core/error.h"
#include "core/wrap.h"
#include "maps/cone_map.h"

namespace reliefsim::detail {

constexpr int kMaxSectors = 8;
constexpr double kInfQ = std::numeric_limits<double>::infinity();

/// Integer geometry of a W x H texture. The squared uv distance of a texel offset (dx,
/// dy) is S / scale^2 with S = dx^2 * hq^2 + dy^2 * wq^2 an exact integer (wq = W/g, hq =
/// H/g, g = gcd(W, H), scale = wq * hq * g); for square maps S = dx^2 + dy^2 and scale =
/// W.
struct Geometry {
    int w = 0, h = 0;
    int64_t wx = 1;  ///< weight of dx^2 (hq^2)
    int64_t wy = 1;  ///< weight of dy^2 (wq^2)
    double scale = 1;
    int halfX = 0,
        halfY = 0;  ///< offsets run over [-half, half] (both images at W/2 for even W)
    int64_t S(int dx, int dy) const {
        return int64_t(dx) * dx * wx + int64_t(dy) * dy * wy;
    }
};
Geometry MakeGeometry(int w, int h);

/// The one candidate formula every exact generator uses: q = S / (a - b)^2 in double,
/// where a is the apex depth and b the blocker depth (b < a). Both operations round
/// monotonically, so a bound computed with a smaller b or a smaller S is never larger:
/// the pruning is exact.
inline double CandidateQ(int64_t s, float apex, float blocker) {
    const double dd = double(apex) - double(blocker);
    return double(s) / (dd * dd);
}

/// `v` rounded to a float at most `v` (toward -inf).
inline float FloatAtMost(double v) {
    float r = float(v);
    if (double(r) > v) r = std::nextafter(r, -std::numeric_limits<float>::infinity());
    return r;
}

/// Rounds a ratio (>= 0) to a float strictly below it (unless exactly zero), capped at
/// kConeRatioCap: the stored ratio never exceeds the exact one.
float RoundDownStrict(double r);
/// Ratio from the minimal q: RoundDownStrict(sqrt(q)/scale); the cap for no blocker.
float RatioFromQ(double q, double scale);

/// A texel offset with its exact squared distance and sector mask.
struct Offset {
    int dx, dy;
    int64_t s;
    uint8_t mask;
};
struct OffsetTile {
    int begin, end;  ///< range in TiledOffsets::offsets
    int ox, oy;      ///< window origin relative to the apex texel (tile covers ox..ox+7)
    int64_t minS;
    uint8_t mask;
};
constexpr int kTile = 8;

/// Sector masks: bit k set when the offset lies in closed sector k of `kind`
/// (Cone: bit 0 always).
uint8_t SectorMask(ConeKind kind, const Geometry& g, int dx, int dy);
int SectorCount(ConeKind kind);

/// 4x4 tiles (a 32x32 window of offsets): superOrder[first, last) lists its tiles by
/// minS.
struct OffsetSuperTile {
    int first, last;
    int ox, oy;  ///< window origin relative to the apex texel (covers ox..ox+31)
    int64_t minS;
    uint8_t mask;
};
constexpr int kSuperTile = 4;  ///< tiles per super-tile side

/// All offsets of the wrap range (except 0,0) grouped in 8x8 tiles, tiles sorted by minS;
/// the tiles also grouped by 32x32 window (super-tiles sorted by minS), for searches that
/// mostly reject whole windows.
struct TiledOffsets {
    std::vector<Offset> offsets;
    std::vector<OffsetTile> tiles;
    std::vector<OffsetSuperTile> supers;
    std::vector<int> superOrder;  ///< tile indices, grouped by super-tile
};
/// cells = true: the offsets between bilinear cells (maps/cone_map_bilinear.h) instead
/// of texels: the near ones (|dx| <= 1 and |dy| <= 1) left out, s = S(CellGap(dx),
/// CellGap(dy)) (the squared uv distance between the two cells) and the mask
/// CellSectorMask.
TiledOffsets MakeTiledOffsets(const Geometry& g, ConeKind sectors, bool cells = false);
/// The same offsets in plain scan order (for brute force).
std::vector<Offset> MakeOffsets(const Geometry& g, ConeKind sectors, bool cells = false);

/// The gap, in texels, between two cells (or texel squares) `d` apart along an axis.
inline int CellGap(int d) { return d > 1 ? d - 1 : (d < -1 ? -d - 1 : 0); }

/// Sector masks between cells: bit k set when some point of the cell at offset (dx, dy)
/// lies in sector k (as SectorMask: closed wedges, quad's open half planes) of some
/// point of the cell at the origin, i.e. when the square [dx - 1, dx + 1] x [dy - 1,
/// dy + 1] of their differences meets the sector.
uint8_t CellSectorMask(ConeKind kind, const Geometry& g, int dx, int dy);

/// out[(j*W + i)*C + c] = min of v[(y*W + x)*C + c] over x = i + a*step, y = j + b*step,
/// a, b in [0, k), wrapped (C interleaved channels). With v itself a window minimum of
/// size `step`, the result is the window minimum of size k*step. T: float, or the upper
/// 16 bits of non-negative floats (their order is the floats' order).
template <class T>
std::vector<T> WindowMinima(const std::vector<T>& v, int W, int H, int C, int k,
                            int step = 1);
extern template std::vector<float> WindowMinima(const std::vector<float>&, int, int, int,
                                                int, int);
extern template std::vector<uint8_t> WindowMinima(const std::vector<uint8_t>&, int, int,
                                                  int, int, int);

/// The same with max, one channel.
std::vector<float> WindowMaxima(const std::vector<float>& v, int W, int H, int k,
                                int step = 1);

/// Depth minima over the 8x8 and 32x32 windows starting at each texel (TiledSearch).
struct SearchWindows {
    std::vector<float> win8, win32;
    std::vector<float> scratch;  ///< reused between calls
};
/// Fills `out`, reusing its storage.
void MakeSearchWindows(const DepthField& hf, SearchWindows& out);

using reliefsim::Wrap;  // core/wrap.h

/// Validates the field and returns min depth.
float CheckedMinDepth(const DepthField& hf);

/// best[k] = min(best[k], v) for the bits k of mask; true when one improved.
template <class T>
inline bool LowerMasked(unsigned mask, T v, T* best) {
    bool changed = false;
    for (; mask; mask &= mask - 1) {
        const int k = std::countr_zero(mask);
        if (v < best[k]) {
            best[k] = v;
            changed = true;
        }
    }
    return changed;
}
/// The same for the first nSectors sectors of a sector mask.
inline bool LowerSectors(uint8_t mask, double q, int nSectors, double* best) {
    return LowerMasked(mask & ((1u << nSectors) - 1u), q, best);
}

/// One blocker candidate: updates best[k] of the sectors in off.mask when the texel at
/// the offset is above the apex and accepted; true when a sector improved.
template <class Accept>
RS_INLINE bool ConsiderBlockerAt(const DepthField& hf, const Offset& off, int bx, int by,
                                 float apex, int nSectors, double* best, Accept& accept) {
    const float b = hf.depth[size_t(by) * size_t(hf.width) + size_t(bx)];
    if (!(b < apex)) return false;
    if (!accept(bx, by, off)) return false;
    return LowerSectors(off.mask, CandidateQ(off.s, apex, b), nSectors, best);
}
template <class Accept>
RS_INLINE bool ConsiderBlocker(const DepthField& hf, const Offset& off, int ti, int tj,
                               float apex, int nSectors, double* best, Accept& accept) {
    return ConsiderBlockerAt(hf, off, Wrap(ti + off.dx, hf.width),
                             Wrap(tj + off.dy, hf.height), apex, nSectors, best, accept);
}

/// The tiled exact search for one apex. best[k] holds the running minimum q per sector
/// (seed with kInfQ or a parent's bound). accept(bx, by, off) filters blockers (e.g.
/// limiting texels).
template <class Accept>
void TiledSearch(const DepthField& hf, const TiledOffsets& to, const SearchWindows& sw,
                 float dmin, int ti, int tj, float apex, int nSectors, double* best,
                 Accept&& accept) {
    const int W = hf.width, H = hf.height;
    if (!(apex > dmin)) return;
    auto maxBest = [&] {
        double m = 0;
        for (int k = 0; k < nSectors; ++k) m = std::max(m, best[k]);
        return m;
    };
    // Offsets run over [-W/2, W/2], so i + ox stays in [-W, 2W).
    auto wrapNear = [](int i, int n) { return i < 0 ? i + n : (i >= n ? i - n : i); };
    double mb = maxBest();
    for (const OffsetSuperTile& st : to.supers) {
        if (CandidateQ(st.minS, apex, dmin) >= mb) break;  // super-tiles sorted by minS
        const float w32 = sw.win32[size_t(wrapNear(tj + st.oy, H)) * size_t(W) +
                                   size_t(wrapNear(ti + st.ox, W))];
        if (!(w32 < apex)) continue;
        const double lbSuper = CandidateQ(st.minS, apex, w32);
        bool any = false;
        for (int k = 0; k < nSectors; ++k)
            any |= (st.mask >> k & 1u) && lbSuper < best[k];
        if (!any) continue;
        for (int x = st.first; x < st.last; ++x) {
            const OffsetTile& t = to.tiles[size_t(to.superOrder[size_t(x)])];
            if (CandidateQ(t.minS, apex, dmin) >= mb)
                break;  // sorted by minS in the group
            // The tile's window origin, wrapped; its texels are at most W (H) further.
            const int wx = wrapNear(ti + t.ox, W), wy = wrapNear(tj + t.oy, H);
            const float wmin = sw.win8[size_t(wy) * size_t(W) + size_t(wx)];
            if (!(wmin < apex)) continue;
            const double lbTile = CandidateQ(t.minS, apex, wmin);
            uint8_t open = 0;
            for (int k = 0; k < nSectors; ++k)
                if ((t.mask >> k & 1u) && lbTile < best[k]) open |= uint8_t(1u << k);
            if (!open) continue;
            bool changed = false;
            for (int o = t.begin; o < t.end; ++o) {
                const Offset& off = to.offsets[size_t(o)];
                if (!(off.mask & open)) continue;
                int bx = wx + (off.dx - t.ox), by = wy + (off.dy - t.oy);
                if (bx >= W) bx -= W;
                if (by >= H) by -= H;
                changed |=
                    ConsiderBlockerAt(hf, off, bx, by, apex, nSectors, best, accept);
            }
            if (changed) mb = maxBest();
        }
    }
}

/// Brute force: every offset, no pruning, same arithmetic.
template <class Accept>
void BruteSearch(const DepthField& hf, const std::vector<Offset>& offs, int ti, int tj,
                 float apex, int nSectors, double* best, Accept&& accept) {
    for (const Offset& off : offs)
        ConsiderBlocker(hf, off, ti, tj, apex, nSectors, best, accept);
}

/// Bán et al.'s limiting test: the blocker's outward neighbour (one texel further along
/// the offset direction, rounded to the 8-neighbourhood) is strictly deeper than the
/// blocker.
inline bool IsLimiting(const DepthField& hf, int bx, int by, int dx, int dy) {
    const int m = std::max(std::abs(dx), std::abs(dy));
    const int sx = (2 * std::abs(dx) >= m) ? (dx > 0 ? 1 : -1) : 0;
    const int sy = (2 * std::abs(dy) >= m) ? (dy > 0 ? 1 : -1) : 0;
    const int nx = Wrap(bx + sx, hf.width), ny = Wrap(by + sy, hf.height);
    return hf.At(nx, ny) > hf.At(bx, by);
}

/// Listing 18-2 for one (source, offset) pair in float (GPU) arithmetic, apex depth
/// `apex` (the source depth for plain relaxed cones); NaN-free: returns +inf for the
/// destinations the listing ignores (depth 0 gives a NaN ratio there). The brute force's
/// evaluation.
float RelaxedPairRatio(const DepthField& hf, int ti, int tj, int dx, int dy, int steps,
                       float apex);

/// Listing 18-1/18-2 relaxed map (maps/cone_map_relaxed.cpp): outKind Relaxed
/// (ratios), ConeNormal (n_z of the ratio) or Stacked (p.stackedCount channels, apex
/// StackedApex). brute = every pair, no pruning (the oracle); otherwise the exact pruned
/// search, which uses the exit-field bound where its float argument holds (maps up to
/// ~2040 texels a side at 4096 steps, ~58,000 at 128); exitField = false forces the
/// search without it, aheadEveryPair = true tries the windows ahead on every pair the
/// exit bound keeps (where they rarely prune the search tries them on one pair in 16)
/// (tests).
ConeMap RelaxedListingMap(const DepthField& hf, const ConeMapParams& p, bool brute,
                          ConeKind outKind, bool exitField = true,
                          bool aheadEveryPair = false);

/// The relaxed search's exit field for `steps` steps (docs/cone_maps.md, "Exit bound"):
/// 16 sector codes per texel (0 is 0, 255 is +inf); empty where the search runs without
/// it. scan: built as the search builds it (AVX-512 or AVX2 as ConeSearchIsa() says);
/// otherwise from every cell of the window, with no skipping (the scan's oracle).
std::vector<uint8_t> RelaxedExitField(const DepthField& hf, int steps, bool scan);

/// Apex depth of stacked cone k of K: d * (K - k) / K (k = 0: the surface point).
inline float StackedApex(float d, int k, int K) { return d * (float(K - k) / float(K)); }

/// n_z of the cone side normal from a ratio r: r / sqrt(1 + r^2); 1 for an unbounded
/// cone.
inline float ConeNormalFromRatio(double r) {
    if (!(r < double(kConeRatioCap))) return 1.0f;
    return RoundDownStrict(r / std::sqrt(1.0 + r * r));
}

/// Counts work units done by any thread and reports whole percents to a ConeMapProgress
/// (serialised, growing). A no-op without a callback.
class ProgressCounter {
  public:
    ProgressCounter(const ConeMapProgress& f, int64_t total)
        : f_(f), total_(std::max<int64_t>(total, 1)) {}
    void Add(int64_t n) {
        if (!f_) return;
        const int64_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
        const int pct = int(std::min<int64_t>(100, done * 100 / total_));
        if (pct <= reported_.load(std::memory_order_relaxed)) return;
        std::lock_guard<std::mutex> lock(m_);
        if (pct <= reported_.load(std::memory_order_relaxed)) return;
        reported_.store(pct, std::memory_order_relaxed);
        f_(double(pct) / 100.0);
    }

  private:
    const ConeMapProgress& f_;
    int64_t total_;
    std::atomic<int64_t> done_{0};
    std::atomic<int> reported_{0};
    std::mutex m_;
};

}  // namespace reliefsim::detail
