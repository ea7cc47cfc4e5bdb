// Relaxed cone maps by Policarpo & Oliveira's Listing 18-1/18-2 (GPU Gems 3, ch. 18): the
// definition in float (GPU) arithmetic, its brute force, and the fast exact generator.
// Used by `relaxed`, `cone-normal --relaxed` and `stacked --relaxed` (apex above the
// surface).
//
// The fast generator evaluates the same float Listing and skips only (source,
// destination) pairs that provably cannot lower the running minimum, by two bounds: the
// distance bound (the march moves away from the source and down) and the exit bound (the
// exit field: per texel and 22.5 degree sector, a lower bound of the distance to a cell
// that can end the march). Both apply to single pairs and to 4x4, 8x8 and 32x32 windows
// of destinations. The search takes 4x4 source texels at a time (RelaxedTileSearch), so
// that each destination's depth and exit-field bytes are loaded once for up to 16 apexes.
// Stages: BuildExitField, MakeDenseOffsets and MakeLaneWindows set up the bounds,
// RelaxedTileSearch::SearchTile searches one tile (super-tiles, tiles, quarters,
// destinations). Proofs, with the slack terms for float error: docs/cone_maps.md, section
// "Exact pruning of the Listing". Where the lane search runs AVX-512 (ConeSearchIsa), the
// exit field's scan, the window and pair bounds and the marches run in vector registers
// (the *Avx512 functions, VectorSectors, MarchLanes) with the same arithmetic: the same
// maps (docs/cone_maps.md, "With AVX-512").
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/huge_pages.h"
#include "maps/cone_map.h"
#include "maps/cone_map_detail.h"
#include "maps/cone_search.h"

#if RS_HAVE_CONE_SEARCH_AVX
#include <immintrin.h>
/// The AVX-512 parts of the search (where the lane search uses AVX-512, ConeSearchIsa):
/// compiled for it whatever the build's target, called only where the CPU has it.
#define RS_TARGET_AVX512 __attribute__((target("avx512f,avx512dq,avx512bw,avx512vl")))
// GCC 12's AVX-512 intrinsics start some results from _mm512_undefined_*(), which
// -W(maybe-)uninitialized reports where they are inlined (GCC bug 105593, fixed in GCC
// 13): off around this file's AVX-512 code.
#if defined(__clang__)
#define RS_AVX512_WARNINGS_OFF _Pragma("clang diagnostic push")
#define RS_AVX512_WARNINGS_ON _Pragma("clang diagnostic pop")
#else
#define RS_AVX512_WARNINGS_OFF                                      \
    _Pragma("GCC diagnostic push")                                  \
        _Pragma("GCC diagnostic ignored \"-Wmaybe-uninitialized\"") \
            _Pragma("GCC diagnostic ignored \"-Wuninitialized\"")
#define RS_AVX512_WARNINGS_ON _Pragma("GCC diagnostic pop")
#endif
#endif

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
    float code;  ///< the code of `dist` (SetCodes), as a float: what ExitScan takes
    SectorBits mask;
};
/// An 8x8 tile of the window: offsets[begin + 8 * ly + lx] is (ox + lx, oy + ly) (the
/// offsets outside the window and (0, 0) are empty slots, in no sector's mask).
struct ExitTile {
    int begin, ox, oy;
    float minDist;
    SectorBits mask;
    float minCode;  ///< the code of minDist (SetCodes)
};

/// The exit-field search window of radius (Rx, Ry) texels: its offsets (but (0, 0)) in
/// 8x8 tiles, the tiles in 32x32 super-tiles (4x4 tiles), each sorted by its smallest
/// distance to the eps-dilated cells: super-tiles in `supers`, the tiles of each in
/// `tiles[first, last)`.
struct ExitSuper {
    int first, last, ox, oy;
    float minDist;
    SectorBits mask;
    float minCode;  ///< the code of minDist (SetCodes)
};
struct ExitWindow {
    std::vector<ExitOffset> offs;
    /// Per slot of `offs`: the uv distance from the centre to the eps-dilated cell,
    /// rounded down (+inf for empty slots).
    std::vector<float> dist;
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
            ExitSuper st{int(win.tiles.size()), 0, sx, sy, kInfF, 0, 255.0f};
            for (int oy = sy; oy < std::min(sy + kSuper, Ry + 1); oy += kTile)
                for (int ox = sx; ox < std::min(sx + kSuper, Rx + 1); ox += kTile) {
                    ExitTile t{int(offs.size()), ox, oy, kInfF, 0, 255.0f};
                    bool any = false;
                    offs.resize(offs.size() + kTile * kTile, ExitOffset{255.0f, 0});
                    win.dist.resize(offs.size(), kInfF);
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
                            const float dist = NonNegFloatAtMost(
                                std::sqrt(ax * ax + ay * ay) * (1 - 1e-12));
                            const ExitOffset o{255.0f, RectSectorMask(x0, x1, y0, y1)};
                            const int slot = (dy - oy) * kTile + (dx - ox);
                            offs[size_t(t.begin + slot)] = o;
                            win.dist[size_t(t.begin + slot)] = dist;
                            any = true;
                            for (unsigned m = o.mask; m; m &= m - 1)
                                slotsOf[std::countr_zero(m)] |= uint64_t(1) << slot;
                            t.minDist = std::min(t.minDist, dist);
                            t.mask |= o.mask;
                        }
                    if (!any) {
                        offs.resize(size_t(t.begin));
                        win.dist.resize(size_t(t.begin));
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

/// The field is stored as codes (ExitCodes, EncodeDown), and EncodeDown is monotone: the
/// code of a minimum of distances is the minimum of their codes. So ExitScan takes every
/// distance as its code: each offset's, and each tile's and super-tile's least one; a
/// (super-)tile can lower a sector's code only where that code is above the tile's.
void SetCodes(ExitWindow& win, const std::array<float, 256>& decode) {
    const auto code = [&](float v) { return float(EncodeDown(decode, v)); };
    for (size_t s = 0; s < win.offs.size(); ++s) win.offs[s].code = code(win.dist[s]);
    for (ExitTile& t : win.tiles) t.minCode = code(t.minDist);
    for (ExitSuper& st : win.supers) st.minCode = code(st.minDist);
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

/// A texel's 16 sector codes for ExitScan, as an array of floats (the scalar build; the
/// AVX-512 one keeps them in one register, VectorSectors).
struct ScalarSectors {
    float L[kSectors];
    explicit ScalarSectors(float edgeCode) { std::fill(L, L + kSectors, edgeCode); }
    /// Sectors of `mask` whose code is above v.
    SectorBits Open(SectorBits mask, float v) const { return OpenSectors(L, mask, v); }
    /// The 8 cells row[0..8) deeper than d, one bit each.
    static unsigned Deeper(const float* row, float d) {
        unsigned bits = 0;
        for (int b = 0; b < kTile; ++b) bits |= unsigned(row[b] > d) << b;
        return bits;
    }
    /// Lowers the sectors of each cell (bit s of `cells`: offs[s]) to its code; true when
    /// one was above it.
    bool LowerCells(uint64_t cells, const ExitOffset* offs) {
        bool changed = false;
        for (; cells; cells &= cells - 1) {
            const ExitOffset& off = offs[std::countr_zero(cells)];
            changed |= LowerMasked(unsigned(off.mask), off.code, L);
        }
        return changed;
    }
    float Worst() const { return *std::max_element(L, L + kSectors); }
    void Store(uint8_t* out) const {
        for (int k = 0; k < kSectors; ++k) out[k] = uint8_t(L[k]);
    }
};

/// What ExitScan reads: the map, the window, the depth maxima over the 8x8 and 32x32
/// windows (tiles and super-tiles without a deeper cell are skipped) and the window
/// edge's code (SetCodes).
struct ExitScanInputs {
    const DepthField& hf;
    const ExitWindow& win;
    const std::vector<float>& max8;
    const std::vector<float>& max32;
    float edgeCode;
};

/// The exit field of texel (i, j) into L (ScalarSectors, Avx2Sectors or VectorSectors):
/// per sector, the code of the distance to the nearest cell deeper than d (the march's z
/// after its first step) in the window, the window edge's code when none is.
template <class Sectors>
inline void ExitScan(const ExitScanInputs& in, int i, int j, float d, Sectors& L) {
    const DepthField& hf = in.hf;
    const ExitWindow& win = in.win;
    const std::vector<float>&max8 = in.max8, &max32 = in.max32;
    const int W = hf.width, H = hf.height;
    float worst = in.edgeCode;
    for (const ExitSuper& st : win.supers) {
        if (!(worst > st.minCode)) break;  // sorted by distance
        if (!L.Open(st.mask, st.minCode)) continue;
        if (!(max32[size_t(WrapFast(j + st.oy, H)) * size_t(W) +
                    size_t(WrapFast(i + st.ox, W))] > d))
            continue;
        for (int x = st.first; x < st.last; ++x) {
            const ExitTile& t = win.tiles[size_t(x)];
            if (!(worst > t.minCode)) break;  // sorted by distance
            const SectorBits open = L.Open(t.mask, t.minCode);
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
                    bits = Sectors::Deeper(row + wx, d);
                } else {
                    for (int b = 0; b < kTile; ++b)
                        bits |= unsigned(row[WrapFast(wx + b, W)] > d) << b;
                }
                deeper |= uint64_t(bits & rowWanted) << (kTile * a);
            }
            if (L.LowerCells(deeper, &win.offs[size_t(t.begin)])) worst = L.Worst();
        }
    }
}

/// ExitScan of texel (i, j) into the codes out[0..kSectors), in Sectors' registers.
template <class Sectors>
inline void ExitCodesOfTexel(const ExitScanInputs& in, int i, int j, float d,
                             uint8_t* out) {
    Sectors sectors(in.edgeCode);
    ExitScan(in, i, j, d, sectors);
    sectors.Store(out);
}

#if RS_HAVE_CONE_SEARCH_AVX
/// The exit field's AVX2 scan (where the lane search runs its AVX2 unit): compiled for
/// it whatever the build's target, called only where the CPU has it.
#define RS_TARGET_AVX2 __attribute__((target("avx2")))
/// ScalarSectors in two AVX2 registers (sectors 0-7 and 8-15): the same comparisons and
/// minima, so the same codes.
struct Avx2Sectors {
    __m256 lo, hi;
    RS_TARGET_AVX2 explicit Avx2Sectors(float edgeCode)
        : lo(_mm256_set1_ps(edgeCode)), hi(_mm256_set1_ps(edgeCode)) {}
    /// The 8 lanes of `bits` (bit k: lane k) as a vector mask.
    RS_TARGET_AVX2 static __m256 Lanes(unsigned bits) {
        const __m256i one = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        return _mm256_castsi256_ps(
            _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(int(bits)), one), one));
    }
    RS_TARGET_AVX2 static unsigned Above(__m256 a, __m256 b) {
        return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_GT_OQ)));
    }
    RS_TARGET_AVX2 SectorBits Open(SectorBits mask, float v) const {
        const __m256 vv = _mm256_set1_ps(v);
        return SectorBits((Above(lo, vv) | Above(hi, vv) << 8) & unsigned(mask));
    }
    RS_TARGET_AVX2 static unsigned Deeper(const float* row, float d) {
        return Above(_mm256_loadu_ps(row), _mm256_set1_ps(d));
    }
    /// The cells in two running minima (independent chains), then their minimum.
    RS_TARGET_AVX2 bool LowerCells(uint64_t cells, const ExitOffset* offs) {
        __m256 l[2] = {lo, lo}, h[2] = {hi, hi};
        for (int k = 0; cells; cells &= cells - 1, k ^= 1) {
            const ExitOffset& off = offs[std::countr_zero(cells)];
            const __m256 c = _mm256_set1_ps(off.code);
            const unsigned m = unsigned(off.mask);
            l[k] = _mm256_blendv_ps(l[k], _mm256_min_ps(l[k], c), Lanes(m & 0xFFu));
            h[k] = _mm256_blendv_ps(h[k], _mm256_min_ps(h[k], c), Lanes(m >> 8));
        }
        const __m256 nl = _mm256_min_ps(l[0], l[1]), nh = _mm256_min_ps(h[0], h[1]);
        const bool changed = (Above(lo, nl) | Above(hi, nh)) != 0;
        lo = nl;
        hi = nh;
        return changed;
    }
    RS_TARGET_AVX2 float Worst() const {
        __m256 m = _mm256_max_ps(lo, hi);
        m = _mm256_max_ps(m, _mm256_permute2f128_ps(m, m, 1));
        m = _mm256_max_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
        m = _mm256_max_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
        return _mm256_cvtss_f32(m);
    }
    RS_TARGET_AVX2 void Store(uint8_t* out) const {
        alignas(32) float v[kSectors];
        _mm256_store_ps(v, lo);
        _mm256_store_ps(v + 8, hi);
        for (int k = 0; k < kSectors; ++k) out[k] = uint8_t(v[k]);
    }
};

