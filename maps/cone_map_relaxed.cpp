// Relaxed cone maps by Policarpo & Oliveira's Listing 18-1/18-2 (GPU Gems 3, ch. 18): the
// definition in float (GPU) arithmetic, its brute force, and the fast exact generator.
// Used by `relaxed`, `cone-normal --relaxed` and `stacked --relaxed` (apex above the
// surface).
//
// The fast generator evaluates the same float Listing and skips only (source,
// destination) pairs that provably cannot lower the running minimum, by two bounds: the
// distance bound (the march moves away from the source and down) and the exit bound (the
// exit field: per texel and 22.5 degree sector, a lower bound of the distance to a cell
// that can end the march). Both apply to single offsets and to 4x4, 8x8 and 32x32 groups
// of offsets. Stages: BuildExitField, GroupTileOffsets and BoundSuperTiles set up the
// bounds, RelaxedSearch::SearchTexel searches one texel (super-tiles, tiles, quarters,
// offsets). Proofs, with the slack terms for float error: docs/cone_maps.md, section
// "Exact pruning of the Listing".
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "core/error.h"
#include "maps/cone_map.h"
#include "maps/cone_map_detail.h"

namespace reliefsim::detail {

namespace {

/// Nearest-texel index of a float texel coordinate f = u * n, wrapped: the listing's
/// point sampling with repeat. Same result as fmod on the float (exact) for every f; the
/// integer path is only taken where the conversion cannot overflow.
RS_INLINE int WrapFloorIndex(float f, int n) {
    const float fi = std::floor(f);
    if (std::abs(fi) < 1073741824.0f) {
        const int k = int(fi);
        if (k >= 0 && k < n) return k;
        if (k < 0 && k >= -n) return k + n;
        if (k >= n && k < 2 * n) return k - n;
        return Wrap(k % n, n);
    }
    return Wrap(int(std::fmod(double(fi), double(n))), n);
}

RS_INLINE float NearestWrap(const DepthField& hf, float u, float v) {
    const int i = WrapFloorIndex(u * float(hf.width), hf.width);
    const int j = WrapFloorIndex(v * float(hf.height), hf.height);
    return hf.depth[size_t(j) * size_t(hf.width) + size_t(i)];
}

constexpr float kInfF = std::numeric_limits<float>::infinity();

/// i mod n for i in [-n, 2n).
inline int WrapNear(int i, int n) { return i < 0 ? i + n : (i >= n ? i - n : i); }
constexpr int kSectors =
    16;  ///< exit-field sectors: closed 22.5° wedges counter-clockwise from +u
using SectorBits = uint16_t;
constexpr SectorBits kAllSectors = 0xFFFF;

/// One coordinate of the listing's forward step: v / steps (v * inv when steps is a power
/// of two and inv = 1/steps, the same float). The exit field uses it too, so that its
/// threshold is the march's z after the first step bit for bit.
RS_INLINE float ListingStep(float v, int steps, float inv) {
    return inv > 0.0f ? v * inv : v / float(steps);
}

/// The listing's float arithmetic for one pair, given the source position (sx, sy), the
/// destination (dstx, dsty) and its sampled depth dstz. `inv` = 1/steps when steps is a
/// power of two (then v * inv == v / steps exactly: scaling by a power of two), else 0
/// (divide). `clear` (uv, 0 when unknown; used only when best < +inf): a march point
/// nearer the destination than this, along the float step, provably samples a cell no
/// deeper than the march's z after its first step (the exit field, ExitField), so the
/// march does not sample there (docs/cone_maps.md, section "Early outs inside the
/// march").
RS_INLINE float ListingRatio(const DepthField& hf, float sx, float sy, float dstx,
                             float dsty, float dstz, int steps, float inv, float apex,
                             float best, double clear = 0) {
    if (!(dstz > 0.0f)) return kInfF;  // NaN in the listing
    const float src = apex;
    // Exit point deeper than the apex: the march only goes deeper (step z >= 0), ratio 1.
    if (!(dstz < src)) return 1.0f;
    float vx = dstx - sx, vy = dsty - sy, vz = dstz;
    // Early out, provably exact (no margin; proof: docs/cone_maps.md, section "Early outs
    // inside the march"). best = +inf, the brute force's default, never prunes.
    const bool prune = best < kInfF;
    if (prune) {
        const float lb = std::sqrt(vx * vx + vy * vy) / (src - dstz);
        if (lb >= best) return best;
    }
    vx /= vz;
    vy /= vz;
    vz /= vz;
    const float scale = 1.0f - dstz;
    vx *= scale;
    vy *= scale;
    vz *= scale;
    const float stx = ListingStep(vx, steps, inv), sty = ListingStep(vy, steps, inv),
                stz = ListingStep(vz, steps, inv);
    float px = dstx + stx, py = dsty + sty, pz = dstz + stz;
    if (pz >= src) return 1.0f;
    int i = 1;
    if (prune && clear > 0) {
        // Samples k = 1..k0 with k |step| < clear continue the march: only their sums.
        const double step2 = double(stx) * double(stx) + double(sty) * double(sty);
        if (step2 > 0) {
            const double k = std::floor(clear / std::sqrt(step2));
            int k0 = k < double(steps) ? int(k) : steps - 1;
            while (k0 > 0 && double(k0) * double(k0) * step2 >= clear * clear) --k0;
            for (; i <= k0; ++i) {
                px += stx;
                py += sty;
                pz += stz;
            }
            if (pz >= src) return 1.0f;
        }
    }
    const double best2 = double(best) * double(best) * (1.0 + 0x1p-20);
    for (; i < steps; ++i) {
        if (NearestWrap(hf, px, py) <= pz) {
            px += stx;
            py += sty;
            pz += stz;
            if (pz >= src) return 1.0f;
            if (prune) {
                // The same bound at the current point, without sqrt or division (proof:
                // docs/cone_maps.md, section "Early outs inside the march").
                const double cx = double(px - sx), cy = double(py - sy);
                const double den = double(src - pz);
                if (cx * cx + cy * cy >= best2 * den * den) return best;
            }
        } else {
            break;  // the listing keeps sampling the same point from here on: same result
        }
    }
    const float ex = px - sx, ey = py - sy;
    return std::sqrt(ex * ex + ey * ey) / (src - pz);
}

/// 1/steps when steps is a power of two, else 0.
float PowerOfTwoInverse(int steps) {
    return (steps & (steps - 1)) == 0 ? 1.0f / float(steps) : 0.0f;
}

}  // namespace

float RelaxedPairRatio(const DepthField& hf, int ti, int tj, int dx, int dy, int steps,
                       float apex) {
    const float W = float(hf.width), H = float(hf.height);
    const float sx = (float(ti) + 0.5f) / W, sy = (float(tj) + 0.5f) / H;
    const float dstx = sx + float(dx) / W, dsty = sy + float(dy) / H;
    return ListingRatio(hf, sx, sy, dstx, dsty, NearestWrap(hf, dstx, dsty), steps, 0.0f,
                        apex, kInfF);
}

namespace {

/// v rounded to a float at most v, and at least 0.
float NonNegFloatAtMost(double v) { return std::max(FloatAtMost(v), 0.0f); }

/// Bounds on where the listing's float march can stop, and the exit field: per texel t
/// (depth b) and sector k, L[t * kSectors + k] <= the uv distance from t's centre to
/// every cell deeper than t(b) = fl(b + fl(fl(1 - b) / steps)) (the march's z after its
/// first step) whose eps-dilation meets the closed wedge k at t's centre (cells beyond
/// the searched window count as being at the window's edge; +inf when no cell is deeper
/// than t(b)).
struct ExitField {
    double eps =
        0;  ///< uv: march points lie within eps of the exact ray (MakeExitFieldSlack)
    double eta = 0;  ///< depth: accumulated rounding of the march's z
    bool usable = false;
    // One byte per value, a code of ExitCodes (rounded down, so still a lower bound):
    // 64 MB each at 2048², against 128 MB as bfloat16 and 256 MB as floats.
    std::vector<uint8_t> L;  ///< kSectors per texel
    std::vector<uint8_t>
        Lwin;  ///< kSectors per texel: min of L over the 8x8 window starting there
    std::vector<uint8_t> Lwin4;       ///< the same over the 4x4 window
    std::vector<uint8_t> Lwin32;      ///< the same over the 32x32 window
    std::array<float, 256> decode{};  ///< code -> uv distance (ExitCodes)
};

/// The exit field's byte codes: 0 is 0, 255 is +inf, and 1..254 are uv distances in
/// geometric steps from a quarter texel (1/4 of 1/max(W, H)) to `edge` (the largest
/// finite value of the field), each rounded down to a float: a step of 2.8% at 2048²
/// (edge = 256 texels), 2.6% at 1024². A value is stored as the largest code whose
/// distance is at most the value, so the codes' order is the values' order and a
/// decoded code is a lower bound.
std::array<float, 256> ExitCodes(int W, int H, float edge) {
    std::array<float, 256> d{};
    const double lo = 0.25 / double(std::max(W, H));
    const double r = std::pow(std::max(double(edge), 2 * lo) / lo, 1.0 / 253.0);
    d[0] = 0.0f;
    for (int c = 1; c < 255; ++c)
        d[size_t(c)] = NonNegFloatAtMost(lo * std::pow(r, c - 1));
    d[254] = std::min(d[254], edge);
    d[255] = kInfF;
    for (int c = 1; c < 256; ++c) RS_CHECK(d[size_t(c)] > d[size_t(c - 1)]);
    return d;
}

/// The code of a distance v >= 0 (the largest c with decode[c] <= v).
inline uint8_t EncodeDown(const std::array<float, 256>& decode, float v) {
    const auto it = std::upper_bound(decode.begin(), decode.end(), v);
    return uint8_t(it - decode.begin() - 1);
}

/// eps covers, for a march point E whose ratio is < 1 (so |E - src| < 1 and |E| < 2): the
/// float source and destination positions (< 2^-23 per coordinate) and the accumulation
/// of up to `steps` float additions (< 2^-24 each): E lies within eps of the ray from the
/// exact destination centre along the float step vector. The same eps also covers the
/// rounding of |E - src| against |dst - src| + the distance travelled
/// (docs/cone_maps.md, section "Exit bound").
ExitField MakeExitFieldSlack(const DepthField& hf, int steps) {
    ExitField f;
    const double n = double(std::max(hf.width, hf.height));
    f.eps = 0x1p-18 + double(steps) * 0x1p-23;
    f.eta = double(steps) * 0x1p-24 + 0x1p-21;
    // The march may also end by running out of steps, at pz >= 1 - eta, where the float
    // ratio is >= fl|v| / (apex - pz) >= (1 / n - 2^-21) / eta. The exit bound ignores
    // that ending, so it is used only where such a ratio is always >= 1 (then it cannot
    // lower the minimum).
    f.usable = (1.0 / n - 0x1p-20) >= 2.0 * f.eta && n <= 65536.0;
    return f;
}

constexpr double kSectorAngle = 2 * std::numbers::pi / kSectors;

/// Closed sectors that meet the angle interval [lo, hi] (radians, any turn, hi - lo < 2
/// pi).
SectorBits IntervalSectorMask(double lo, double hi) {
    constexpr double kPi = std::numbers::pi;
    SectorBits m = 0;
    for (int k = 0; k < kSectors; ++k) {
        const double s0 = k * kSectorAngle, s1 = (k + 1) * kSectorAngle;
        for (int w = -2; w <= 2; ++w)
            if (lo + 2 * kPi * w <= s1 && hi + 2 * kPi * w >= s0)
                m |= SectorBits(1u << k);
    }
    return m;
}

/// Closed sectors met by the rectangle [x0, x1] x [y0, y1] (uv, relative to the apex),
/// conservatively (a tolerance widens every test); all sectors when it contains the
/// origin.
SectorBits RectSectorMask(double x0, double x1, double y0, double y1) {
    if (x0 <= 0 && x1 >= 0 && y0 <= 0 && y1 >= 0) return kAllSectors;
    constexpr double kPi = std::numbers::pi;
    const double mid = std::atan2(0.5 * (y0 + y1), 0.5 * (x0 + x1));
    double lo = 0, hi = 0;
    for (double x : {x0, x1})
        for (double y : {y0, y1}) {
            const double a = std::remainder(std::atan2(y, x) - mid, 2 * kPi);
            lo = std::min(lo, a);
            hi = std::max(hi, a);
        }
    return IntervalSectorMask(lo + mid - 1e-9, hi + mid + 1e-9);
}

/// The exit-field search window: offsets in [-R, R]^2 (unwrapped, texel units) in 8x8
/// tiles sorted by their smallest dilated distance.
struct ExitOffset {
    float dist;  ///< uv distance from the centre to the eps-dilated cell, rounded down
    SectorBits mask;
};
/// An 8x8 tile of the window: offsets[begin + 8 * ly + lx] is (ox + lx, oy + ly) (the
/// offsets outside the window and (0, 0) are empty slots, in no sector's mask).
struct ExitTile {
    int begin, ox, oy;
    float minDist;
    SectorBits mask;
};

/// The exit-field search window of radius (Rx, Ry) texels: its offsets (but (0, 0)) in
/// 8x8 tiles, the tiles in 32x32 super-tiles (4x4 tiles), each sorted by its smallest
/// distance to the eps-dilated cells: super-tiles in `supers`, the tiles of each in
/// `tiles[first, last)`.
struct ExitSuper {
    int first, last, ox, oy;
    float minDist;
    SectorBits mask;
};
struct ExitWindow {
    std::vector<ExitOffset> offs;
    /// Per tile (block begin / 64) and sector: the slots whose mask holds the sector.
    std::vector<uint64_t> sectorSlots;
    std::vector<ExitTile> tiles;
    std::vector<ExitSuper> supers;
};
ExitWindow MakeExitWindow(int W, int H, int Rx, int Ry, double e) {
    ExitWindow win;
    std::vector<ExitOffset>& offs = win.offs;
    constexpr int kSuper = kSuperTile * kTile;
    for (int sy = -Ry; sy <= Ry; sy += kSuper)
        for (int sx = -Rx; sx <= Rx; sx += kSuper) {
            ExitSuper st{int(win.tiles.size()), 0, sx, sy, kInfF, 0};
            for (int oy = sy; oy < std::min(sy + kSuper, Ry + 1); oy += kTile)
                for (int ox = sx; ox < std::min(sx + kSuper, Rx + 1); ox += kTile) {
                    ExitTile t{int(offs.size()), ox, oy, kInfF, 0};
                    bool any = false;
                    offs.resize(offs.size() + kTile * kTile, ExitOffset{kInfF, 0});
                    win.sectorSlots.resize(offs.size() / (kTile * kTile) * kSectors, 0);
                    uint64_t* slotsOf =
                        &win.sectorSlots[win.sectorSlots.size() - kSectors];
                    for (int dy = oy; dy < std::min(oy + kTile, Ry + 1); ++dy)
                        for (int dx = ox; dx < std::min(ox + kTile, Rx + 1); ++dx) {
                            if (dx == 0 && dy == 0) continue;
                            const double x0 = (dx - 0.5) / W - e, x1 = (dx + 0.5) / W + e;
                            const double y0 = (dy - 0.5) / H - e, y1 = (dy + 0.5) / H + e;
                            const double ax = std::max({0.0, x0, -x1}),
                                         ay = std::max({0.0, y0, -y1});
                            const ExitOffset o{
                                NonNegFloatAtMost(std::sqrt(ax * ax + ay * ay) *
                                                  (1 - 1e-12)),
                                RectSectorMask(x0, x1, y0, y1)};
                            const int slot = (dy - oy) * kTile + (dx - ox);
                            offs[size_t(t.begin + slot)] = o;
                            any = true;
                            for (unsigned m = o.mask; m; m &= m - 1)
                                slotsOf[std::countr_zero(m)] |= uint64_t(1) << slot;
                            t.minDist = std::min(t.minDist, o.dist);
                            t.mask |= o.mask;
                        }
                    if (!any) {
                        offs.resize(size_t(t.begin));
                        win.sectorSlots.resize(win.sectorSlots.size() - kSectors);
                        continue;
                    }
                    win.tiles.push_back(t);
                    st.minDist = std::min(st.minDist, t.minDist);
                    st.mask |= t.mask;
                }
            st.last = int(win.tiles.size());
            if (st.last == st.first) continue;
            std::stable_sort(win.tiles.begin() + st.first, win.tiles.end(),
                             [](const ExitTile& a, const ExitTile& b) {
                                 return a.minDist < b.minDist;
                             });
            win.supers.push_back(st);
        }
    std::stable_sort(
        win.supers.begin(), win.supers.end(),
        [](const ExitSuper& a, const ExitSuper& b) { return a.minDist < b.minDist; });
    return win;
}

/// i mod n for any i; without a division for i in [-n, 2n) (the exit window wraps more
/// than once only on maps smaller than it).
inline int WrapFast(int i, int n) {
    return i >= -n && i < 2 * n ? WrapNear(i, n) : Wrap(i, n);
}

/// Sectors of `mask` whose L is above v.
RS_INLINE SectorBits OpenSectors(const float* L, SectorBits mask, float v) {
    unsigned open = 0;
    for (int k = 0; k < kSectors; ++k) open |= unsigned(L[k] > v) << k;
    return SectorBits(open & mask);
}

/// The exit field of texel (i, j) into L[0..kSectors): per sector, the distance to the
/// nearest cell deeper than d (the march's z after its first step) in the window, `edge`
/// when none is. max8, max32: depth maxima over the 8x8 and 32x32 windows (tiles and
/// super-tiles without a deeper cell are skipped).
void ExitDistancesOfTexel(const DepthField& hf, const ExitWindow& win,
                          const std::vector<float>& max8, const std::vector<float>& max32,
                          int i, int j, float d, float edge, float* L) {
    const int W = hf.width, H = hf.height;
    std::fill(L, L + kSectors, edge);
    float worst = edge;
    for (const ExitSuper& st : win.supers) {
        if (st.minDist >= worst) break;
        if (!OpenSectors(L, st.mask, st.minDist)) continue;
        if (!(max32[size_t(WrapFast(j + st.oy, H)) * size_t(W) +
                    size_t(WrapFast(i + st.ox, W))] > d))
            continue;
        for (int x = st.first; x < st.last; ++x) {
            const ExitTile& t = win.tiles[size_t(x)];
            if (t.minDist >= worst) break;  // sorted by distance
            const SectorBits open = OpenSectors(L, t.mask, t.minDist);
            if (!open) continue;
            const int wy = WrapFast(j + t.oy, H), wx = WrapFast(i + t.ox, W);
            if (!(max8[size_t(wy) * size_t(W) + size_t(wx)] > d)) continue;
            // The slots in an open sector, and of those the cells deeper than d, one bit
            // per slot, a row at a time.
            const uint64_t* slotsOf =
                &win.sectorSlots[size_t(t.begin / (kTile * kTile)) * kSectors];
            uint64_t wanted = 0;
            for (unsigned m = open; m; m &= m - 1) wanted |= slotsOf[std::countr_zero(m)];
            uint64_t deeper = 0;
            for (int a = 0; a < kTile; ++a) {
                const unsigned rowWanted = unsigned(wanted >> (kTile * a)) & 0xFFu;
                if (!rowWanted) continue;
                const float* row = &hf.depth[size_t(WrapFast(wy + a, H)) * size_t(W)];
                unsigned bits = 0;
                if (wx + kTile <= W) {
                    for (int b = 0; b < kTile; ++b)
                        bits |= unsigned(row[wx + b] > d) << b;
                } else {
                    for (int b = 0; b < kTile; ++b)
                        bits |= unsigned(row[WrapFast(wx + b, W)] > d) << b;
                }
                deeper |= uint64_t(bits & rowWanted) << (kTile * a);
            }
            bool changed = false;
            for (; deeper; deeper &= deeper - 1) {
                const ExitOffset& off =
                    win.offs[size_t(t.begin + std::countr_zero(deeper))];
                changed |= LowerMasked(unsigned(off.mask), off.dist, L);
            }
            if (changed) worst = *std::max_element(L, L + kSectors);
        }
    }
}

/// The exit field (ExitField) of a map for `steps` steps; empty (usable = false) when
/// its float argument does not hold or it is not wanted. max8, max32: the map's depth
/// maxima over 8x8 and 32x32 windows.
ExitField BuildExitField(const DepthField& hf, int steps, float inv, bool wanted,
                         const std::vector<float>& max8,
                         const std::vector<float>& max32) {
    ExitField f = MakeExitFieldSlack(hf, steps);
    f.usable = f.usable && wanted;
    if (!f.usable) return f;
    const int W = hf.width, H = hf.height;
    const size_t N = size_t(W) * size_t(H);
    // Window radius: 1/8 uv (at least 8 texels); farther exits are bounded by the window
    // edge.
    const int Rx = std::max(8, (W + 7) / 8), Ry = std::max(8, (H + 7) / 8);
    const double e = f.eps;
    const ExitWindow win = MakeExitWindow(W, H, Rx, Ry, e);
    // Every cell outside the window is at least this far (its dilation included).
    const float edge = NonNegFloatAtMost(std::min((Rx + 0.5) / W, (Ry + 0.5) / H) - e);
    float dmax = hf.depth[0];
    for (float d : hf.depth) dmax = std::max(dmax, d);
    // Coded as each texel is done (a float field would take 64 bytes per texel).
    f.decode = ExitCodes(W, H, edge);
    f.L.assign(N * kSectors, 255);
    tbb::parallel_for(
        tbb::blocked_range<int>(0, H, 1), [&](const tbb::blocked_range<int>& r) {
            float L[kSectors];
            for (int j = r.begin(); j < r.end(); ++j)
                for (int i = 0; i < W; ++i) {
                    // A march from this texel stops only in a cell deeper than its z
                    // after the first step, fl(b + fl(fl(1 - b) / steps)) as the listing
                    // computes it (z only grows).
                    const float b = hf.At(i, j);
                    const float d = b + ListingStep(1.0f - b, steps, inv);
                    if (!(d < dmax))
                        continue;  // nothing is deeper: no cell can end a march
                    ExitDistancesOfTexel(hf, win, max8, max32, i, j, d, edge, L);
                    uint8_t* out = &f.L[(size_t(j) * size_t(W) + size_t(i)) * kSectors];
                    for (int k = 0; k < kSectors; ++k)
                        out[k] = EncodeDown(f.decode, L[k]);
                }
        });
    // Window minima of L per sector, for offset tiles (8x8) and their quarters (4x4),
    // on the codes (their order is the distances' order).
    f.Lwin4 = WindowMinima(f.L, W, H, kSectors, 4);
    f.Lwin = WindowMinima(f.Lwin4, W, H, kSectors, 2, 4);
    f.Lwin32 = WindowMinima(f.Lwin, W, H, kSectors, 4, kTile);
    return f;
}

/// The exit bound, as a test: true when the listing's float ratio is provably >= best (or
/// the march provably ends at or below the apex: ratio 1) for every pair with
/// source-to-destination distance >= dLo (exact uv), numerator factor invD <= (1 - 2^-20)
/// / (distance + 2^-21) (so the depth gained per uv along the ray is >= b * invD),
/// destination depth >= b and exit-field value >= L. Real numbers in double with slack
/// for every float rounding (docs/cone_maps.md, section "Exit bound"); the double
/// roundings here are far inside the 2^-20 margins.
RS_INLINE bool ExitBoundPrunes(const ExitField& f, double dLo, double invD, double b,
                               double L, double apex, double best, double stepLo = 0) {
    // A lower bound of the distance the march travels from the destination before it
    // stops (k * |step| for k >= 1 steps): the exit field, less the float slack, or one
    // step.
    const double lam = std::max(L - 2.0 * f.eps, stepLo);
    if (!(lam > 0)) return false;
    const double den = apex - b - lam * (b * invD) + f.eta;
    if (!(den > 0)) return true;
    return (dLo + lam - f.eps) * (1.0 - 0x1p-20) >= best * den;
}

/// The smallest exit-field value over the sectors of `mask` at texel (or window) t.
inline float MinOverSectors(const ExitField& f, const std::vector<uint8_t>& field,
                            size_t t, unsigned mask) {
    unsigned m = 255;
    const uint8_t* v = &field[t * kSectors];
    for (; mask; mask &= mask - 1) m = std::min(m, unsigned(v[std::countr_zero(mask)]));
    return f.decode[m];
}

/// One offset of the pruned search, with what its tests need. The bounds are floats
/// rounded down from their double values (each is used as a lower bound; 36 bytes an
/// offset, and a 2048² map has 4 M offsets).
struct RelaxedOffset {
    float distLo;  ///< below the float distance bound (MakeRelaxedOffset's margins)
    float dist;    ///< uv distance (rounded down)
    float invD;    ///< (1 - 2^-20) / (dist + 2^-21), rounded down
    float stepK;   ///< one march step is >= stepK * (1 - b) / b (b: destination depth)
    int dx, dy;
    float fdx, fdy;   ///< float(dx) / W, float(dy) / H: the listing's offset
    uint8_t lx, ly;   ///< position in its 8x8 tile
    SectorBits mask;  ///< sectors the listing's float step direction can lie in
};
/// A group of offsets (an 8x8 tile or one of its 4x4 quarters) with bounds for all of
/// them.
struct RelaxedGroup {
    int begin = 0, end = 0;  ///< range in the offset list
    int ox = 0, oy = 0;      ///< window origin relative to the source texel
    double distLo = 0;       ///< min distLo of its offsets
    double dLo = 0;          ///< min exact distance
    double invD = 1;         ///< min invD (farthest offset)
    SectorBits mask = 0;     ///< union of the offsets' sectors
    void Add(const RelaxedOffset& o) {
        Add(double(o.distLo), double(o.dist), double(o.invD), o.mask);
    }
    /// Extends the bounds to a whole group (a tile into its super-tile); counts one
    /// member.
    void Add(const RelaxedGroup& g) { Add(g.distLo, g.dLo, g.invD, g.mask); }

