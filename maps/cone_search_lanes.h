// The lane search's shared data: what RunConeSearch prepares for the engine
// (maps/cone_search_engine.h) and the sector and class tables of its cells. Only for
// cone_search*.cpp; see maps/cone_search.h.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "maps/cone_search.h"

namespace reliefsim::detail {

/// A rip-map's layout: its shear (real texel X = c1 + alpha * c2, Y = c2 + beta * c1)
/// and the sectors (channels) it serves, each a quadrant of (c1, c2) offsets given by
/// its signs: +1 (>= 0), -1 (<= 0) or 0 (either) per coordinate.
struct RipLayout {
    int alpha = 0, beta = 0;
    int n = 0;  ///< sectors served
    int ch[kMaxSectors] = {}, s1[kMaxSectors] = {}, s2[kMaxSectors] = {};
    constexpr uint32_t Channels() const {
        uint32_t m = 0;
        for (int i = 0; i < n; ++i) m |= 1u << ch[i];
        return m;
    }
};

/// Every rip-map layout (RipMapLayout picks them; the engine is compiled once per
/// layout, with its shear and signs as constants). acm4: the closed quadrants, one
/// rip-map. acm8: each pair of opposite 45-degree sectors is a pair of quadrants of one
/// shear: c1 = X - Y for sectors 0, 4 (edges: the x axis and the diagonal), c2 = Y - X
/// for 1, 5, c2 = Y + X for 2, 6, c1 = X + Y for 3, 7.
inline constexpr RipLayout kRipLayouts[] = {
    {0, 0, 4, {0, 1, 2, 3}, {1, -1, -1, 1}, {1, 1, -1, -1}},
    {1, 0, 2, {0, 4}, {1, -1}, {1, -1}},
    {0, 1, 2, {1, 5}, {1, -1}, {1, -1}},
    {0, -1, 2, {2, 6}, {-1, 1}, {1, -1}},
    {-1, 0, 2, {3, 7}, {-1, 1}, {1, -1}},
};
inline constexpr int kNumRipLayouts = int(sizeof(kRipLayouts) / sizeof(kRipLayouts[0]));
inline constexpr int kRipLayoutAcm4 = 0, kRipLayoutAcm8 = 1;  ///< acm8: 1 to 4

/// Whether the rip-map traversal splits a cell of levels (lx, ly) in c1 (its longer
/// side; else in c2). From the root (levelsX, levelsY) it visits one chain of levels,
/// each split once: the rip planes are built for those levels only.
constexpr bool RipSplitsC1(int lx, int ly) { return ly == 0 || (lx > 0 && lx >= ly); }

/// The rip cells with lower planes: those of the traversal's chain of levels with at
/// least 2^kRipPlaneLevel texels (smaller ones are tested texel by texel) and at most
/// 2^-kRipPlaneTopSkip of the map (on larger ones the bound prunes little and costs a
/// test).
inline constexpr int kRipPlaneLevel = 4, kRipPlaneTopSkip = 6;

/// Everything a band of tiles reads, prepared once by RunConeSearch.
struct ConeSearchData {
    const DepthField* field = nullptr;
    const float* apex = nullptr;
    Geometry g;
    int W = 0, H = 0;
    int top = 0;  ///< the pyramid's top level (one cell)
    std::array<int, 32> levelW{}, levelH{};
    std::array<size_t, 32> levelOff{};
    size_t pyramidSize = 0;  ///< floats per pyramid
    /// With `limiting` only: min-depth pyramids (level 0 = the texels), one per
    /// direction class, holding the depth of the texels limiting for that class (+inf
    /// elsewhere), back to back. (The other quadtree searches keep each cell's least
    /// depth in `planes`.)
    std::vector<float> pyramids;
    /// A lower plane of a quadtree cell: every texel t of the cell (unwrapped box
    /// [X0, X1] x [Y0, Y1], centre c) has depth >= q0 + gx (t.x - c.x) + gy (t.y - c.y);
    /// and the cell's least depth. A rip cell's plane is the same in its sheared
    /// coordinates: gx, gy are the slopes in c1 and c2.
    struct LowerPlane {
        float q0, gx, gy, least;
    };
    /// Per cell of levels 1..top (index: pyramid index - levelOff[1]), for the
    /// first-order cell bound (docs/cone_maps.md, "The first-order cell bound"); empty
    /// where unused (rip-maps, limiting).
    std::vector<LowerPlane> planes;
    std::vector<uint8_t> flags;  ///< limiting: per texel, bit ClassBit(sx, sy) set when
                                 ///< the neighbour (i + sx, j + sy) is strictly deeper
    /// Sector kinds: rip-maps (min over every aligned 2^lx x 2^ly rectangle) in sheared
    /// coordinates (c1, c2) (RipLayout), chosen so that the edges of the sectors each
    /// serves are lines c1 = const and c2 = const: a cell then never straddles them for
    /// long.
    struct RipMap {
        int layout = 0;  ///< in kRipLayouts
        const RipLayout& Layout() const { return kRipLayouts[layout]; }
        int levelsX = 0, levelsY = 0;
        std::vector<int> cellsX, cellsY;  ///< per level
        std::vector<size_t> offset;       ///< per (lx, ly): lx * (levelsY + 1) + ly
        /// The cells, level after level (RunConeSearch's buffer, shared by the passes).
        const float* mins = nullptr;
        /// Lower planes (and least depths) of the cells that have them (kRipPlaneLevel),
        /// level after level; planeOffset per (lx, ly) as `offset`, kNoPlanes for the
        /// levels without.
        static constexpr size_t kNoPlanes = ~size_t(0);
        const LowerPlane* planes = nullptr;
        std::vector<size_t> planeOffset;
        const LowerPlane* PlaneAt(int lx, int ly, int cx, int cy) const {
            const size_t o = planeOffset[size_t(lx) * size_t(levelsY + 1) + size_t(ly)];
            if (o == kNoPlanes) return nullptr;
            return planes + o + size_t(cy) * size_t(cellsX[size_t(lx)]) + size_t(cx);
        }
        float At(int lx, int ly, int cx, int cy) const {
            return mins[offset[size_t(lx) * size_t(levelsY + 1) + size_t(ly)] +
                        size_t(cy) * size_t(cellsX[size_t(lx)]) + size_t(cx)];
        }
    };
    std::vector<RipMap> rips;
    /// The rip-map this pass traverses (rips are searched one pass each, so only one
    /// rip-map's cells are read at a time), and the channels the pass writes.
    int ripPass = 0;
    uint32_t passChannels = ~0u;
    ConeKind sectors = ConeKind::Cone;
    int nChannels = 1;
    bool limiting = false;
    ConeSearchOutput output = ConeSearchOutput::Ratio;
    float* out = nullptr;
    int outStride = 1, outBase = 0;
    float dmin = 0.0f;  ///< the smallest depth: an apex at or above it has no blocker
    ProgressCounter* progress = nullptr;
};

/// The bit of direction (sx, sy) in {-1,0,1}^2 minus (0,0): (sy+1)*3 + (sx+1),
/// skipping 4.
constexpr int ClassBit(int sx, int sy) {
    const int i = (sy + 1) * 3 + (sx + 1);
    return i > 4 ? i - 1 : i;
}

/// IsLimiting's direction class of an offset: sx, sy in {-1, 0, 1}.
inline void OffsetClass(int dx, int dy, int& sx, int& sy) {
    const int ax = dx < 0 ? -dx : dx, ay = dy < 0 ? -dy : dy;
    const int m = ax > ay ? ax : ay;
    sx = (2 * ax >= m) ? (dx > 0 ? 1 : (dx < 0 ? -1 : 0)) : 0;
    sy = (2 * ay >= m) ? (dy > 0 ? 1 : (dy < 0 ? -1 : 0)) : 0;
}

/// The regions (acm4 / acm8 sectors, or direction classes) an offset rectangle
/// [x0, x1] x [y0, y1] can touch, a superset: every region when it holds the origin,
/// else the regions between its two extreme corners (it spans less than 180 degrees).
/// `closed(dx, dy)` gives the bits of the closed regions holding a direction, `order`
/// the bits in counter-clockwise order.
template <class Closed>
uint32_t RegionsOfRect(int64_t x0, int64_t x1, int64_t y0, int64_t y1, int n,
                       const int* order, Closed&& closed) {
    const uint32_t all = (1u << n) - 1u;
    if (x0 <= 0 && x1 >= 0 && y0 <= 0 && y1 >= 0) return all;
    const int64_t cx[4] = {x0, x1, x0, x1}, cy[4] = {y0, y0, y1, y1};
    auto cross = [&](int a, int b) { return cx[a] * cy[b] - cy[a] * cx[b]; };
    int first = 0, last = 0;
    for (int k = 1; k < 4; ++k) {
        if (cross(k, first) > 0) first = k;  // k lies clockwise of first
        if (cross(last, k) > 0) last = k;    // k lies counter-clockwise of last
    }
    // Positions in the counter-clockwise order.
    auto positions = [&](uint32_t bits) {
        uint32_t p = 0;
        for (int k = 0; k < n; ++k)
            if (bits >> order[k] & 1u) p |= 1u << k;
        return p;
    };
    const uint32_t a = positions(closed(cx[first], cy[first]));
    const uint32_t b = positions(closed(cx[last], cy[last]));
    // The counter-clockwise-last position of a (cyclic), the first of b.
    auto lastOf = [&](uint32_t p) {
        for (int k = 0; k < n; ++k)
            if ((p >> k & 1u) && !(p >> ((k + 1) % n) & 1u)) return k;
        return 0;
    };
    auto firstOf = [&](uint32_t p) {
        for (int k = 0; k < n; ++k)
            if ((p >> k & 1u) && !(p >> ((k + n - 1) % n) & 1u)) return k;
        return 0;
    };
    uint32_t pos = a | b;
    const int la = lastOf(a), fb = firstOf(b);
    const int dist = ((fb - la) % n + n) % n;
    if (dist <= n / 2)
        for (int k = (la + 1) % n; k != fb; k = (k + 1) % n) pos |= 1u << k;
    uint32_t bits = 0;
    for (int k = 0; k < n; ++k)
        if (pos >> k & 1u) bits |= 1u << order[k];
    return bits & all;
}

/// The closed direction classes holding an offset (both classes on a boundary).
inline uint32_t ClosedClasses(int64_t dx, int64_t dy) {
    const int64_t ax = dx < 0 ? -dx : dx, ay = dy < 0 ? -dy : dy;
    const int sx = dx > 0 ? 1 : (dx < 0 ? -1 : 0), sy = dy > 0 ? 1 : (dy < 0 ? -1 : 0);
    uint32_t bits = 0;
    if (ax >= 2 * ay) bits |= 1u << ClassBit(sx, 0);
    if (ay >= 2 * ax) bits |= 1u << ClassBit(0, sy);
    if (2 * ay >= ax && 2 * ax >= ay && ax > 0 && ay > 0) bits |= 1u << ClassBit(sx, sy);
    return bits;
}

/// The channels (sectors) of `d.sectors` an offset rectangle can touch (superset).
inline uint32_t ChannelsOfRect(const ConeSearchData& d, int x0, int x1, int y0, int y1) {
    switch (d.sectors) {
        case ConeKind::Quad:
            return uint32_t((x1 > 0 ? 1 : 0) | (x0 < 0 ? 2 : 0) | (y1 > 0 ? 4 : 0) |
                            (y0 < 0 ? 8 : 0));
        case ConeKind::Acm4:
        case ConeKind::Acm8: {
            static constexpr int kOrder[8] = {0, 1, 2, 3, 4, 5, 6, 7};
            const int n = d.nChannels;
            const Geometry& g = d.g;
            const ConeKind kind = d.sectors;
            // Sectors are taken in uv space: (dx * H, dy * W).
            return RegionsOfRect(
                int64_t(x0) * g.h, int64_t(x1) * g.h, int64_t(y0) * g.w,
                int64_t(y1) * g.w, n, kOrder, [&](int64_t vx, int64_t vy) {
                    return uint32_t(SectorMask(kind, g, int(vx / g.h), int(vy / g.w)));
                });
        }
        default:
            return 1u;
    }
}

/// The direction classes an offset rectangle can touch (superset), as class bits.
inline uint32_t ClassesOfRect(int x0, int x1, int y0, int y1) {
    static constexpr int kOrder[8] = {ClassBit(1, 0),  ClassBit(1, 1),  ClassBit(0, 1),
                                      ClassBit(-1, 1), ClassBit(-1, 0), ClassBit(-1, -1),
                                      ClassBit(0, -1), ClassBit(1, -1)};
    return RegionsOfRect(x0, x1, y0, y1, 8, kOrder,
                         [](int64_t dx, int64_t dy) { return ClosedClasses(dx, dy); });
}

}  // namespace reliefsim::detail