/// ExitCodesOfTexel with AVX2 (flatten: ExitScan and the methods it calls are compiled
/// into it, for AVX2).
RS_TARGET_AVX2 __attribute__((flatten)) void ExitCodesOfTexelAvx2(
    const ExitScanInputs& in, int i, int j, float d, uint8_t* out) {
    ExitCodesOfTexel<Avx2Sectors>(in, i, j, d, out);
}

RS_AVX512_WARNINGS_OFF
/// ScalarSectors in one AVX-512 register: the same comparisons and minima, so the same
/// distances.
struct VectorSectors {
    __m512 L;
    RS_TARGET_AVX512 explicit VectorSectors(float edgeCode)
        : L(_mm512_set1_ps(edgeCode)) {}
    RS_TARGET_AVX512 SectorBits Open(SectorBits mask, float v) const {
        return _mm512_mask_cmp_ps_mask(__mmask16(mask), L, _mm512_set1_ps(v), _CMP_GT_OQ);
    }
    RS_TARGET_AVX512 static unsigned Deeper(const float* row, float d) {
        return _mm256_cmp_ps_mask(_mm256_loadu_ps(row), _mm256_set1_ps(d), _CMP_GT_OQ);
    }
    /// The cells in four running minima (independent chains), then their minimum: the
    /// same minimum as one cell after the other.
    RS_TARGET_AVX512 bool LowerCells(uint64_t cells, const ExitOffset* offs) {
        __m512 m[4] = {L, L, L, L};
        for (int k = 0; cells; cells &= cells - 1, k = (k + 1) & 3) {
            const ExitOffset& off = offs[std::countr_zero(cells)];
            m[k] = _mm512_mask_min_ps(m[k], __mmask16(off.mask), m[k],
                                      _mm512_set1_ps(off.code));
        }
        const __m512 lowered =
            _mm512_min_ps(_mm512_min_ps(m[0], m[1]), _mm512_min_ps(m[2], m[3]));
        const bool changed = _mm512_cmp_ps_mask(lowered, L, _CMP_LT_OQ) != 0;
        L = lowered;
        return changed;
    }
    RS_TARGET_AVX512 float Worst() const { return _mm512_reduce_max_ps(L); }
    RS_TARGET_AVX512 void Store(uint8_t* out) const {
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out),
                         _mm512_cvtepi32_epi8(_mm512_cvttps_epi32(L)));
    }
};

/// ExitCodesOfTexel with AVX-512 (flatten: ExitScan and the methods it calls are
/// compiled into it, for AVX-512).
RS_TARGET_AVX512 __attribute__((flatten)) void ExitCodesOfTexelAvx512(
    const ExitScanInputs& in, int i, int j, float d, uint8_t* out) {
    ExitCodesOfTexel<VectorSectors>(in, i, j, d, out);
}
RS_AVX512_WARNINGS_ON
#endif

/// The exit field of texel (i, j) into L[0..kSectors) from every cell of the window, in
/// no order and with no skipping: ExitScan's oracle.
void ExitDistancesEveryCell(const DepthField& hf, const ExitWindow& win, int i, int j,
                            float d, float edge, float* L) {
    const int W = hf.width, H = hf.height;
    std::fill(L, L + kSectors, edge);
    for (const ExitTile& t : win.tiles)
        for (int slot = 0; slot < kTile * kTile; ++slot) {
            const ExitOffset& o = win.offs[size_t(t.begin + slot)];
            const int x = WrapFast(i + t.ox + slot % kTile, W);
            const int y = WrapFast(j + t.oy + slot / kTile, H);
            if (o.mask && hf.depth[size_t(y) * size_t(W) + size_t(x)] > d)
                LowerMasked(unsigned(o.mask), win.dist[size_t(t.begin + slot)], L);
        }
}

/// How BuildExitField takes a texel's distances: ExitScan (scalar, AVX2 or AVX-512), or
/// every cell of the window (ExitDistancesEveryCell, the tests' oracle).
enum class ExitBuild { Scan, ScanAvx2, ScanAvx512, EveryCell };

/// The exit field's scan for the unit the lane search runs (ConeSearchIsa): AVX-512,
/// AVX2 or scalar; the same codes.
ExitBuild ExitScanBuild() {
#if RS_HAVE_CONE_SEARCH_AVX
    const std::string_view isa = ConeSearchIsa();
    if (isa == "avx512") return ExitBuild::ScanAvx512;
    if (isa == "avx2") return ExitBuild::ScanAvx2;
#endif
    return ExitBuild::Scan;
}

/// The exit field (ExitField) of a map for `steps` steps; empty (usable = false) when
/// its float argument does not hold or it is not wanted. max8, max32: the map's depth
/// maxima over 8x8 and 32x32 windows.
ExitField BuildExitField(const DepthField& hf, int steps, float inv, bool wanted,
                         const std::vector<float>& max8, const std::vector<float>& max32,
                         ExitBuild how) {
    ExitField f = MakeExitFieldSlack(hf, steps);
    f.usable = f.usable && wanted;
    if (!f.usable) return f;
    const int W = hf.width, H = hf.height;
    const size_t N = size_t(W) * size_t(H);
    // Window radius: 1/12 uv (at least 8 texels); farther exits are bounded by the window
    // edge. Against 1/8, the build is cheaper and the search loses little: 0.90-0.95x the
    // time on rocks and noise at 1024² and 2048², 0.99-1.02x on `shapes` (alternating
    // runs of `maps --kind relaxed`; docs/cone_maps.md, "Where the pruned search's work
    // goes").
    const int Rx = std::max(8, (W + 11) / 12), Ry = std::max(8, (H + 11) / 12);
    const double e = f.eps;
    ExitWindow win = MakeExitWindow(W, H, Rx, Ry, e);
    // Every cell outside the window is at least this far (its dilation included).
    const float edge = NonNegFloatAtMost(std::min((Rx + 0.5) / W, (Ry + 0.5) / H) - e);
    float dmax = hf.depth[0];
    for (float d : hf.depth) dmax = std::max(dmax, d);
    // The scan takes the codes themselves (SetCodes; a float field would take 64 bytes
    // per texel); the oracle takes distances, coded as each texel is done.
    f.decode = ExitCodes(W, H, edge);
    SetCodes(win, f.decode);
    const float edgeCode = float(EncodeDown(f.decode, edge));
    AssignOnHugePages(f.L, N * kSectors, uint8_t(255));
    const ExitScanInputs in{hf, win, max8, max32, edgeCode};
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
                    uint8_t* out = &f.L[(size_t(j) * size_t(W) + size_t(i)) * kSectors];
                    if (how == ExitBuild::EveryCell) {
                        ExitDistancesEveryCell(hf, win, i, j, d, edge, L);
                        for (int k = 0; k < kSectors; ++k)
                            out[k] = EncodeDown(f.decode, L[k]);
                        continue;
                    }
#if RS_HAVE_CONE_SEARCH_AVX
                    if (how == ExitBuild::ScanAvx512) {
                        ExitCodesOfTexelAvx512(in, i, j, d, out);
                        continue;
                    }
                    if (how == ExitBuild::ScanAvx2) {
                        ExitCodesOfTexelAvx2(in, i, j, d, out);
                        continue;
                    }
#endif
                    ExitCodesOfTexel<ScalarSectors>(in, i, j, d, out);
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

/// The bounds of offset (dx, dy) (squared distance S = g.S(dx, dy)): RelaxedOffset's
/// distLo, dist, invD, stepK and mask (margins: docs/cone_maps.md, section "Margins of
/// the per-offset bounds").
struct OffsetBounds {
    float distLo, dist, invD, stepK;
    SectorBits mask;
};
OffsetBounds MakeOffsetBounds(const Geometry& g, int W, int H, int steps, int dx,
                              int dy) {
    OffsetBounds ob;
    const double dist = std::sqrt(double(g.S(dx, dy))) / g.scale;
    ob.dist = NonNegFloatAtMost(dist);
    ob.distLo = NonNegFloatAtMost(std::max(0.0, dist - 0x1p-20) * (1.0 - 0x1p-19));
    ob.invD = NonNegFloatAtMost((1.0 - 0x1p-20) * (1.0 - 0x1p-40) / (dist + 0x1p-21));
    ob.stepK = NonNegFloatAtMost(std::max(0.0, dist - 0x1p-22) / double(steps) *
                                 (1.0 - 0x1p-20) * (1.0 - 0x1p-30));
    // Sectors the listing's float step direction can lie in (tolerance:
    // docs/cone_maps.md, section "Margins of the per-offset bounds").
    const double angle = std::atan2(double(dy) / H, double(dx) / W);
    const double tol = 0x1p-22 / dist + 1e-12;
    ob.mask = IntervalSectorMask(angle - tol, angle + tol);
    return ob;
}

/// The windows ahead of a destination (AheadPrunes) in one line: the greatest depth of
/// the 2^(k+1)-square window for k = 0..6 (2x2 to 128x128) that starts at the texel and
/// extends in one quadrant, each as a code whose value (AheadDepth) is at least it.
struct alignas(8) AheadCodes {
    static constexpr size_t kLevels = 7;
    std::array<uint8_t, 8> code{0, 0, 0, 0, 0, 0, 0, 255};  // the last one unused
};
static_assert(sizeof(AheadCodes) == 8, "AheadPrunesAvx512 loads a record as 8 bytes");

/// The value of an AheadCodes code: the depth of that 8-bit code (Unorm8ToFloat, 255: 1,
/// the deepest depth), so that the codes of an 8-bit map's depths are exact.
inline double AheadDepth(uint8_t c) { return double(Unorm8ToFloat(c)); }

/// The least code whose value is at least the depth d, which lies in [0, 1] (255 for
/// NaN).
inline uint8_t AheadCode(float d) {
    if (!(d < 1.0f)) return 255;
    if (!(d > 0.0f)) return 0;
    auto c = int(std::ceil(double(d) * 255.0));
    while (AheadDepth(uint8_t(c)) < double(d)) ++c;  // the product's rounding
    while (c > 0 && AheadDepth(uint8_t(c - 1)) >= double(d)) --c;
    return uint8_t(c);
}

/// Per texel, over the windows of the search's groups starting there (4x4 quarters, 8x8
/// tiles, 32x32 super-tiles): the least and the greatest depth; and (1 - b) / b of the
/// texel's own depth b, rounded down (0 where b = 0).
struct DepthWindows {
    std::vector<float> min4, min8, min32;
    std::vector<float> max4, max8, max32;
    /// ahead[q]: per texel, the windows ahead in quadrant q (bit 0: towards -x, bit 1:
    /// towards -y), rounded up (AheadCodes): a pair's windows are one load of 8 bytes.
    std::array<std::vector<AheadCodes>, 4> ahead;
    std::vector<float> shallow;
    /// The windows ahead of texel t for a march at offset (dx, dy).
    const AheadCodes& Ahead(int dx, int dy, size_t t) const {
        return ahead[(dx < 0 ? 1u : 0u) | (dy < 0 ? 2u : 0u)][t];
    }
};

/// DepthWindows::ahead, from the groups' maxima (4x4, 8x8, 32x32) and the other levels':
/// each level's maxima coded once (AheadCode), then every record written whole.
void MakeWindowsAhead(DepthWindows& dw, const std::vector<float>& depth, int W, int H) {
    const size_t n = size_t(W) * size_t(H);
    std::array<std::vector<uint8_t>, AheadCodes::kLevels> codes;
    const auto code = [&](size_t level, const std::vector<float>& max) {
        ResizeOnHugePages(codes[level], n);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t t = r.begin(); t < r.end(); ++t)
                                  codes[level][t] = AheadCode(max[t]);
                          });
    };
    code(0, WindowMaxima(depth, W, H, 2));
    code(1, dw.max4);
    code(2, dw.max8);
    code(3, WindowMaxima(dw.max8, W, H, 2, 8));
    code(4, dw.max32);
    {
        const std::vector<float> max64 = WindowMaxima(dw.max32, W, H, 2, 32);
        code(5, max64);
        code(6, WindowMaxima(max64, W, H, 2, 64));
    }
    for (size_t q = 0; q < 4; ++q) {
        auto& ahead = dw.ahead[q];
        ResizeOnHugePages(ahead, n);
        tbb::parallel_for(
            tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& r) {
                for (int y = r.begin(); y < r.end(); ++y)
                    for (int x = 0; x < W; ++x) {
                        AheadCodes a;
                        for (size_t level = 0; level < AheadCodes::kLevels; ++level) {
                            // The (2 << level)-square window, towards -x and -y where q
                            // says.
                            const int k = 2 << level;
                            const int x0 = (q & 1) ? WrapFast(x - (k - 1), W) : x;
                            const int y0 = (q & 2) ? WrapFast(y - (k - 1), H) : y;
                            a.code[level] =
                                codes[level][size_t(y0) * size_t(W) + size_t(x0)];
                        }
                        ahead[size_t(y) * size_t(W) + size_t(x)] = a;
                    }
            });
    }
}