  private:
    void Add(double lo, double d, double inv, SectorBits m) {
        distLo = begin == end ? lo : std::min(distLo, lo);
        dLo = begin == end ? d : std::min(dLo, d);
        invD = std::min(invD, inv);
        mask |= m;
        ++end;
    }
};
struct RelaxedTile {
    RelaxedGroup all;
    RelaxedGroup quarter[4];
    int nx = 0, ny = 0;  ///< extent of its offsets
};
enum class RelaxedOut { Ratio, ConeNormal, Stacked };

/// The output of a relaxed map: ratios, n_z of them, or K stacked channels.
struct RelaxedOutput {
    RelaxedOut out = RelaxedOut::Ratio;
    int K = 1;  ///< channels (stacked cones)
    ConeMap m;
    /// Apex depth of channel c at a texel of depth d.
    float Apex(float d, int c) const {
        return out == RelaxedOut::Stacked ? StackedApex(d, c, K) : d;
    }
    void Store(int i, int j, int c, float best) {
        m.values[(size_t(j) * size_t(m.width) + size_t(i)) * size_t(K) + size_t(c)] =
            out == RelaxedOut::ConeNormal ? ConeNormalFromRatio(double(best)) : best;
    }
};

/// The brute force: every pair of the definition, no pruning (the oracle).
void BruteRelaxedMap(const DepthField& hf, const ConeMapParams& p, const Geometry& g,
                     RelaxedOutput& out) {
    const int W = hf.width, H = hf.height, K = out.K;
    const std::vector<Offset> offs = MakeOffsets(g, ConeKind::Cone);
    ProgressCounter progress(p.progress, H);
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 1),
                      [&](const tbb::blocked_range<int>& r) {
                          for (int j = r.begin(); j < r.end(); ++j, progress.Add(1))
                              for (int i = 0; i < W; ++i)
                                  for (int c = 0; c < K; ++c) {
                                      const float apex = out.Apex(hf.At(i, j), c);
                                      float best = 1.0f;
                                      for (const Offset& o : offs) {
                                          const float r2 = RelaxedPairRatio(
                                              hf, i, j, o.dx, o.dy, p.searchSteps, apex);
                                          if (best > r2) best = r2;
                                      }
                                      out.Store(i, j, c, best);
                                  }
                      });
}