/// The apex-tile search: the 4x4 source texels of a tile (its lanes) searched together,
/// so that each destination's depth and exit-field bytes are loaded once for the 16
/// apexes whose offsets reach it. The destinations are enumerated by their offset e from
/// the tile's origin, in windows of 32x32, 8x8 and 4x4 (super-tiles, tiles, quarters);
/// lane l = (lx, ly) reaches destination e by offset e - l. A lane's bounds for a window
/// are those of its own offsets into it (distLo, dLo, invD), but for the sectors, which
/// are the union over the window's lanes (a superset: the bound only gets weaker), so
/// the minimum of each lane is the brute force's (docs/cone_maps.md, section "Exact
/// pruning of the Listing").
constexpr int kApexSide = 4;
constexpr int kLanes = kApexSide * kApexSide;
using LaneBits = uint32_t;

/// The offsets' bounds (OffsetBounds) in a dense table over [-halfX - kPadLo, halfX +
/// kPadHi] x [-halfY - kPadLo, halfY + kPadHi]: the lanes' offsets of every window
/// stay inside it. Offsets outside the definition's range and (0, 0) have distLo = +inf
/// (every bound prunes them).
struct DenseOffsets {
    static constexpr int kPadLo = kApexSide - 1;
    static constexpr int kPadHi = kSuperTile * kTile + kApexSide;
    int hx = 0, hy = 0, pitch = 0;
    /// float(dx) / float(W) and float(dy) / float(H), the listing's destination offsets,
    /// for |dx|, |dy| <= offsetPad (every offset of the table, from any lane of a tile):
    /// the same floats without a division.
    int offsetPad = 0;
    std::vector<float> uOf, vOf;
    float OffsetU(int dx) const {
        RS_DCHECK(dx >= -offsetPad && dx <= offsetPad);
        return uOf[size_t(dx + offsetPad)];
    }
    float OffsetV(int dy) const {
        RS_DCHECK(dy >= -offsetPad && dy <= offsetPad);
        return vOf[size_t(dy + offsetPad)];
    }
    /// One record per offset (a lane's test reads one line), or, for the AVX-512 search
    /// (RelaxedTileSearch::SearchQuarterAvx512, which loads 4 adjacent offsets of a field
    /// at a time), the same fields in arrays of their own: one of the two is filled.
    std::vector<OffsetBounds> at;
    struct Fields {
        std::vector<float> distLo, dist, invD, stepK;
        std::vector<uint32_t> mask;
    } soa;
    size_t Index(int dx, int dy) const {
        return size_t(dy + hy + kPadLo) * size_t(pitch) + size_t(dx + hx + kPadLo);
    }
    OffsetBounds At(size_t o) const {
        if (!at.empty()) return at[o];
        return {soa.distLo[o], soa.dist[o], soa.invD[o], soa.stepK[o],
                SectorBits(soa.mask[o])};
    }
    bool Valid(size_t o) const {
        return (at.empty() ? soa.distLo[o] : at[o].distLo) < kInfF;
    }
};

/// The dense table of offsets, as records or (`fields`) as arrays of fields.
DenseOffsets MakeDenseOffsets(const Geometry& g, int W, int H, int steps, bool fields) {
    DenseOffsets t;
    t.hx = g.halfX;
    t.hy = g.halfY;
    t.pitch = 2 * t.hx + 1 + DenseOffsets::kPadLo + DenseOffsets::kPadHi;
    const int rows = 2 * t.hy + 1 + DenseOffsets::kPadLo + DenseOffsets::kPadHi;
    const size_t n = size_t(t.pitch) * size_t(rows);
    const OffsetBounds none{kInfF, kInfF, 0.0f, 0.0f, 0};
    t.offsetPad = std::max(t.hx, t.hy) + DenseOffsets::kPadHi + kApexSide;
    for (int k = -t.offsetPad; k <= t.offsetPad; ++k) {
        t.uOf.push_back(float(k) / float(W));
        t.vOf.push_back(float(k) / float(H));
    }
    if (fields) {
        AssignOnHugePages(t.soa.distLo, n, none.distLo);
        AssignOnHugePages(t.soa.dist, n, none.dist);
        AssignOnHugePages(t.soa.invD, n, none.invD);
        AssignOnHugePages(t.soa.stepK, n, none.stepK);
        AssignOnHugePages(t.soa.mask, n, uint32_t(none.mask));
    } else {
        AssignOnHugePages(t.at, n, none);
    }
    tbb::parallel_for(
        tbb::blocked_range<int>(-t.hy, t.hy + 1), [&](const tbb::blocked_range<int>& r) {
            for (int dy = r.begin(); dy < r.end(); ++dy)
                for (int dx = -t.hx; dx <= t.hx; ++dx) {
                    if (dx == 0 && dy == 0) continue;
                    const size_t o = t.Index(dx, dy);
                    const OffsetBounds ob = MakeOffsetBounds(g, W, H, steps, dx, dy);
                    if (fields) {
                        t.soa.distLo[o] = ob.distLo;
                        t.soa.dist[o] = ob.dist;
                        t.soa.invD[o] = ob.invD;
                        t.soa.stepK[o] = ob.stepK;
                        t.soa.mask[o] = ob.mask;
                    } else {
                        t.at[o] = ob;
                    }
                }
        });
    return t;
}

/// A window of destinations (offsets ex..ex+size-1, ey..ey+size-1 from the tile origin)
/// with, per lane, bounds over the lane's offsets into it: the least distLo and dist, the
/// least invD (distLo = +inf when it has none).
struct LaneGroup {
    std::array<float, kLanes> distLo, dLo, invD;
    float minDistLo = kInfF;  ///< over the lanes
    int ex = 0, ey = 0;
    SectorBits mask = 0;  ///< over the lanes and offsets
    void Clear() {
        distLo.fill(kInfF);
        dLo.fill(kInfF);
        invD.fill(kInfF);
    }
    void Add(const LaneGroup& o) {
        for (int l = 0; l < kLanes; ++l) {
            distLo[size_t(l)] = std::min(distLo[size_t(l)], o.distLo[size_t(l)]);
            dLo[size_t(l)] = std::min(dLo[size_t(l)], o.dLo[size_t(l)]);
            invD[size_t(l)] = std::min(invD[size_t(l)], o.invD[size_t(l)]);
        }
        minDistLo = std::min(minDistLo, o.minDistLo);
        mask |= o.mask;
    }
};

/// The windows of the apex-tile search: quarters and tiles in grids (tile (tx, ty) holds
/// quarters (2 tx + a, 2 ty + b)), super-tiles sorted by distance, the tiles of each
/// sorted by distance (empty windows left out).
struct LaneWindows {
    int nqx = 0, nqy = 0, ntx = 0;
    std::vector<LaneGroup> quarters, tiles;
    struct Super {
        LaneGroup bounds;
        std::vector<int> tiles;  ///< indices into `tiles`
    };
    std::vector<Super> supers;
};

LaneWindows MakeLaneWindows(const DenseOffsets& d) {
    constexpr int kSuper = kSuperTile * kTile;
    LaneWindows lw;
    const int nsx = (2 * d.hx + kApexSide + kSuper - 1) / kSuper;
    const int nsy = (2 * d.hy + kApexSide + kSuper - 1) / kSuper;
    lw.ntx = nsx * kSuperTile;
    const int nty = nsy * kSuperTile;
    lw.nqx = 2 * lw.ntx;
    lw.nqy = 2 * nty;
    ResizeOnHugePages(lw.quarters, size_t(lw.nqx) * size_t(lw.nqy));
    tbb::parallel_for(
        tbb::blocked_range<int>(0, lw.nqy), [&](const tbb::blocked_range<int>& r) {
            for (int qy = r.begin(); qy < r.end(); ++qy)
                for (int qx = 0; qx < lw.nqx; ++qx) {
                    LaneGroup& q = lw.quarters[size_t(qy) * size_t(lw.nqx) + size_t(qx)];
                    q.Clear();
                    q.ex = -d.hx + 4 * qx;
                    q.ey = -d.hy + 4 * qy;
                    for (int l = 0; l < kLanes; ++l) {
                        const int lx = l % kApexSide, ly = l / kApexSide;
                        for (int a = 0; a < 4; ++a)
                            for (int b = 0; b < 4; ++b) {
                                const size_t o = d.Index(q.ex + b - lx, q.ey + a - ly);
                                if (!d.Valid(o)) continue;
                                const OffsetBounds ob = d.At(o);
                                q.distLo[size_t(l)] =
                                    std::min(q.distLo[size_t(l)], ob.distLo);
                                q.dLo[size_t(l)] = std::min(q.dLo[size_t(l)], ob.dist);
                                q.invD[size_t(l)] = std::min(q.invD[size_t(l)], ob.invD);
                                q.mask |= ob.mask;
                            }
                        q.minDistLo = std::min(q.minDistLo, q.distLo[size_t(l)]);
                    }
                }
        });
    lw.tiles.resize(size_t(lw.ntx) * size_t(nty));
    for (int ty = 0; ty < nty; ++ty)
        for (int tx = 0; tx < lw.ntx; ++tx) {
            LaneGroup& t = lw.tiles[size_t(ty) * size_t(lw.ntx) + size_t(tx)];
            t.Clear();
            t.ex = -d.hx + kTile * tx;
            t.ey = -d.hy + kTile * ty;
            for (int k = 0; k < 4; ++k)
                t.Add(lw.quarters[size_t(2 * ty + (k >> 1)) * size_t(lw.nqx) +
                                  size_t(2 * tx + (k & 1))]);
        }
    for (int sy = 0; sy < nsy; ++sy)
        for (int sx = 0; sx < nsx; ++sx) {
            LaneGroup s;
            s.Clear();
            s.ex = -d.hx + kSuper * sx;
            s.ey = -d.hy + kSuper * sy;
            std::vector<int> members;
            for (int ty = sy * kSuperTile; ty < (sy + 1) * kSuperTile; ++ty)
                for (int tx = sx * kSuperTile; tx < (sx + 1) * kSuperTile; ++tx) {
                    const int ti = ty * lw.ntx + tx;
                    if (!(lw.tiles[size_t(ti)].minDistLo < kInfF)) continue;
                    members.push_back(ti);
                    s.Add(lw.tiles[size_t(ti)]);
                }
            if (members.empty()) continue;
            std::stable_sort(members.begin(), members.end(), [&](int a, int b) {
                return lw.tiles[size_t(a)].minDistLo < lw.tiles[size_t(b)].minDistLo;
            });
            lw.supers.push_back({s, std::move(members)});
        }
    std::stable_sort(lw.supers.begin(), lw.supers.end(),
                     [](const LaneWindows::Super& a, const LaneWindows::Super& b) {
                         return a.bounds.minDistLo < b.bounds.minDistLo;
                     });
    return lw;
}

/// The running minima of one tile's lanes (one vector) and the destinations that set
/// them (offsets from the lane's texel; `found`: one bit per lane that has one).
struct TileBest {
    alignas(64) std::array<float, kLanes> best;
    std::array<int, kLanes> argDx{}, argDy{};
    LaneBits found = 0;
    TileBest() { best.fill(1.0f); }
    /// Lowers lane l's minimum to r, set by the destination at (dx, dy), if r is lower.
    void Lower(size_t l, float r, int dx, int dy) {
        if (best[l] > r) {
            best[l] = r;
            argDx[l] = dx;
            argDy[l] = dy;
            found |= LaneBits(1) << l;
        }
    }
};

#if RS_HAVE_CONE_SEARCH_AVX
RS_AVX512_WARNINGS_OFF
/// Lanes 0..7 and 8..15 of a float vector, as doubles; two 8-lane masks as one.
RS_TARGET_AVX512 inline __m512d lo(__m512 v) {
    return _mm512_maskz_cvtps_pd(0xFF, _mm512_castps512_ps256(v));
}
RS_TARGET_AVX512 inline __m512d hi(__m512 v) {
    return _mm512_maskz_cvtps_pd(0xFF, _mm512_castps512_ps256(_mm512_shuffle_f32x4(
                                           v, v, _MM_SHUFFLE(3, 2, 3, 2))));
}
/// Rows r = 0..3 of 4 adjacent values at p + r * pitch, as one vector (row-major).
RS_TARGET_AVX512 inline __m512 Rows4(const float* p, size_t pitch) {
    __m512 v = _mm512_castps128_ps512(_mm_loadu_ps(p));
    v = _mm512_insertf32x4(v, _mm_loadu_ps(p + pitch), 1);
    v = _mm512_insertf32x4(v, _mm_loadu_ps(p + 2 * pitch), 2);
    return _mm512_insertf32x4(v, _mm_loadu_ps(p + 3 * pitch), 3);
}
RS_TARGET_AVX512 inline __m512i Rows4(const uint32_t* p, size_t pitch) {
    const auto row = [&](size_t r) {
        return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + r * pitch));
    };
    __m512i v = _mm512_castsi128_si512(row(0));
    v = _mm512_inserti32x4(v, row(1), 1);
    v = _mm512_inserti32x4(v, row(2), 2);
    return _mm512_inserti32x4(v, row(3), 3);
}
inline __mmask16 join(__mmask8 l8, __mmask8 h8) {
    return __mmask16(unsigned(l8) | (unsigned(h8) << 8));
}
/// ExitBoundPrunes for 8 lanes, in its double arithmetic operation by operation (no
/// contraction: -ffp-contract=off), so the same lanes are pruned.
RS_TARGET_AVX512 inline __mmask8 ExitBoundPrunes8(const ExitField& f, __m512d dLo,
                                                  __m512d invD, __m512d b, __m512d L,
                                                  __m512d apex, __m512d best,
                                                  __m512d stepLo) {
    const __m512d zero = _mm512_setzero_pd();
    const __m512d a = _mm512_sub_pd(L, _mm512_set1_pd(2.0 * f.eps));
    // std::max(a, stepLo): stepLo where a < stepLo.
    const __m512d lam =
        _mm512_mask_blend_pd(_mm512_cmp_pd_mask(a, stepLo, _CMP_LT_OQ), a, stepLo);
    const __mmask8 moves = _mm512_cmp_pd_mask(lam, zero, _CMP_GT_OQ);
    const __m512d den = _mm512_add_pd(
        _mm512_sub_pd(_mm512_sub_pd(apex, b), _mm512_mul_pd(lam, _mm512_mul_pd(b, invD))),
        _mm512_set1_pd(f.eta));
    const __mmask8 below = _mm512_cmp_pd_mask(den, zero, _CMP_NGT_UQ);
    const __mmask8 far = _mm512_cmp_pd_mask(
        _mm512_mul_pd(_mm512_sub_pd(_mm512_add_pd(dLo, lam), _mm512_set1_pd(f.eps)),
                      _mm512_set1_pd(1.0 - 0x1p-20)),
        _mm512_mul_pd(best, den), _CMP_GE_OQ);
    return __mmask8(moves & (below | far));
}
/// The distance bound for 16 lanes (two halves of 8 in double): distLo >= best * (apex -
/// b) prunes, operation by operation as the scalar test.
RS_TARGET_AVX512 inline __mmask16 DistancePrunes16(__m512 distLo, __m512d bestL,
                                                   __m512d bestH, __m512d apexL,
                                                   __m512d apexH, __m512d bL,
                                                   __m512d bH) {
    return join(
        _mm512_cmp_pd_mask(lo(distLo), _mm512_mul_pd(bestL, _mm512_sub_pd(apexL, bL)),
                           _CMP_GE_OQ),
        _mm512_cmp_pd_mask(hi(distLo), _mm512_mul_pd(bestH, _mm512_sub_pd(apexH, bH)),
                           _CMP_GE_OQ));
}
RS_AVX512_WARNINGS_ON
#endif

/// Pairs waiting for their marches (RelaxedTileSearch::MarchBatchAvx512): the lane, the
/// offset, the destination's position as Consider computes it, its depth, and the
/// exit-field distance the march may skip (ListingRatio's `clear`).
struct MarchQueue {
    static constexpr int kGroups = 4;  ///< MarchLanes run side by side
    static constexpr int kSize = kGroups * kLanes;
    int n = 0;
    alignas(64) int32_t lane[kSize], dx[kSize], dy[kSize];
    alignas(64) float dstx[kSize], dsty[kSize], b[kSize];
    alignas(64) double clear[kSize];
    void Add(int l, int x, int y, float px, float py, float depth, double c) {
        lane[n] = l;
        dx[n] = x;
        dy[n] = y;
        dstx[n] = px;
        dsty[n] = py;
        b[n] = depth;
        clear[n] = c;
        ++n;
    }
};

#if RS_HAVE_CONE_SEARCH_AVX
RS_AVX512_WARNINGS_OFF
/// ListingRatio for up to 16 pairs at once, one vector lane each: its float and double
/// arithmetic lane by lane, operation by operation (no contraction: -ffp-contract=off),
/// so the same ratios. A sampled point whose texel coordinate is outside [-n, 2n) takes
/// WrapFloorIndex itself. Start sets the pairs up to the march's loop, Step takes one
/// sample of every live lane, Ratios gives the results once none is live.
struct MarchLanes {
    __mmask16 live = 0;
    __mmask16 prune = 0;  // lanes with a finite minimum (the early outs)
    __mmask16 exit = 0;   // lanes whose march ended: the ratio at the point reached
    int steps = 0;
    __m512 sx, sy, src, best, r, px, py, pz, stx, sty, stz;
    __m512d best2L, best2H;
    __m512i i;