/// One offset of tile t with its bounds (margins: docs/cone_maps.md, section "Margins of
/// the per-offset bounds").
RelaxedOffset MakeRelaxedOffset(const Offset& off, const OffsetTile& t, const Geometry& g,
                                int W, int H, int steps) {
    RelaxedOffset ro;
    const double dist = std::sqrt(double(off.s)) / g.scale;
    ro.dist = NonNegFloatAtMost(dist);
    ro.distLo = NonNegFloatAtMost(std::max(0.0, dist - 0x1p-20) * (1.0 - 0x1p-19));
    ro.invD = NonNegFloatAtMost((1.0 - 0x1p-20) * (1.0 - 0x1p-40) / (dist + 0x1p-21));
    ro.stepK = NonNegFloatAtMost(std::max(0.0, dist - 0x1p-22) / double(steps) *
                                 (1.0 - 0x1p-20) * (1.0 - 0x1p-30));
    ro.dx = off.dx;
    ro.dy = off.dy;
    ro.fdx = float(off.dx) / float(W);
    ro.fdy = float(off.dy) / float(H);
    ro.lx = uint8_t(off.dx - t.ox);
    ro.ly = uint8_t(off.dy - t.oy);
    // Sectors the listing's float step direction can lie in (tolerance:
    // docs/cone_maps.md, section "Margins of the per-offset bounds").
    const double angle = std::atan2(double(off.dy) / H, double(off.dx) / W);
    const double tol = 0x1p-22 / dist + 1e-12;
    ro.mask = IntervalSectorMask(angle - tol, angle + tol);
    return ro;
}