    /// The pairs [first, first + n) of q; sxOf, syOf, apexOf, bestOf: per search lane.
    RS_TARGET_AVX512 RS_INLINE void Start(int nSteps, float inv, const MarchQueue& q,
                                          int first, int n,
                                          const std::array<float, kLanes>& sxOf,
                                          const std::array<float, kLanes>& syOf,
                                          const std::array<float, kLanes>& apexOf,
                                          const std::array<float, kLanes>& bestOf) {
        steps = nSteps;
        const __mmask16 all = __mmask16((1u << n) - 1u);
        live = all;
        exit = 0;
        const __m512 one = _mm512_set1_ps(1.0f), inf = _mm512_set1_ps(kInfF);
        r = one;
        if (!n) return;
        const __m512i lane = _mm512_maskz_loadu_epi32(all, q.lane + first);
        sx = _mm512_permutexvar_ps(lane, _mm512_loadu_ps(sxOf.data()));
        sy = _mm512_permutexvar_ps(lane, _mm512_loadu_ps(syOf.data()));
        src = _mm512_permutexvar_ps(lane, _mm512_loadu_ps(apexOf.data()));
        best = _mm512_permutexvar_ps(lane, _mm512_loadu_ps(bestOf.data()));
        const __m512 dstx = _mm512_maskz_loadu_ps(all, q.dstx + first),
                     dsty = _mm512_maskz_loadu_ps(all, q.dsty + first),
                     dstz = _mm512_maskz_loadu_ps(all, q.b + first);
        // NaN in the listing (b <= 0); ratio 1 when the destination is not above the
        // apex.
        const __mmask16 nan =
            _mm512_mask_cmp_ps_mask(live, dstz, _mm512_setzero_ps(), _CMP_NGT_UQ);
        r = _mm512_mask_mov_ps(r, nan, inf);
        live &= __mmask16(~nan);
        live &= _mm512_cmp_ps_mask(dstz, src, _CMP_LT_OQ);
        __m512 vx = _mm512_sub_ps(dstx, sx), vy = _mm512_sub_ps(dsty, sy), vz = dstz;
        prune = _mm512_cmp_ps_mask(best, inf, _CMP_LT_OQ);
        {
            const __m512 lb =
                _mm512_div_ps(_mm512_sqrt_ps(_mm512_add_ps(_mm512_mul_ps(vx, vx),
                                                           _mm512_mul_ps(vy, vy))),
                              _mm512_sub_ps(src, dstz));
            const __mmask16 out =
                _mm512_mask_cmp_ps_mask(__mmask16(live & prune), lb, best, _CMP_GE_OQ);
            r = _mm512_mask_mov_ps(r, out, best);
            live &= __mmask16(~out);
        }
        vx = _mm512_div_ps(vx, vz);
        vy = _mm512_div_ps(vy, vz);
        vz = _mm512_div_ps(vz, vz);
        const __m512 scale = _mm512_sub_ps(one, dstz);
        vx = _mm512_mul_ps(vx, scale);
        vy = _mm512_mul_ps(vy, scale);
        vz = _mm512_mul_ps(vz, scale);
        if (inv > 0.0f) {
            const __m512 k = _mm512_set1_ps(inv);
            stx = _mm512_mul_ps(vx, k);
            sty = _mm512_mul_ps(vy, k);
            stz = _mm512_mul_ps(vz, k);
        } else {
            const __m512 k = _mm512_set1_ps(float(steps));
            stx = _mm512_div_ps(vx, k);
            sty = _mm512_div_ps(vy, k);
            stz = _mm512_div_ps(vz, k);
        }
        px = _mm512_add_ps(dstx, stx);
        py = _mm512_add_ps(dsty, sty);
        pz = _mm512_add_ps(dstz, stz);
        live &= __mmask16(~_mm512_cmp_ps_mask(pz, src, _CMP_GE_OQ));  // r = 1
        i = _mm512_set1_epi32(1);
        // The samples proven inside the solid by the exit field (`clear`): only their
        // sums.
        __m512i k0 = _mm512_setzero_si512();
        __mmask16 skip = 0;
        for (int h = 0; h < 2; ++h) {
            const __mmask8 hl = __mmask8((live & prune) >> (8 * h));
            const __m512d clear = _mm512_loadu_pd(q.clear + first + 8 * h);
            const __m512d sxd = h ? hi(stx) : lo(stx), syd = h ? hi(sty) : lo(sty);
            const __m512d step2 =
                _mm512_add_pd(_mm512_mul_pd(sxd, sxd), _mm512_mul_pd(syd, syd));
            const __mmask8 m = __mmask8(
                _mm512_mask_cmp_pd_mask(hl, clear, _mm512_setzero_pd(), _CMP_GT_OQ) &
                _mm512_cmp_pd_mask(step2, _mm512_setzero_pd(), _CMP_GT_OQ));
            if (!m) continue;
            const __m512d k = _mm512_roundscale_pd(
                _mm512_div_pd(clear, _mm512_sqrt_pd(step2)), _MM_FROUND_TO_NEG_INF);
            // k < steps ? int(k) : steps - 1
            const __mmask8 small =
                _mm512_cmp_pd_mask(k, _mm512_set1_pd(double(steps)), _CMP_LT_OQ);
            __m256i kk = _mm256_mask_blend_epi32(
                small, _mm256_set1_epi32(steps - 1),
                _mm512_cvttpd_epi32(_mm512_mask_blend_pd(small, _mm512_setzero_pd(), k)));
            const __m512d clear2 = _mm512_mul_pd(clear, clear);
            for (;;) {
                const __m512d kd = _mm512_cvtepi32_pd(kk);
                const __mmask8 dec = __mmask8(
                    m & _mm256_cmp_epi32_mask(kk, _mm256_setzero_si256(), _MM_CMPINT_GT) &
                    _mm512_cmp_pd_mask(_mm512_mul_pd(_mm512_mul_pd(kd, kd), step2),
                                       clear2, _CMP_GE_OQ));
                if (!dec) break;
                kk = _mm256_mask_sub_epi32(kk, dec, kk, _mm256_set1_epi32(1));
            }
            kk = _mm256_maskz_mov_epi32(m, kk);
            k0 = h ? _mm512_inserti64x4(k0, kk, 1) : _mm512_inserti64x4(k0, kk, 0);
            skip |= __mmask16(unsigned(m) << (8 * h));
        }
        if (skip) {
            for (int it = 1;; ++it) {
                const __mmask16 add = _mm512_mask_cmp_epi32_mask(
                    skip, _mm512_set1_epi32(it), k0, _MM_CMPINT_LE);
                if (!add) break;
                px = _mm512_mask_add_ps(px, add, px, stx);
                py = _mm512_mask_add_ps(py, add, py, sty);
                pz = _mm512_mask_add_ps(pz, add, pz, stz);
            }
            i = _mm512_mask_add_epi32(i, skip, k0, _mm512_set1_epi32(1));
            live &= __mmask16(~_mm512_mask_cmp_ps_mask(skip, pz, src, _CMP_GE_OQ));
        }
        const __m512d c = _mm512_set1_pd(1.0 + 0x1p-20);
        best2L = _mm512_mul_pd(_mm512_mul_pd(lo(best), lo(best)), c);
        best2H = _mm512_mul_pd(_mm512_mul_pd(hi(best), hi(best)), c);
        // Lanes out of steps take the ratio at their last point.
        const __mmask16 spent =
            _mm512_mask_cmp_epi32_mask(live, i, _mm512_set1_epi32(steps), _MM_CMPINT_GE);
        exit |= spent;
        live &= __mmask16(~spent);
    }

    /// NearestWrap's wrapped texel index of the coordinates p * n of the live lanes;
    /// `odd`: the lanes outside [-n, 2n), left to the caller.
    RS_TARGET_AVX512 RS_INLINE __m512i Index(__m512 p, int n, __mmask16& odd) const {
        const __m512 f = _mm512_roundscale_ps(_mm512_mul_ps(p, _mm512_set1_ps(float(n))),
                                              _MM_FROUND_TO_NEG_INF);
        const __m512i k = _mm512_cvttps_epi32(f);
        const __m512i nv = _mm512_set1_epi32(n);
        // [-n, 2n) in floats first: the conversion is exact there.
        odd |= __mmask16(
            _mm512_mask_cmp_ps_mask(live, f, _mm512_set1_ps(-float(n)), _CMP_NGE_UQ) |
            _mm512_mask_cmp_ps_mask(live, f, _mm512_set1_ps(2.0f * float(n)),
                                    _CMP_NLT_UQ));
        __m512i w = _mm512_mask_add_epi32(
            k, _mm512_cmp_epi32_mask(k, _mm512_setzero_si512(), _MM_CMPINT_LT), k, nv);
        w = _mm512_mask_sub_epi32(w, _mm512_cmp_epi32_mask(w, nv, _MM_CMPINT_NLT), w, nv);
        return w;
    }

    /// One sample of every live lane (the listing's loop body).
    RS_TARGET_AVX512 RS_INLINE void Step(const DepthField& hf) {
        const int W = hf.width, H = hf.height;
        __mmask16 odd = 0;
        __m512i ix = Index(px, W, odd), iy = Index(py, H, odd);
        if (odd) {
            alignas(64) int32_t xs[kLanes], ys[kLanes];
            alignas(64) float us[kLanes], vs[kLanes];
            _mm512_store_si512(xs, ix);
            _mm512_store_si512(ys, iy);
            _mm512_store_ps(us, px);
            _mm512_store_ps(vs, py);
            for (unsigned m = odd; m; m &= m - 1) {
                const int l = std::countr_zero(m);
                xs[l] = WrapFloorIndex(us[l] * float(W), W);
                ys[l] = WrapFloorIndex(vs[l] * float(H), H);
            }
            ix = _mm512_load_si512(xs);
            iy = _mm512_load_si512(ys);
        }
        const __m512 depth = _mm512_mask_i32gather_ps(
            _mm512_setzero_ps(), live,
            _mm512_add_epi32(_mm512_mullo_epi32(iy, _mm512_set1_epi32(W)), ix),
            hf.depth.data(), 4);
        const __mmask16 adv = _mm512_mask_cmp_ps_mask(live, depth, pz, _CMP_LE_OQ);
        exit |= __mmask16(live & ~adv);  // sampled above the ray: the listing stops
        live = adv;
        if (!live) return;
        px = _mm512_mask_add_ps(px, live, px, stx);
        py = _mm512_mask_add_ps(py, live, py, sty);
        pz = _mm512_mask_add_ps(pz, live, pz, stz);
        const __mmask16 above = _mm512_mask_cmp_ps_mask(live, pz, src, _CMP_GE_OQ);
        r = _mm512_mask_mov_ps(r, above, _mm512_set1_ps(1.0f));
        live &= __mmask16(~above);
        // The early out at the current point, in double (ListingRatio).
        const __m512 cxf = _mm512_sub_ps(px, sx), cyf = _mm512_sub_ps(py, sy),
                     denf = _mm512_sub_ps(src, pz);
        __mmask8 outs[2];
        for (int h = 0; h < 2; ++h) {
            const __m512d cx = h ? hi(cxf) : lo(cxf), cy = h ? hi(cyf) : lo(cyf),
                          den = h ? hi(denf) : lo(denf);
            outs[h] = _mm512_mask_cmp_pd_mask(
                __mmask8((live & prune) >> (8 * h)),
                _mm512_add_pd(_mm512_mul_pd(cx, cx), _mm512_mul_pd(cy, cy)),
                _mm512_mul_pd(_mm512_mul_pd(h ? best2H : best2L, den), den), _CMP_GE_OQ);
        }
        const __mmask16 out = join(outs[0], outs[1]);
        r = _mm512_mask_mov_ps(r, out, best);
        live &= __mmask16(~out);
        i = _mm512_mask_add_epi32(i, live, i, _mm512_set1_epi32(1));
        const __mmask16 spent =
            _mm512_mask_cmp_epi32_mask(live, i, _mm512_set1_epi32(steps), _MM_CMPINT_GE);
        exit |= spent;
        live &= __mmask16(~spent);
    }

    /// The ratios, once no lane is live.
    RS_TARGET_AVX512 RS_INLINE void Ratios(float* out) {
        if (exit) {
            const __m512 ex = _mm512_sub_ps(px, sx), ey = _mm512_sub_ps(py, sy);
            r = _mm512_mask_div_ps(r, exit,
                                   _mm512_sqrt_ps(_mm512_add_ps(_mm512_mul_ps(ex, ex),
                                                                _mm512_mul_ps(ey, ey))),
                                   _mm512_sub_ps(src, pz));
        }
        _mm512_store_ps(out, r);
    }
};
RS_AVX512_WARNINGS_ON
#endif

struct RelaxedTileSearch {
    const DepthField& hf;
    const DenseOffsets& d;
    const LaneWindows& lw;
    const DepthWindows& dw;
    const ExitField& ef;
    int steps;
    float inv;
    float dmin;
    // The tile searched.
    int I = 0, J = 0;
    LaneBits active = 0;
    std::array<float, kLanes> apex{}, sx{}, sy{};
    std::array<double, kLanes> dApex{}, reach{};
    std::array<size_t, kLanes> laneDelta{};
    bool avx512 = false;  ///< quarters by SearchQuarterAvx512 (DenseOffsets as fields)
    MarchQueue marches;   ///< pairs SearchQuarterAvx512 kept (MarchBatchAvx512)
    /// AheadPrunes' travel a clear window of each level proves, and (AheadPrunesAvx512)
    /// the one the levels before it prove (-inf for the first).
    alignas(64) std::array<double, 8> provenAt{}, provenBefore{};
    TileBest tb;

    RelaxedTileSearch(const DepthField& hf, const DenseOffsets& d, const LaneWindows& lw,
                      const DepthWindows& dw, const ExitField& ef, int steps, float inv,
                      float dmin)
        : hf(hf), d(d), lw(lw), dw(dw), ef(ef), steps(steps), inv(inv), dmin(dmin) {
        for (int l = 0; l < kLanes; ++l)
            laneDelta[size_t(l)] =
                size_t(l / kApexSide) * size_t(d.pitch) + size_t(l % kApexSide);
        // Eight values: cheaper made here than shared.
        const double texel = std::min(1.0 / double(hf.width), 1.0 / double(hf.height));
        for (size_t level = 0; level < provenAt.size(); ++level) {
            provenAt[level] = (double(2 << level) - 0.5) * texel - 4.0 * ef.eps;
            provenBefore[level] = level == 0 ? -double(kInfF) : provenAt[level - 1];
        }
    }

    float OffsetU(int dx) const { return d.OffsetU(dx); }
    float OffsetV(int dy) const { return d.OffsetV(dy); }

    /// The listing's ratio of lane l's pair at offset (dx, dy); lowers its minimum.
    RS_INLINE void Consider(int l, int dx, int dy, float b, double clear = 0) {
        const size_t u = size_t(l);
        const float fdx = OffsetU(dx), fdy = OffsetV(dy);
        const float r = ListingRatio(hf, sx[u], sy[u], sx[u] + fdx, sy[u] + fdy, b, steps,
                                     inv, apex[u], tb.best[u], clear);
        tb.Lower(u, r, dx, dy);
    }

    /// The largest best * (apex - dmin) over the active lanes: a window whose distLo is
    /// at least this cannot hold a pair that lowers any lane's minimum.
    double Reach() const {
        double r = 0;
        for (LaneBits m = active; m; m &= m - 1) {
            const int l = std::countr_zero(m);
            r = std::max(r, double(tb.best[size_t(l)]) * reach[size_t(l)]);
        }
        return r;
    }

    /// The exit bound's inputs for window q (GroupLanes): its least exit-field value over
    /// the group's sectors (lam) and its one step's factor for its deepest depth (k);
    /// `ignored` where every destination gives NaN. Zero without the exit field.
    struct WindowExit {
        bool ignored = false;
        double lam = 0, k = 0;
    };
    WindowExit ExitOfWindow(const LaneGroup& q, size_t w, float wmax,
                            const std::vector<uint8_t>& lwin) const {
        WindowExit we;
        if (!ef.usable) return we;
        if (!(wmax > 0.0f)) {
            we.ignored = true;
            return we;
        }
        we.lam = double(MinOverSectors(ef, lwin, w, q.mask));
        const double bmax = double(wmax);
        we.k = (1.0 - bmax) / (bmax * double(steps)) * (1.0 - 0x1p-20) * (1.0 - 0x1p-30);
        return we;
    }

    /// The lanes of `lanes` for which window q may hold a pair that lowers the lane's
    /// minimum. A lane is pruned when no destination lies above its apex in the window
    /// (least depth wmin at window index w), by the distance bound, or by the exit bound
    /// (lwin: the exit field's minima over windows of q's size; wmax: the window's
    /// greatest depth, which bounds the length of one march step: one step is at least
    /// |v| (1 - b) / (b steps) long, and (1 - b) / b only shrinks as b grows). The
    /// factor (1 - 2^-30) covers the double roundings of the step bound.
    LaneBits GroupLanes(const LaneGroup& q, LaneBits lanes, size_t w, float wmin,
                        float wmax, const std::vector<uint8_t>& lwin) const {
#if RS_HAVE_CONE_SEARCH_AVX
        if (avx512) return GroupLanesAvx512(q, lanes, w, wmin, wmax, lwin);
#endif
        LaneBits keep = 0;
        const double dmin = double(wmin);
        const bool exit = ef.usable;
        const WindowExit we = ExitOfWindow(q, w, wmax, lwin);
        if (we.ignored) return 0;
        const double lam = we.lam, k = we.k;
        for (LaneBits m = lanes; m; m &= m - 1) {
            const int l = std::countr_zero(m);
            const size_t u = size_t(l);
            if (!(wmin < apex[u])) continue;
            const double best = double(tb.best[u]);
            if (double(q.distLo[u]) >= best * (dApex[u] - dmin)) continue;
            if (exit) {
                const double dLo = double(q.dLo[u]);
                if (ExitBoundPrunes(ef, dLo, double(q.invD[u]), dmin, lam, dApex[u], best,
                                    (dLo - 0x1p-22) * k))
                    continue;
            }
            keep |= LaneBits(1) << l;
        }
        return keep;
    }

    /// How often AheadPrunes pruned lately: where it rarely does (steep, rough content,
    /// e.g. around the hemisphere of `shapes`) it costs more than the marches it saves,
    /// so it is then tried on one pair in 16 only, until it pays again. Pruning fewer
    /// pairs never changes a minimum, so the maps do not depend on it.
    struct AheadRate {
        uint32_t tried = 0, pruned = 0, skip = 0;
        void Count(bool p) {
            ++tried;
            pruned += p ? 1u : 0u;
            if (tried == 256) {  // a new window of 256 tries
                tried /= 2;
                pruned /= 2;
            }
        }
        bool Paying() const { return pruned * 4 >= tried; }
    } ahead;
    bool aheadEveryPair = false;  ///< tests: AheadPrunes on every pair, paying or not
    bool TryAhead() {
        if (aheadEveryPair || ahead.Paying()) return true;
        return (++ahead.skip & 15u) == 0;
    }

    /// The exit bound carried further by the depth maxima ahead of the destination (x, y)
    /// of a pair at offset (dx, dy) whose march travels at least `lam` (uv) before it can
    /// stop (docs/cone_maps.md, section "Windows ahead"): the march only moves away from
    /// the source, so it samples the k x k window of cells that starts at the destination
    /// and extends along the offset's signs until it has travelled (k - 1/2) texels; a
    /// window whose deepest cell is not deeper than the march's z after `lam` cannot stop
    /// it, so the march travels at least that far. Windows of 2 to 128 texels in turn,
    /// each tested with the travel the smaller one proved.
    RS_INLINE bool AheadPrunes(int dx, int dy, int x, int y, double b,
                               const OffsetBounds& ob, double lam, double apexD,
                               double best) const {
        if (!(lam > 0)) return false;
        const int W = hf.width;
        const double m = b * double(ob.invD);
        // The travel the exit bound needs to prune the pair, in real numbers: it only
        // picks the first window worth the bound (and skips pairs no window can prune);
        // the bound itself is evaluated as always.
        const double c = 1.0 - 0x1p-20;
        const double need =
            (best * (apexD - b + ef.eta) - (double(ob.dist) - ef.eps) * c) /
            (c + best * m) * (1.0 - 0x1p-30);
        // The travel a clear window of (2 << level) texels proves.
        const auto proven = [&](size_t level) { return provenAt[level]; };
        const size_t levels = AheadCodes::kLevels;
        size_t first = 0;
        while (first < levels && proven(first) < need) ++first;
        if (first == levels) return false;
        const AheadCodes& ahead = dw.Ahead(dx, dy, size_t(y) * size_t(W) + size_t(x));
        const auto deepestAhead = [&](size_t level) {
            return AheadDepth(ahead.code[level]);
        };
        // That window first, against the largest z the windows before it can prove: one
        // load rejects most pairs.
        if (first > 0) {
            const double lamBefore = std::max(lam, proven(first - 1));
            if (!(deepestAhead(first) <= b + lamBefore * m - ef.eta - 0x1p-40))
                return false;
        }
        for (size_t level = 0; level < levels; ++level) {
            if (!(deepestAhead(level) <= b + lam * m - ef.eta - 0x1p-40)) return false;
            lam = std::max(lam, proven(level));
            if (level >= first && ExitBoundPrunes(ef, double(ob.dist), double(ob.invD), b,
                                                  lam + 2.0 * ef.eps, apexD, best))
                return true;
        }
        return false;
    }

    /// GroupLanes for window g of the tile, with the depth minima, maxima and exit minima
    /// over windows of its size; (wx, wy) is its origin in the map (wrapped).
    LaneBits WindowLanes(const LaneGroup& g, LaneBits lanes,
                         const std::vector<float>& mins, const std::vector<float>& maxs,
                         const std::vector<uint8_t>& lwin, int& wx, int& wy) const {
        const int W = hf.width, H = hf.height;
        wx = WrapFast(I + g.ex, W);
        wy = WrapFast(J + g.ey, H);
        const size_t w = size_t(wy) * size_t(W) + size_t(wx);
        return GroupLanes(g, lanes, w, mins[w], maxs[w], lwin);
    }

    /// Every destination of quarter q (window origin wx, wy) for the lanes of `lanes`:
    /// the same bounds per pair, then the listing. The listing samples exactly the
    /// destination texel (its float texel coordinate is within W * 2^-22 < 1/2 of the
    /// centre), so the bounds with its depth b hold for the pair. One march step is
    /// |v| (1 - b) / (b steps) long (float roundings of v, the scale and the step within
    /// the factors: OffsetBounds::stepK, and (1 - b) / b rounded down per texel). A pair
    /// kept is marched with `clear` = its exit-field value (ListingRatio; 1 - 2^-40: the
    /// double roundings of its comparison of squares).
    void SearchQuarter(const LaneGroup& q, LaneBits lanes, int wx, int wy) {
        const int W = hf.width, H = hf.height;
        float maxApex = 0;
        for (LaneBits m = lanes; m; m &= m - 1)
            maxApex = std::max(maxApex, apex[size_t(std::countr_zero(m))]);
        for (int a = 0; a < 4; ++a) {
            const int rowIndex = WrapFast(wy + a, H);
            const size_t row = size_t(rowIndex) * size_t(W);
            for (int c = 0; c < 4; ++c) {
                const int col = WrapFast(wx + c, W);
                const size_t dst = row + size_t(col);
                const float b = hf.depth[dst];
                // The listing gives NaN (ignored) for b <= 0, and 1 for b >= the apex.
                if (!(b > 0.0f) || !(b < maxApex)) continue;
                const double db = double(b);
                const int ex = q.ex + c, ey = q.ey + a;
                const size_t oe = d.Index(ex, ey);
                const double shallow = double(dw.shallow[dst]);
                for (LaneBits m = lanes; m; m &= m - 1) {
                    const int l = std::countr_zero(m);
                    const size_t u = size_t(l);
                    const size_t o = oe - laneDelta[u];
                    if (!(b < apex[u])) continue;
                    const double best = double(tb.best[u]);
                    const OffsetBounds& ob = d.at[o];
                    if (double(ob.distLo) >= best * (dApex[u] - db)) continue;
                    double lp = 0, stepLo = 0;
                    if (ef.usable) {
                        lp = double(MinOverSectors(ef, ef.L, dst, ob.mask));
                        stepLo = double(ob.stepK) * shallow;
                        if (ExitBoundPrunes(ef, double(ob.dist), double(ob.invD), db, lp,
                                            dApex[u], best, stepLo))
                            continue;
                    }
                    MarchPair(l, ex, ey, col, rowIndex, b, ob, lp, stepLo);
                }
            }
        }
    }