/// The offsets of the pruned search: the tiled offsets of the brute force (8x8 tiles
/// sorted by distance), inside a tile grouped by 4x4 quarter, with the bounds of every
/// quarter, tile and 32x32 super-tile.
struct RelaxedGroups {
    std::vector<RelaxedOffset> offs;
    std::vector<RelaxedTile> tiles;
    std::vector<RelaxedGroup> superBounds;  ///< per to.supers entry
};

/// Offsets and groups of every tile of `to`, quarter by quarter.
void GroupTileOffsets(const TiledOffsets& to, const Geometry& g, int W, int H, int steps,
                      RelaxedGroups& groups) {
    std::vector<RelaxedOffset>& offs = groups.offs;
    offs.reserve(to.offsets.size());
    groups.tiles.resize(to.tiles.size());
    for (size_t ti = 0; ti < to.tiles.size(); ++ti) {
        const OffsetTile& t = to.tiles[ti];
        RelaxedTile& rt = groups.tiles[ti];
        std::vector<RelaxedOffset> q[4];
        for (int o = t.begin; o < t.end; ++o) {
            const RelaxedOffset off =
                MakeRelaxedOffset(to.offsets[size_t(o)], t, g, W, H, steps);
            rt.nx = std::max(rt.nx, int(off.lx) + 1);
            rt.ny = std::max(rt.ny, int(off.ly) + 1);
            q[(off.lx >= 4 ? 1 : 0) + (off.ly >= 4 ? 2 : 0)].push_back(off);
        }
        rt.all.begin = rt.all.end = int(offs.size());
        rt.all.ox = t.ox;
        rt.all.oy = t.oy;
        for (int k = 0; k < 4; ++k) {
            RelaxedGroup& gq = rt.quarter[k];
            gq.begin = gq.end = int(offs.size());
            gq.ox = t.ox + (k & 1) * 4;
            gq.oy = t.oy + (k >> 1) * 4;
            for (const RelaxedOffset& off : q[k]) {
                offs.push_back(off);
                gq.Add(off);
                rt.all.Add(off);
            }
        }
    }
}

/// Bounds of the 32x32 super-tiles of the tiled offsets (to.supers, sorted by distance;
/// their tiles sorted by distance inside). Any order of evaluation gives the same
/// minimum.
void BoundSuperTiles(const TiledOffsets& to, RelaxedGroups& groups) {
    groups.superBounds.resize(to.supers.size());
    for (size_t si = 0; si < to.supers.size(); ++si) {
        const OffsetSuperTile& st = to.supers[si];
        RelaxedGroup& sb = groups.superBounds[si];
        sb.ox = st.ox;
        sb.oy = st.oy;
        for (int x = st.first; x < st.last; ++x)
            sb.Add(groups.tiles[size_t(to.superOrder[size_t(x)])].all);
    }
}

/// The running minimum of one (texel, channel) search and the destination that set it.
struct RelaxedBest {
    float best = 1.0f;
    int argDx = 0, argDy = 0;
    bool found = false;
};

/// Per texel, over the windows of the search's groups starting there (4x4 quarters, 8x8
/// tiles, 32x32 super-tiles): the least and the greatest depth; and (1 - b) / b of the
/// texel's own depth b, rounded down (0 where b = 0).
struct DepthWindows {
    std::vector<float> min4, min8, min32;
    std::vector<float> max4, max8, max32;
    std::vector<float> shallow;
};