    /// A pair of lane l (destination offset (ex, ey) from the tile's origin, at map
    /// texel (col, row), depth b) that passed the distance and exit bounds (lp: its exit
    /// field over the offset's sectors, stepLo: its one-step bound; both unused without
    /// the exit field): the windows ahead, then the listing.
    RS_INLINE void MarchPair(int l, int ex, int ey, int col, int row, float b,
                             const OffsetBounds& ob, double lp, double stepLo,
                             bool batch = false) {
        const int dxo = ex - l % kApexSide, dyo = ey - l / kApexSide;
        double clear = 0;
        if (ef.usable) {
            if (TryAhead()) {
                const size_t u = size_t(l);
                const double lam = std::max(lp - 2.0 * ef.eps, stepLo);
                const double best = double(tb.best[u]);
#if RS_HAVE_CONE_SEARCH_AVX
                const bool pruned = batch
                                        ? AheadPrunesAvx512(dxo, dyo, col, row, double(b),
                                                            ob, lam, dApex[u], best)
                                        : AheadPrunes(dxo, dyo, col, row, double(b), ob,
                                                      lam, dApex[u], best);
#else
                const bool pruned =
                    AheadPrunes(dxo, dyo, col, row, double(b), ob, lam, dApex[u], best);
#endif
                ahead.Count(pruned);
                if (pruned) return;
            }
            clear = lp * (1.0 - 0x1p-40);
        }
#if RS_HAVE_CONE_SEARCH_AVX
        if (batch) {
            const size_t u = size_t(l);
            marches.Add(l, dxo, dyo, sx[u] + OffsetU(dxo), sy[u] + OffsetV(dyo), b,
                        clear);
            if (marches.n == MarchQueue::kSize) MarchBatchAvx512();
            return;
        }
#endif
        static_cast<void>(batch);
        Consider(l, dxo, dyo, b, clear);
    }

#if RS_HAVE_CONE_SEARCH_AVX
    RS_AVX512_WARNINGS_OFF
    /// AheadPrunes with AVX-512: the pair's seven windows at once (one load of their
    /// codes), in its double arithmetic operation by operation. A level prunes where its
    /// window and every smaller one are clear and the exit bound with the travel they
    /// prove prunes the pair, as in AheadPrunes; every level is tried (AheadPrunes starts
    /// at the first worth the bound: the levels before it rarely prune, and pruning more
    /// pairs, each by a valid bound, never changes a minimum).
    RS_TARGET_AVX512 bool AheadPrunesAvx512(int dx, int dy, int x, int y, double b,
                                            const OffsetBounds& ob, double lam,
                                            double apexD, double best) const {
        if (!(lam > 0)) return false;
        const AheadCodes& a = dw.Ahead(dx, dy, size_t(y) * size_t(hf.width) + size_t(x));
        // AheadDepth: Unorm8ToFloat's float product, then widened.
        const __m512d deepest = _mm512_cvtps_pd(
            _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(
                              _mm_loadl_epi64(reinterpret_cast<const __m128i*>(&a)))),
                          _mm256_set1_ps(float(1.0 / 255.0))));
        const __m512d bV = _mm512_set1_pd(b), lamV = _mm512_set1_pd(lam);
        const __m512d m = _mm512_set1_pd(b * double(ob.invD));
        // Clear: deepest <= b + lam * m - eta - 2^-40, lam the travel the levels before
        // prove (std::max(lam, proven): the same value as max_pd here, no NaN).
        const __m512d lamBefore =
            _mm512_max_pd(lamV, _mm512_load_pd(provenBefore.data()));
        const __m512d z =
            _mm512_sub_pd(_mm512_sub_pd(_mm512_add_pd(bV, _mm512_mul_pd(lamBefore, m)),
                                        _mm512_set1_pd(ef.eta)),
                          _mm512_set1_pd(0x1p-40));
        const unsigned clear = _mm512_cmp_pd_mask(deepest, z, _CMP_LE_OQ) & 0x7Fu;
        const unsigned upTo = (1u << std::countr_one(clear)) - 1u;
        if (!upTo) return false;
        const __m512d lamAt = _mm512_max_pd(lamV, _mm512_load_pd(provenAt.data()));
        const __mmask8 prunes = ExitBoundPrunes8(
            ef, _mm512_set1_pd(double(ob.dist)), _mm512_set1_pd(double(ob.invD)), bV,
            _mm512_add_pd(lamAt, _mm512_set1_pd(2.0 * ef.eps)), _mm512_set1_pd(apexD),
            _mm512_set1_pd(best), _mm512_setzero_pd());
        return (prunes & upTo) != 0;
    }

    /// GroupLanes with AVX-512, all lanes at once in its double arithmetic operation by
    /// operation (the same lanes are kept).
    RS_TARGET_AVX512 LaneBits GroupLanesAvx512(const LaneGroup& q, LaneBits lanes,
                                               size_t w, float wmin, float wmax,
                                               const std::vector<uint8_t>& lwin) const {
        const bool exit = ef.usable;
        const WindowExit we = ExitOfWindow(q, w, wmax, lwin);
        if (we.ignored) return 0;
        __mmask16 keep =
            _mm512_mask_cmp_ps_mask(__mmask16(lanes), _mm512_set1_ps(wmin),
                                    _mm512_loadu_ps(apex.data()), _CMP_LT_OQ);
        if (!keep) return 0;
        const __m512 best = _mm512_load_ps(tb.best.data());
        const __m512d bestL = lo(best), bestH = hi(best);
        const __m512d apexL = _mm512_loadu_pd(dApex.data()),
                      apexH = _mm512_loadu_pd(dApex.data() + 8);
        const __m512d dmin = _mm512_set1_pd(double(wmin));
        keep &= __mmask16(~DistancePrunes16(_mm512_loadu_ps(q.distLo.data()), bestL,
                                            bestH, apexL, apexH, dmin, dmin));
        if (!keep || !exit) return keep;
        const __m512 dLo = _mm512_loadu_ps(q.dLo.data()),
                     invD = _mm512_loadu_ps(q.invD.data());
        const __m512d L = _mm512_set1_pd(we.lam), kk = _mm512_set1_pd(we.k),
                      slack = _mm512_set1_pd(0x1p-22);
        const __m512d dLoL = lo(dLo), dLoH = hi(dLo);
        keep &= __mmask16(
            ~join(ExitBoundPrunes8(ef, dLoL, lo(invD), dmin, L, apexL, bestL,
                                   _mm512_mul_pd(_mm512_sub_pd(dLoL, slack), kk)),
                  ExitBoundPrunes8(ef, dLoH, hi(invD), dmin, L, apexH, bestH,
                                   _mm512_mul_pd(_mm512_sub_pd(dLoH, slack), kk))));
        return keep;
    }

    /// SearchQuarter with AVX-512 (DenseOffsets as arrays of fields): lane by lane, the
    /// distance and exit bounds of the lane's 16 pairs into the quarter at once, one
    /// vector lane per destination, in the scalar tests' double arithmetic operation by
    /// operation (no contraction: -ffp-contract=off). The pairs kept go on to MarchPair,
    /// destinations in order, and are marched in batches (MarchBatchAvx512) when the
    /// queue is full and at the end of the tile (SearchTile): fuller batches of marches
    /// (2-3% less time on rocks and noise at 1024² than a batch per quarter). So a
    /// lane's pairs are tested against its minimum as the last batch left it, never
    /// below the scalar search's at the same pair: more pairs may be kept, and the
    /// minimum is the same.
    RS_TARGET_AVX512 void SearchQuarterAvx512(const LaneGroup& q, LaneBits lanes, int wx,
                                              int wy) {
        const int W = hf.width, H = hf.height;
        int colOf[4], rowOf[4];
        for (int k = 0; k < 4; ++k) {
            colOf[k] = WrapFast(wx + k, W);
            rowOf[k] = WrapFast(wy + k, H);
        }
        alignas(64) float depthOf[16], shallowOf[16];
        size_t dstOf[16];
        for (int i = 0; i < 16; ++i) {
            dstOf[i] = size_t(rowOf[i >> 2]) * size_t(W) + size_t(colOf[i & 3]);
            depthOf[i] = hf.depth[dstOf[i]];
            shallowOf[i] = dw.shallow[dstOf[i]];
        }
        const __m512 b = _mm512_load_ps(depthOf);
        // The listing gives NaN (ignored) for b <= 0, and 1 for b >= the apex.
        const __mmask16 positive = _mm512_cmp_ps_mask(b, _mm512_setzero_ps(), _CMP_GT_OQ);
        if (!positive) return;
        // The exit field of the destinations in the quarter's sectors, decoded:
        // exitOf[k][i] (the decoded codes keep their order, so their minimum is the
        // decoded minimum code, as MinOverSectors takes it).
        const unsigned sectors = ef.usable ? unsigned(q.mask) : 0u;
        alignas(64) float exitOf[kSectors][16];
        for (unsigned m = sectors; m; m &= m - 1) {
            const int k = std::countr_zero(m);
            for (int i = 0; i < 16; ++i)
                exitOf[k][i] = ef.decode[ef.L[dstOf[i] * kSectors + size_t(k)]];
        }
        const __m512d bL = lo(b), bH = hi(b);
        const __m512 shallow = _mm512_load_ps(shallowOf);
        const __m512d shL = lo(shallow), shH = hi(shallow);
        const size_t pitch = size_t(d.pitch);
        const size_t base = d.Index(q.ex, q.ey);
        for (LaneBits m = lanes; m; m &= m - 1) {
            const int l = std::countr_zero(m);
            const size_t u = size_t(l);
            __mmask16 keep =
                positive & _mm512_cmp_ps_mask(b, _mm512_set1_ps(apex[u]), _CMP_LT_OQ);
            if (!keep) continue;
            const size_t o0 = base - laneDelta[u];  // the lane's offset to destination 0
            const __m512d best = _mm512_set1_pd(double(tb.best[u]));
            const __m512d apexD = _mm512_set1_pd(dApex[u]);
            // The distance bound: distLo >= best * (apex - b) prunes.
            keep &= __mmask16(~DistancePrunes16(Rows4(&d.soa.distLo[o0], pitch), best,
                                                best, apexD, apexD, bL, bH));
            if (!keep) continue;
            alignas(64) float lpOf[16];
            if (ef.usable) {
                // MinOverSectors of each pair's offset mask, then ExitBoundPrunes.
                const __m512i masks = Rows4(&d.soa.mask[o0], pitch);
                __m512 lp = _mm512_set1_ps(kInfF);
                for (unsigned sm = sectors; sm; sm &= sm - 1) {
                    const int k = std::countr_zero(sm);
                    const __mmask16 has = _mm512_mask_test_epi32_mask(
                        keep, masks, _mm512_set1_epi32(1 << k));
                    lp = _mm512_mask_min_ps(lp, has, lp, _mm512_load_ps(exitOf[k]));
                }
                _mm512_store_ps(lpOf, lp);
                const __m512 stepK = Rows4(&d.soa.stepK[o0], pitch),
                             invD = Rows4(&d.soa.invD[o0], pitch),
                             dist = Rows4(&d.soa.dist[o0], pitch);
                keep &= __mmask16(
                    ~join(ExitBoundPrunes8(ef, lo(dist), lo(invD), bL, lo(lp), apexD,
                                           best, _mm512_mul_pd(lo(stepK), shL)),
                          ExitBoundPrunes8(ef, hi(dist), hi(invD), bH, hi(lp), apexD,
                                           best, _mm512_mul_pd(hi(stepK), shH))));
            }
            for (unsigned k = keep; k; k &= k - 1) {
                const int i = std::countr_zero(k);
                const OffsetBounds ob = d.At(o0 + size_t(i >> 2) * pitch + size_t(i & 3));
                MarchPair(l, q.ex + (i & 3), q.ey + (i >> 2), colOf[i & 3], rowOf[i >> 2],
                          depthOf[i], ob, ef.usable ? double(lpOf[i]) : 0.0,
                          double(ob.stepK) * double(shallowOf[i]), true);
            }
        }
    }

    /// Consider for the pairs of `marches`, with AVX-512 (MarchLanes), in groups of up to
    /// 16 whose marches run side by side: independent chains of latency (each sample
    /// waits for its gather). Four groups took 1-3% less time than two on rocks 8-bit
    /// at 1024² and `builtin:shapes:512`; refilling a group's finished lanes from the
    /// queue as they end took more (the start of a march costs more than idle lanes).
    /// Every pair is marched against its lane's minimum as it was before the batch (at
    /// least the scalar search's then: an early out returns that minimum, which lowers
    /// nothing); the minima are lowered in the batch's order.
    RS_TARGET_AVX512 void MarchBatchAvx512() {
        const int n = marches.n;
        marches.n = 0;
        constexpr int G = MarchQueue::kGroups;
        MarchLanes group[G];
        for (int g = 0; g < G; ++g) {
            const int f = std::min(n, g * kLanes);
            group[g].Start(steps, inv, marches, f, std::min(n - f, kLanes), sx, sy, apex,
                           tb.best);
        }
        for (;;) {
            bool any = false;
            for (int g = 0; g < G; ++g)
                if (group[g].live) {
                    group[g].Step(hf);
                    any = true;
                }
            if (!any) break;
        }
        alignas(64) float rs[G * kLanes];
        for (int g = 0; g < G; ++g) group[g].Ratios(rs + g * kLanes);
        for (int k = 0; k < n; ++k)
            tb.Lower(size_t(marches.lane[k]), rs[k], marches.dx[k], marches.dy[k]);
    }
    RS_AVX512_WARNINGS_ON
#endif

    /// The minima of the tile at (ti, tj) (texels ti..ti+3, tj..tj+3 inside the map) for
    /// apexes apexOf(lane), seeded with the minimisers of the tile to its left (`prev`,
    /// its lanes' offsets; used where found).
    template <class ApexOf>
    const TileBest& SearchTile(int ti, int tj, ApexOf apexOf, const TileBest* prev) {
        const int W = hf.width, H = hf.height;
        I = ti;
        J = tj;
        active = 0;
        tb = TileBest{};
        for (int l = 0; l < kLanes; ++l) {
            const size_t u = size_t(l);
            const int i = I + l % kApexSide, j = J + l / kApexSide;
            if (i >= W || j >= H) continue;
            apex[u] = apexOf(i, j);
            dApex[u] = double(apex[u]);
            reach[u] = dApex[u] - double(dmin);
            sx[u] = (float(i) + 0.5f) / float(W);
            sy[u] = (float(j) + 0.5f) / float(H);
            if (apex[u] > dmin) active |= LaneBits(1) << l;
        }
        if (!active) return tb;
        // Seeds: the destinations that set the minima of the left tile's lanes in the
        // same row, as offsets from this lane (any pair of the definition is an upper
        // bound).
        if (prev)
            for (LaneBits m = active; m; m &= m - 1) {
                const int l = std::countr_zero(m);
                const int lx = l % kApexSide, ly = l / kApexSide;
                for (int px = kApexSide - 1; px >= 0; --px) {
                    const size_t p = size_t(ly * kApexSide + px);
                    if (!(prev->found >> p & 1u)) continue;
                    const int dx = prev->argDx[p] - (kApexSide + lx - px),
                              dy = prev->argDy[p];
                    if ((dx == 0 && dy == 0) || dx < -d.hx || dx > d.hx) continue;
                    Consider(l, dx, dy,
                             hf.At(Wrap(I + lx + dx, W), Wrap(J + ly + dy, H)));
                }
            }
        for (const LaneWindows::Super& super : lw.supers) {
            const LaneGroup& sg = super.bounds;
            if (double(sg.minDistLo) >= Reach()) break;  // sorted by distance
            int sx0 = 0, sy0 = 0;
            const LaneBits ls =
                WindowLanes(sg, active, dw.min32, dw.max32, ef.Lwin32, sx0, sy0);
            if (!ls) continue;
            for (int tileIndex : super.tiles) {
                const LaneGroup& tg = lw.tiles[size_t(tileIndex)];
                if (double(tg.minDistLo) >= Reach()) break;  // sorted by distance
                int wx = 0, wy = 0;
                const LaneBits lt =
                    WindowLanes(tg, ls, dw.min8, dw.max8, ef.Lwin, wx, wy);
                if (!lt) continue;
                const int tx = tileIndex % lw.ntx, ty = tileIndex / lw.ntx;
                for (int k = 0; k < 4; ++k) {
                    const LaneGroup& qg =
                        lw.quarters[size_t(2 * ty + (k >> 1)) * size_t(lw.nqx) +
                                    size_t(2 * tx + (k & 1))];
                    if (!(qg.minDistLo < kInfF)) continue;
                    int qx = 0, qy = 0;
                    const LaneBits lq =
                        WindowLanes(qg, lt, dw.min4, dw.max4, ef.Lwin4, qx, qy);
                    if (!lq) continue;
#if RS_HAVE_CONE_SEARCH_AVX
                    if (avx512) {
                        SearchQuarterAvx512(qg, lq, qx, qy);
                        continue;
                    }
#endif
                    SearchQuarter(qg, lq, qx, qy);
                }
            }
        }
#if RS_HAVE_CONE_SEARCH_AVX
        if (marches.n) MarchBatchAvx512();
#endif
        return tb;
    }
};

/// The pruned search of every texel and channel: 4x4 tiles of texels (RelaxedTileSearch),
/// rows of tiles in parallel; each tile's search is seeded by the minimisers of the tile
/// to its left (docs/cone_maps.md, section "Exact pruning of the Listing").
void PrunedRelaxedMap(const DepthField& hf, const ConeMapParams& p, const Geometry& g,
                      float dmin, bool exitField, bool aheadEveryPair,
                      RelaxedOutput& out) {
    const int W = hf.width, H = hf.height, K = out.K;
    // Depth maxima over 4x4, 8x8 and 32x32 windows (the exit field's build and the
    // group bounds both use them; the others, for AheadPrunes, after the exit field).
    DepthWindows dw;
    dw.max4 = WindowMaxima(hf.depth, W, H, 4);
    dw.max8 = WindowMaxima(dw.max4, W, H, 2, 4);
    dw.max32 = WindowMaxima(dw.max8, W, H, kSuperTile, kTile);
    // The exit field before the offsets and the other windows: its build's scratch is
    // freed before they are made (peak memory at 2048²).
    const float inv = PowerOfTwoInverse(p.searchSteps);
    // The exit field's build with AVX-512 or AVX2, and the search's bounds with AVX-512,
    // where the lane search uses that unit (RS_CONE_SEARCH_ISA forces a unit; the tests
    // compare them).
    const ExitBuild unit = ExitScanBuild();
    const bool avx512 = unit == ExitBuild::ScanAvx512;
    const ExitField ef =
        BuildExitField(hf, p.searchSteps, inv, exitField, dw.max8, dw.max32, unit);
    {
        SearchWindows sw;  // depth minima over 8x8 and 32x32 windows (the tiled search's)
        MakeSearchWindows(hf, sw);
        dw.min8 = std::move(sw.win8);
        dw.min32 = std::move(sw.win32);
    }
    dw.min4 = WindowMinima(hf.depth, W, H, 1, 4);
    MakeWindowsAhead(dw, hf.depth, W, H);
    AssignOnHugePages(dw.shallow, hf.depth.size(), 0.0f);
    for (size_t t = 0; t < dw.shallow.size(); ++t) {
        const double b = double(hf.depth[t]);
        if (b > 0) dw.shallow[t] = NonNegFloatAtMost((1.0 - b) / b);
    }
    const DenseOffsets dense = MakeDenseOffsets(g, W, H, p.searchSteps, avx512);
    const LaneWindows lw = MakeLaneWindows(dense);
    ProgressCounter progress(p.progress, H);
    const int tileRows = (H + kApexSide - 1) / kApexSide;
    tbb::parallel_for(
        tbb::blocked_range<int>(0, tileRows, 1),
        [&](const tbb::blocked_range<int>& rows) {
            RelaxedTileSearch search(hf, dense, lw, dw, ef, p.searchSteps, inv, dmin);
            search.aheadEveryPair = aheadEveryPair;
            search.avx512 = avx512;
            for (int ty = rows.begin(); ty < rows.end(); ++ty) {
                const int J = ty * kApexSide;
                for (int c = 0; c < K; ++c) {
                    TileBest prev;
                    for (int I = 0; I < W; I += kApexSide) {
                        const TileBest& tb = search.SearchTile(
                            I, J, [&](int i, int j) { return out.Apex(hf.At(i, j), c); },
                            I > 0 ? &prev : nullptr);
                        for (int l = 0; l < kLanes; ++l) {
                            const int i = I + l % kApexSide, j = J + l / kApexSide;
                            if (i < W && j < H) out.Store(i, j, c, tb.best[size_t(l)]);
                        }
                        prev = tb;
                    }
                }
                progress.Add(std::min(kApexSide, H - J));
            }
        });
}

}  // namespace

ConeMap RelaxedListingMap(const DepthField& hf, const ConeMapParams& p, bool brute,
                          ConeKind outKind, bool exitField, bool aheadEveryPair) {
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
    AssignOnHugePages(out.m.values, size_t(hf.width) * size_t(hf.height) * size_t(out.K),
                      0.0f);
    if (brute)
        BruteRelaxedMap(hf, p, g, out);
    else
        PrunedRelaxedMap(hf, p, g, dmin, exitField, aheadEveryPair, out);
    return std::move(out.m);
}

std::vector<uint8_t> RelaxedExitField(const DepthField& hf, int steps, bool scan) {
    const int W = hf.width, H = hf.height;
    const std::vector<float> max8 =
        WindowMaxima(WindowMaxima(hf.depth, W, H, 4), W, H, 2, 4);
    const std::vector<float> max32 = WindowMaxima(max8, W, H, kSuperTile, kTile);
    const ExitBuild how = scan ? ExitScanBuild() : ExitBuild::EveryCell;
    ExitField f =
        BuildExitField(hf, steps, PowerOfTwoInverse(steps), true, max8, max32, how);
    return std::move(f.L);
}

}  // namespace reliefsim::detail