/// The pruned search of one (source texel, apex): the listing's ratio of every pair that
/// survives the bounds, tile group by tile group. Pruning is exact (the distance bound
/// below the listing's float bound, for offsets and whole groups, and the exit bound): a
/// pair is skipped only when its listing ratio provably cannot lower the running minimum;
/// ties do not change it either (strict "<" as in the listing), so the minimum equals the
/// brute force's for any order of evaluation (proof: docs/cone_maps.md, section "Exact
/// pruning of the Listing").
struct RelaxedSearch {
    const DepthField& hf;
    const TiledOffsets& to;
    const RelaxedGroups& groups;
    const DepthWindows& dw;
    const ExitField& ef;
    int steps;  ///< the listing's search steps
    float inv;  ///< PowerOfTwoInverse(steps)
    float dmin;
    int halfX;  ///< Geometry::halfX
    // The texel searched and its running minimum.
    int i = 0, j = 0;
    float apex = 0;
    double dApex = 0;
    float sx = 0, sy = 0;  ///< the listing's source position
    RelaxedBest rb;

    RelaxedSearch(const DepthField& hf, const TiledOffsets& to,
                  const RelaxedGroups& groups, const DepthWindows& dw,
                  const ExitField& ef, int steps, float inv, float dmin, int halfX)
        : hf(hf),
          to(to),
          groups(groups),
          dw(dw),
          ef(ef),
          steps(steps),
          inv(inv),
          dmin(dmin),
          halfX(halfX) {}

    /// The listing's ratio of one pair; lowers the running minimum.
    RS_INLINE void Consider(int dx, int dy, float fdx, float fdy, float b,
                            double clear = 0) {
        const float r = ListingRatio(hf, sx, sy, sx + fdx, sy + fdy, b, steps, inv, apex,
                                     rb.best, clear);
        if (rb.best > r) {
            rb.best = r;
            rb.argDx = dx;
            rb.argDy = dy;
            rb.found = true;
        }
    }

    /// A group is skipped when no pair in it can lower `best`: no destination above the
    /// apex in its window (minimum depth wmin at window index w), the distance bound, or
    /// the exit bound (lwin: the exit field's minima over windows of the group's size;
    /// wmax: the window's maximum depth, which bounds the length of one march step).
    RS_INLINE bool GroupPrunes(const RelaxedGroup& q, size_t w, float wmin, float wmax,
                               const std::vector<uint8_t>& lwin) const {
        if (!(wmin < apex)) return true;
        if (q.distLo >= double(rb.best) * (dApex - double(wmin))) return true;
        if (!ef.usable) return false;
        // One step of the march is at least |v| (1 - b) / (b steps) long (OffsetPrunes),
        // and (1 - b) / b only shrinks as b grows: the window's deepest texel bounds it.
        if (!(wmax > 0.0f)) return true;  // every destination gives NaN: ignored
        const double bmax = double(wmax);
        const double stepLo = (q.dLo - 0x1p-22) * (1.0 - bmax) / (bmax * double(steps)) *
                              (1.0 - 0x1p-20) * (1.0 - 0x1p-30);
        return ExitBoundPrunes(ef, q.dLo, q.invD, double(wmin),
                               double(MinOverSectors(ef, lwin, w, q.mask)), dApex,
                               double(rb.best), stepLo);
    }

    /// The same for one offset whose destination texel `dst` has depth b. The listing
    /// samples exactly this texel as the destination (its float texel coordinate is
    /// within W * 2^-22 < 1/2 of the centre), so the bounds with its depth hold for the
    /// pair. When it keeps the pair, `clear` is the exit field's value for it (0 without
    /// the field): ListingRatio's `clear`.
    RS_INLINE bool OffsetPrunes(const RelaxedOffset& off, size_t dst, float b,
                                double& clear) const {
        const double db = double(b);
        if (!(b < apex) || double(off.distLo) >= double(rb.best) * (dApex - db))
            return true;
        if (ef.usable) {
            const float lp = MinOverSectors(ef, ef.L, dst, off.mask);
            // One step of the march is |v| (1 - b) / (b steps) long (float roundings of
            // v, the scale and the step within the factors: RelaxedOffset::stepK, and
            // (1 - b) / b rounded down per texel).
            if (!(b > 0.0f)) return true;  // the listing gives NaN: ignored
            const double stepLo = double(off.stepK) * double(dw.shallow[dst]);
            if (ExitBoundPrunes(ef, double(off.dist), double(off.invD), db, double(lp),
                                dApex, double(rb.best), stepLo))
                return true;
            // (1 - 2^-40: the double roundings of ListingRatio's comparison of squares.)
            clear = double(lp) * (1.0 - 0x1p-40);
        }
        return false;
    }

    /// Every offset of tile t that survives its quarter's bound and its own.
    void SearchTile(const RelaxedTile& t, int wx, int wy) {
        const int W = hf.width, H = hf.height;
        // Wrapped rows and columns of the tile's destinations.
        size_t rowBase[kTile];
        int col[kTile];
        for (int a = 0; a < t.ny; ++a)
            rowBase[a] = size_t(WrapNear(wy + a, H)) * size_t(W);
        for (int a = 0; a < t.nx; ++a) col[a] = WrapNear(wx + a, W);
        for (int k = 0; k < 4; ++k) {
            const RelaxedGroup& q = t.quarter[k];
            if (q.begin == q.end) continue;
            const size_t w4 = rowBase[(k >> 1) * 4] + size_t(col[(k & 1) * 4]);
            if (GroupPrunes(q, w4, dw.min4[w4], dw.max4[w4], ef.Lwin4)) continue;
            for (int o = q.begin; o < q.end; ++o) {
                const RelaxedOffset& off = groups.offs[size_t(o)];
                const size_t dst = rowBase[off.ly] + size_t(col[off.lx]);
                const float b = hf.depth[dst];
                double clear = 0;
                if (OffsetPrunes(off, dst, b, clear)) continue;
                Consider(off.dx, off.dy, off.fdx, off.fdy, b, clear);
            }
        }
    }

    /// The tiles of super-tile si, nearest first, until the distance bound stops them.
    void SearchSuperTile(size_t si, double reachAll) {
        const int W = hf.width, H = hf.height;
        const OffsetSuperTile& st = to.supers[si];
        for (int x = st.first; x < st.last; ++x) {
            const RelaxedTile& t = groups.tiles[size_t(to.superOrder[size_t(x)])];
            if (t.all.distLo >= double(rb.best) * reachAll) break;  // sorted by distance
            const int wx = WrapNear(i + t.all.ox, W), wy = WrapNear(j + t.all.oy, H);
            const size_t w0 = size_t(wy) * size_t(W) + size_t(wx);
            if (GroupPrunes(t.all, w0, dw.min8[w0], dw.max8[w0], ef.Lwin)) continue;
            SearchTile(t, wx, wy);
        }
    }

    /// The minimum for texel (ti, tj) and apex `a`, seeded with the pair `seed` (the left
    /// neighbour's minimiser, moved one texel) when seedOk.
    RelaxedBest SearchTexel(int ti, int tj, float a, bool seedOk, int seedDx,
                            int seedDy) {
        const int W = hf.width, H = hf.height;
        i = ti;
        j = tj;
        apex = a;
        rb = RelaxedBest{};
        // The listing's source position and offsets, the same float values as
        // RelaxedPairRatio's; the destination depth is the texel's (it samples exactly
        // it).
        sx = (float(i) + 0.5f) / float(W);
        sy = (float(j) + 0.5f) / float(H);
        if (!(apex > dmin)) return rb;
        // Seed with the destination that set the left neighbour's minimum (ratios are
        // spatially coherent, so `best` starts near its final value and the bounds prune
        // most of the search): any pair of the definition is an upper bound.
        if (seedOk) {
            const int dx = seedDx - 1, dy = seedDy;
            if ((dx != 0 || dy != 0) && dx >= -halfX)
                Consider(dx, dy, float(dx) / float(W), float(dy) / float(H),
                         hf.At(Wrap(i + dx, W), Wrap(j + dy, H)));
        }
        dApex = double(apex);
        const double reachAll = dApex - double(dmin);
        for (size_t si = 0; si < to.supers.size(); ++si) {
            const RelaxedGroup& sb = groups.superBounds[si];
            if (sb.distLo >= double(rb.best) * reachAll) break;  // sorted by distance
            const size_t ws = size_t(WrapNear(j + sb.oy, H)) * size_t(W) +
                              size_t(WrapNear(i + sb.ox, W));
            if (GroupPrunes(sb, ws, dw.min32[ws], dw.max32[ws], ef.Lwin32)) continue;
            SearchSuperTile(si, reachAll);
        }
        return rb;
    }
};

/// The pruned search of every texel and channel, rows in parallel; each texel's search is
/// seeded by its left neighbour's minimiser (docs/cone_maps.md, section "Exact pruning of
/// the Listing").
void PrunedRelaxedMap(const DepthField& hf, const ConeMapParams& p, const Geometry& g,
                      float dmin, bool exitField, RelaxedOutput& out) {
    const int W = hf.width, H = hf.height, K = out.K;
    // Depth maxima over 4x4, 8x8 and 32x32 windows (the exit field's build and the
    // group bounds both use them).
    DepthWindows dw;
    dw.max4 = WindowMaxima(hf.depth, W, H, 4);
    dw.max8 = WindowMaxima(dw.max4, W, H, 2, 4);
    dw.max32 = WindowMaxima(dw.max8, W, H, kSuperTile, kTile);
    // The exit field before the offsets and the other windows: its build's scratch is
    // freed before they are made (peak memory at 2048²).
    const float inv = PowerOfTwoInverse(p.searchSteps);
    const ExitField ef =
        BuildExitField(hf, p.searchSteps, inv, exitField, dw.max8, dw.max32);
    TiledOffsets to = MakeTiledOffsets(g, ConeKind::Cone);
    {
        SearchWindows sw;  // depth minima over 8x8 and 32x32 windows (the tiled search's)
        MakeSearchWindows(hf, sw);
        dw.min8 = std::move(sw.win8);
        dw.min32 = std::move(sw.win32);
    }
    dw.min4 = WindowMinima(hf.depth, W, H, 1, 4);
    dw.shallow.assign(hf.depth.size(), 0.0f);
    for (size_t t = 0; t < dw.shallow.size(); ++t) {
        const double b = double(hf.depth[t]);
        if (b > 0) dw.shallow[t] = NonNegFloatAtMost((1.0 - b) / b);
    }
    RelaxedGroups groups;
    GroupTileOffsets(to, g, W, H, p.searchSteps, groups);
    std::vector<Offset>().swap(to.offsets);  // the groups hold them now
    BoundSuperTiles(to, groups);
    ProgressCounter progress(p.progress, H);
    tbb::parallel_for(
        tbb::blocked_range<int>(0, H, 1), [&](const tbb::blocked_range<int>& rows) {
            RelaxedSearch search(hf, to, groups, dw, ef, p.searchSteps, inv, dmin,
                                 g.halfX);
            for (int j = rows.begin(); j < rows.end(); ++j, progress.Add(1)) {
                int seedDx[16] = {}, seedDy[16] = {};
                bool seedOk[16] = {};
                for (int i = 0; i < W; ++i)
                    for (int c = 0; c < K; ++c) {
                        const RelaxedBest b =
                            search.SearchTexel(i, j, out.Apex(hf.At(i, j), c), seedOk[c],
                                               seedDx[c], seedDy[c]);
                        seedOk[c] = b.found;
                        seedDx[c] = b.argDx;
                        seedDy[c] = b.argDy;
                        out.Store(i, j, c, b.best);
                    }
            }
        });
}

}  // namespace

ConeMap RelaxedListingMap(const DepthField& hf, const ConeMapParams& p, bool brute,
                          ConeKind outKind, bool exitField) {
    const float dmin = CheckedMinDepth(hf);
    if (hf.width > (1 << 20) || hf.height > (1 << 20))
        throw Error(
            "height map \"" + hf.name + "\": " + std::to_string(hf.width) + "x" +
            std::to_string(hf.height) +
            " too large for the relaxed cone map; expected at most 2^20 texels a side "
            "(the float error bounds of its pruning assume it)");
    RelaxedOutput out;
    out.out = outKind == ConeKind::ConeNormal ? RelaxedOut::ConeNormal
              : outKind == ConeKind::Stacked  ? RelaxedOut::Stacked
                                              : RelaxedOut::Ratio;
    out.K = out.out == RelaxedOut::Stacked ? p.stackedCount : 1;
    const Geometry g = MakeGeometry(hf.width, hf.height);
    out.m.kind = outKind;
    out.m.width = hf.width;
    out.m.height = hf.height;
    out.m.channels = out.K;
    out.m.values.assign(size_t(hf.width) * size_t(hf.height) * size_t(out.K), 0.0f);
    if (brute)
        BruteRelaxedMap(hf, p, g, out);
    else
        PrunedRelaxedMap(hf, p, g, dmin, exitField, out);
    return std::move(out.m);
}

}  // namespace reliefsim::detail
