// The lane search: preparation (min-depth pyramids, limiting flags), the choice of
// instruction set and the parallel loop over bands of tile rows.
#include "maps/cone_search.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string_view>

#include "core/error.h"
#include "maps/cone_search_lanes.h"

namespace reliefsim::detail {

void ConeSearchBandSse41(const ConeSearchData& d, int r0, int r1);
#if RS_HAVE_CONE_SEARCH_AVX
void ConeSearchBandAvx2(const ConeSearchData& d, int r0, int r1);
void ConeSearchBandAvx512(const ConeSearchData& d, int r0, int r1);
#endif

namespace {

using BandFn = void (*)(const ConeSearchData&, int, int);

struct IsaChoice {
    const char* name;
    BandFn fn;
};

/// The widest unit the CPU runs, or the one RS_CONE_SEARCH_ISA names (when the CPU
/// runs it; read at every search, so tests can compare the units).
IsaChoice Isa() {
    const char* forced = std::getenv("RS_CONE_SEARCH_ISA");
    const std::string_view want = forced ? forced : "";
#if RS_HAVE_CONE_SEARCH_AVX
    static const bool avx512 = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
               __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
    }();
    static const bool avx2 = [] {
        __builtin_cpu_init();
        return bool(__builtin_cpu_supports("avx2"));
    }();
    if (avx512 && (want.empty() || want == "avx512"))
        return {"avx512", &ConeSearchBandAvx512};
    if (avx2 && (want.empty() || want == "avx512" || want == "avx2"))
        return {"avx2", &ConeSearchBandAvx2};
#endif
    return {"sse4.1", &ConeSearchBandSse41};
}

/// Min-depth pyramid of `base` (W x H) into `out` at the levels' offsets; a cell holds
/// the minimum over its 2^l x 2^l texels (clipped at the map's edge: no wrap, the
/// traversal places the wrap images itself).
void BuildMinPyramid(const ConeSearchData& d, const float* base, float* out) {
    std::copy(base, base + size_t(d.W) * size_t(d.H), out);
    for (int l = 1; l <= d.top; ++l) {
        const int w = d.levelW[size_t(l)], h = d.levelH[size_t(l)];
        const int pw = d.levelW[size_t(l - 1)], ph = d.levelH[size_t(l - 1)];
        const float* src = out + d.levelOff[size_t(l - 1)];
        float* dst = out + d.levelOff[size_t(l)];
        tbb::parallel_for(
            tbb::blocked_range<int>(0, h, 64), [&](const tbb::blocked_range<int>& r) {
                for (int j = r.begin(); j < r.end(); ++j) {
                    const float* r0 = src + size_t(2 * j) * size_t(pw);
                    const float* r1 = 2 * j + 1 < ph ? r0 + pw : r0;
                    for (int i = 0; i < w; ++i) {
                        const int i1 = 2 * i + 1 < pw ? 2 * i + 1 : 2 * i;
                        dst[size_t(j) * size_t(w) + size_t(i)] = std::min(
                            std::min(r0[2 * i], r0[i1]), std::min(r1[2 * i], r1[i1]));
                    }
                }
            });
    }
}

/// A child cell for CombinePlanes: its box (texel centres) and its lower plane about the
/// box's centre (a texel: a box of one point and a flat plane at its depth).
struct PlaneChild {
    double x0, x1, y0, y1;
    double q0, gx, gy;
    float least;
    double Cx() const { return 0.5 * (x0 + x1); }
    double Cy() const { return 0.5 * (y0 + y1); }
};

/// The lower plane (ConeSearchData::LowerPlane) of the cell that `ch[0..n)` tile, about
/// the centre of their union. Its slope in x is the mean finite difference between
/// children of the same row (the same y extent), likewise in y; where no such pair
/// exists, the children's mean slope. Its height at the centre is the mean of the
/// children's planes there, lowered until the plane lies under each child's plane at the
/// child's corners, hence under every texel (any plane is valid: the lowering makes it
/// so). In double; q0 is rounded down to a float against the float slopes, with a guard
/// far above double rounding.
ConeSearchData::LowerPlane CombinePlanes(const PlaneChild* ch, int n) {
    double X0 = ch[0].x0, X1 = ch[0].x1, Y0 = ch[0].y0, Y1 = ch[0].y1;
    for (int i = 1; i < n; ++i) {
        X0 = std::min(X0, ch[i].x0), X1 = std::max(X1, ch[i].x1);
        Y0 = std::min(Y0, ch[i].y0), Y1 = std::max(Y1, ch[i].y1);
    }
    const double cx = 0.5 * (X0 + X1), cy = 0.5 * (Y0 + Y1);
    double gx = 0, gy = 0, sgx = 0, sgy = 0, p0 = 0;
    int nx = 0, ny = 0;
    float least = std::numeric_limits<float>::infinity();
    for (int i = 0; i < n; ++i) {
        const PlaneChild& c = ch[i];
        for (int j = i + 1; j < n; ++j) {
            const PlaneChild& o = ch[j];
            if (c.y0 == o.y0 && c.y1 == o.y1 && c.x0 != o.x0) {
                gx += (o.q0 - c.q0) / (o.Cx() - c.Cx());
                ++nx;
            } else if (c.x0 == o.x0 && c.x1 == o.x1 && c.y0 != o.y0) {
                gy += (o.q0 - c.q0) / (o.Cy() - c.Cy());
                ++ny;
            }
        }
        sgx += c.gx;
        sgy += c.gy;
        p0 += c.q0 + c.gx * (cx - c.Cx()) + c.gy * (cy - c.Cy());
        least = std::min(least, c.least);
    }
    const float fgx = float(nx ? gx / nx : sgx / n), fgy = float(ny ? gy / ny : sgy / n);
    p0 /= n;
    // Lower it under every child's plane over the child's box.
    double e = -std::numeric_limits<double>::infinity(), mag = 0;
    for (int i = 0; i < n; ++i) {
        const PlaneChild& c = ch[i];
        for (const double X : {c.x0, c.x1})
            for (const double Y : {c.y0, c.y1}) {
                const double up = double(fgx) * (X - cx) + double(fgy) * (Y - cy);
                const double down = c.gx * (X - c.Cx()) + c.gy * (Y - c.Cy());
                e = std::max(e, p0 + up - (c.q0 + down));
                mag = std::max(
                    mag, std::abs(p0) + std::abs(up) + std::abs(c.q0) + std::abs(down));
            }
    }
    return {FloatAtMost(p0 - e - 0x1p-40 * (1 + mag)), fgx, fgy, least};
}

/// The texel box [lo, hi] of cell c at level k along an axis of n texels.
double CellLo(int c, int k) { return double(c << k); }
double CellHi(int c, int k, int n) { return double(std::min((c + 1) << k, n) - 1); }

/// A texel at (x, y) of depth b as a child for CombinePlanes.
PlaneChild TexelChild(double x, double y, float b) {
    return {x, x, y, y, double(b), 0.0, 0.0, b};
}

/// A cell's child for CombinePlanes from its plane and box.
PlaneChild ChildOf(const ConeSearchData::LowerPlane& p, double x0, double x1, double y0,
                   double y1) {
    return {x0, x1, y0, y1, double(p.q0), double(p.gx), double(p.gy), p.least};
}

/// The lower planes of the quadtree's cells (ConeSearchData::LowerPlane), levels 1..top,
/// each from its (at most four) children's; level 0: the texels, flat.
void BuildLowerPlanes(ConeSearchData& d, const float* depth) {
    using LowerPlane = ConeSearchData::LowerPlane;
    if (d.top < 1) return;
    const int W = d.W, H = d.H;
    d.planes.resize(d.pyramidSize - d.levelOff[1]);
    for (int l = 1; l <= d.top; ++l) {
        const int w = d.levelW[size_t(l)], h = d.levelH[size_t(l)];
        const int pw = d.levelW[size_t(l - 1)], ph = d.levelH[size_t(l - 1)];
        LowerPlane* dst = d.planes.data() + (d.levelOff[size_t(l)] - d.levelOff[1]);
        const LowerPlane* src =
            l >= 2 ? d.planes.data() + (d.levelOff[size_t(l - 1)] - d.levelOff[1])
                   : nullptr;
        const auto cell = [&](int i, int j) {
            PlaneChild ch[4];
            int n = 0;
            for (int cj = 2 * j; cj < std::min(2 * j + 2, ph); ++cj)
                for (int ci = 2 * i; ci < std::min(2 * i + 2, pw); ++ci) {
                    const double x0 = CellLo(ci, l - 1), x1 = CellHi(ci, l - 1, W),
                                 y0 = CellLo(cj, l - 1), y1 = CellHi(cj, l - 1, H);
                    if (src) {
                        ch[n++] = ChildOf(src[size_t(cj) * size_t(pw) + size_t(ci)], x0,
                                          x1, y0, y1);
                    } else {  // level 0: texels (x0 = x1, y0 = y1)
                        ch[n++] = TexelChild(x0, y0,
                                             depth[size_t(cj) * size_t(W) + size_t(ci)]);
                    }
                }
            return CombinePlanes(ch, n);
        };
        tbb::parallel_for(tbb::blocked_range<int>(0, h, 16),
                          [&](const tbb::blocked_range<int>& r) {
                              for (int j = r.begin(); j < r.end(); ++j)
                                  for (int i = 0; i < w; ++i)
                                      dst[size_t(j) * size_t(w) + size_t(i)] = cell(i, j);
                          });
    }
}

/// The lower planes of a rip-map's cells (RipMap::planes) on the traversal's chain of
/// levels (RipSplitsC1) of at least 2^kRipPlaneLevel texels, in its sheared coordinates,
/// into `buf` (reused by the passes): the chain's smallest level from its texels, each
/// larger one from its two halves.
void BuildRipPlanes(ConeSearchData::RipMap& rip, int W, int H,
                    std::vector<ConeSearchData::LowerPlane>& buf) {
    using LowerPlane = ConeSearchData::LowerPlane;
    using Rip = ConeSearchData::RipMap;
    struct Level {
        int lx, ly;
    };
    std::vector<Level> chain;  // from the root down
    for (int lx = rip.levelsX, ly = rip.levelsY; lx + ly >= kRipPlaneLevel;) {
        chain.push_back({lx, ly});
        if (RipSplitsC1(lx, ly))
            --lx;
        else
            --ly;
    }
    rip.planeOffset.assign(rip.offset.size(), Rip::kNoPlanes);
    size_t total = 0;
    for (const Level& v : chain) {
        if (v.lx + v.ly > rip.levelsX + rip.levelsY - kRipPlaneTopSkip) continue;
        rip.planeOffset[size_t(v.lx) * size_t(rip.levelsY + 1) + size_t(v.ly)] = total;
        total += size_t(rip.cellsX[size_t(v.lx)]) * size_t(rip.cellsY[size_t(v.ly)]);
    }
    buf.resize(total);
    rip.planes = buf.data();
    const float* texels = rip.mins;  // level (0, 0)
    for (size_t k = chain.size(); k-- > 0;) {
        const int lx = chain[k].lx, ly = chain[k].ly;
        const int w = rip.cellsX[size_t(lx)], h = rip.cellsY[size_t(ly)];
        const size_t at =
            rip.planeOffset[size_t(lx) * size_t(rip.levelsY + 1) + size_t(ly)];
        if (at == Rip::kNoPlanes) break;  // the larger levels have none
        LowerPlane* dst = buf.data() + at;
        const bool fromTexels = k + 1 == chain.size();
        const auto cell = [&](int i, int j) {
            PlaneChild ch[1 << kRipPlaneLevel];
            int n = 0;
            if (fromTexels) {
                for (int c2 = j << ly; c2 < std::min((j + 1) << ly, H); ++c2)
                    for (int c1 = i << lx; c1 < std::min((i + 1) << lx, W); ++c1)
                        ch[n++] = TexelChild(c1, c2,
                                             texels[size_t(c2) * size_t(W) + size_t(c1)]);
                return CombinePlanes(ch, n);
            }
            const int kx = chain[k + 1].lx, ky = chain[k + 1].ly;
            const int cw = rip.cellsX[size_t(kx)], chh = rip.cellsY[size_t(ky)];
            for (int cj = j << (ly - ky); cj < std::min((j + 1) << (ly - ky), chh); ++cj)
                for (int ci = i << (lx - kx); ci < std::min((i + 1) << (lx - kx), cw);
                     ++ci)
                    ch[n++] =
                        ChildOf(*rip.PlaneAt(kx, ky, ci, cj), CellLo(ci, kx),
                                CellHi(ci, kx, W), CellLo(cj, ky), CellHi(cj, ky, H));
            return CombinePlanes(ch, n);
        };
        const int grain = std::max(1, (1 << 14) / w);
        tbb::parallel_for(tbb::blocked_range<int>(0, h, grain),
                          [&](const tbb::blocked_range<int>& r) {
                              for (int j = r.begin(); j < r.end(); ++j)
                                  for (int i = 0; i < w; ++i)
                                      dst[size_t(j) * size_t(w) + size_t(i)] = cell(i, j);
                          });
    }
}

/// The rip-map of `rip`'s sheared image: level (0, 0) holds the depth of real texel
/// (c1 + alpha c2, c2 + beta c1) (wrapped) at (c1, c2); level (lx, ly) the minimum over
/// aligned 2^lx x 2^ly rectangles of it (clipped at the edge). Its cells go to `cells`,
/// allocated by the first pass and reused by the next (every rip-map of a map has the
/// same size). The buffer is left uninitialised, so that its pages are first touched by
/// the parallel fill below and not by one thread zeroing 4 W H floats (on this host's VM,
/// page faults were most of the first passes' build time).
void BuildRipMap(const ConeSearchData& d, ConeSearchData::RipMap& rip,
                 std::unique_ptr<float[]>& cells, size_t& cellsSize) {
    const int W = d.W, H = d.H;
    auto levels = [](int n) {
        int l = 0;
        while ((1 << l) < n) ++l;
        return l;
    };
    rip.levelsX = levels(W);
    rip.levelsY = levels(H);
    rip.cellsX.resize(size_t(rip.levelsX + 1));
    rip.cellsY.resize(size_t(rip.levelsY + 1));
    for (int l = 0; l <= rip.levelsX; ++l)
        rip.cellsX[size_t(l)] = (W + (1 << l) - 1) >> l;
    for (int l = 0; l <= rip.levelsY; ++l)
        rip.cellsY[size_t(l)] = (H + (1 << l) - 1) >> l;
    rip.offset.resize(size_t(rip.levelsX + 1) * size_t(rip.levelsY + 1));
    size_t off = 0;
    for (int lx = 0; lx <= rip.levelsX; ++lx)
        for (int ly = 0; ly <= rip.levelsY; ++ly) {
            rip.offset[size_t(lx) * size_t(rip.levelsY + 1) + size_t(ly)] = off;
            off += size_t(rip.cellsX[size_t(lx)]) * size_t(rip.cellsY[size_t(ly)]);
        }
    if (cellsSize != off) {
        cells.reset(new float[off]);
        cellsSize = off;
    }
    float* mins = cells.get();
    rip.mins = mins;
    const DepthField& hf = *d.field;
    const int a = rip.Layout().alpha, b = rip.Layout().beta;
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 64),
                      [&](const tbb::blocked_range<int>& r) {
                          for (int c2 = r.begin(); c2 < r.end(); ++c2)
                              for (int c1 = 0; c1 < W; ++c1)
                                  mins[size_t(c2) * size_t(W) + size_t(c1)] =
                                      hf.At(Wrap(c1 + a * c2, W), Wrap(c2 + b * c1, H));
                      });
    auto level = [&](int lx, int ly) {
        return mins + rip.offset[size_t(lx) * size_t(rip.levelsY + 1) + size_t(ly)];
    };
    for (int lx = 0; lx <= rip.levelsX; ++lx)
        for (int ly = 0; ly <= rip.levelsY; ++ly) {
            if (lx == 0 && ly == 0) continue;
            const int w = rip.cellsX[size_t(lx)], h = rip.cellsY[size_t(ly)];
            float* dst = level(lx, ly);
            // Rows in parallel where a level is large (at least 2^16 cells).
            const int grain = std::max(1, (1 << 16) / w);
            if (ly > 0) {  // from (lx, ly - 1): pairs of rows
                const float* src = level(lx, ly - 1);
                const int ph = rip.cellsY[size_t(ly - 1)];
                tbb::parallel_for(tbb::blocked_range<int>(0, h, grain),
                                  [&](const tbb::blocked_range<int>& r) {
                                      for (int j = r.begin(); j < r.end(); ++j) {
                                          const float* r0 =
                                              src + size_t(2 * j) * size_t(w);
                                          const float* r1 = 2 * j + 1 < ph ? r0 + w : r0;
                                          for (int i = 0; i < w; ++i)
                                              dst[size_t(j) * size_t(w) + size_t(i)] =
                                                  std::min(r0[i], r1[i]);
                                      }
                                  });
            } else {  // from (lx - 1, 0): pairs of columns
                const float* src = level(lx - 1, 0);
                const int pw = rip.cellsX[size_t(lx - 1)];
                tbb::parallel_for(tbb::blocked_range<int>(0, h, grain),
                                  [&](const tbb::blocked_range<int>& r) {
                                      for (int j = r.begin(); j < r.end(); ++j) {
                                          const float* row = src + size_t(j) * size_t(pw);
                                          for (int i = 0; i < w; ++i) {
                                              const int i1 =
                                                  2 * i + 1 < pw ? 2 * i + 1 : 2 * i;
                                              dst[size_t(j) * size_t(w) + size_t(i)] =
                                                  std::min(row[2 * i], row[i1]);
                                          }
                                      }
                                  });
            }
        }
}

/// The rip-maps of acm4 and acm8 (ConeSearchData::RipMap, without their cells); none for
/// the others (the quadtree serves the cone, and quad's half planes, well), and none for
/// acm8 on non-square maps, whose uv diagonals are not texel diagonals. The one place
/// that decides them: the search makes one pass per rip-map, and ConeSearchPasses counts
/// them for the progress total before the search starts.
std::vector<ConeSearchData::RipMap> RipMapLayout(ConeKind sectors, int W, int H) {
    using Rip = ConeSearchData::RipMap;
    std::vector<Rip> rips;
    auto add = [&](int layout) {
        Rip r;
        r.layout = layout;
        rips.push_back(std::move(r));
    };
    switch (sectors) {
        case ConeKind::Acm4:
            add(kRipLayoutAcm4);
            break;
        case ConeKind::Acm8:
            if (W != H) break;
            for (int i = 0; i < 4; ++i) add(kRipLayoutAcm8 + i);
            break;
        default:
            break;
    }
    // (Each rip-map's cells are built by RunConeSearch right before its pass.)
    return rips;
}

}  // namespace

const char* ConeSearchIsa() { return Isa().name; }

int ConeSearchPasses(ConeKind sectors, int W, int H) {
    return std::max(1, int(RipMapLayout(sectors, W, H).size()));
}

void RunConeSearch(const ConeSearchJob& job, ProgressCounter* progress) {
    const DepthField& hf = *job.field;
    ConeSearchData d;
    d.field = &hf;
    d.apex = job.apex;
    d.W = hf.width;
    d.H = hf.height;
    d.g = MakeGeometry(d.W, d.H);
    d.sectors = job.sectors;
    d.nChannels = SectorCount(job.sectors);
    d.limiting = job.limiting;
    d.output = job.output;
    d.out = job.out;
    d.outStride = job.outStride;
    d.outBase = job.outBase;
    d.progress = progress;
    RS_CHECK(d.nChannels <= kMaxSectors);
    // Pyramid levels: halve (rounding up) until one cell.
    int w = d.W, h = d.H, l = 0;
    size_t off = 0;
    for (;;) {
        RS_CHECK(l < 32);
        d.levelW[size_t(l)] = w;
        d.levelH[size_t(l)] = h;
        d.levelOff[size_t(l)] = off;
        off += size_t(w) * size_t(h);
        if (w == 1 && h == 1) break;
        w = (w + 1) / 2;
        h = (h + 1) / 2;
        ++l;
    }
    d.top = l;
    d.pyramidSize = off;
    const size_t n = size_t(d.W) * size_t(d.H);
    d.rips = RipMapLayout(d.sectors, d.W, d.H);
    if (!d.rips.empty()) {
        // The rip-maps serve the traversal: no pyramid, only the least depth.
        RS_CHECK(!d.limiting);
        d.dmin = *std::min_element(hf.depth.begin(), hf.depth.end());
    } else if (!d.limiting) {
        // The lower planes hold the least depths too: no pyramid.
        BuildLowerPlanes(d, hf.depth.data());
        d.dmin = d.planes.empty() ? hf.depth[0] : d.planes.back().least;
    } else {
        // Per texel, the directions in which it is limiting (IsLimiting): its neighbour
        // one step that way is strictly deeper.
        d.flags.assign(n, 0);
        tbb::parallel_for(
            tbb::blocked_range<int>(0, d.H, 64), [&](const tbb::blocked_range<int>& r) {
                for (int j = r.begin(); j < r.end(); ++j)
                    for (int i = 0; i < d.W; ++i) {
                        const float b = hf.At(i, j);
                        uint8_t f = 0;
                        for (int sy = -1; sy <= 1; ++sy)
                            for (int sx = -1; sx <= 1; ++sx) {
                                if (sx == 0 && sy == 0) continue;
                                if (hf.At(Wrap(i + sx, d.W), Wrap(j + sy, d.H)) > b)
                                    f |= uint8_t(1u << ClassBit(sx, sy));
                            }
                        d.flags[size_t(j) * size_t(d.W) + size_t(i)] = f;
                    }
            });
        d.pyramids.resize(off * 8);
        std::vector<float> base(n);
        float dmin = std::numeric_limits<float>::infinity();
        for (int c = 0; c < 8; ++c) {
            for (size_t t = 0; t < n; ++t)
                base[t] = (d.flags[t] >> c & 1u) ? hf.depth[t]
                                                 : std::numeric_limits<float>::infinity();
            BuildMinPyramid(d, base.data(), d.pyramids.data() + size_t(c) * off);
            dmin = std::min(dmin, d.pyramids[size_t(c) * off + off - 1]);
        }
        d.dmin = dmin;
    }
    const int tileRows = (d.H + kLaneTile - 1) / kLaneTile;
    // Bands of two tile rows: the seeds carry from row to row inside a band.
    constexpr int kBand = 2;
    const BandFn fn = Isa().fn;
    // One pass per rip-map (its channels only), so that one rip-map is read at a time.
    const int passes = ConeSearchPasses(job.sectors, d.W, d.H);
    // Only the pass's rip-map is held (4 W H floats): each pass builds its own into the
    // same buffer.
    std::unique_ptr<float[]> ripCells;
    size_t ripCellsSize = 0;
    std::vector<ConeSearchData::LowerPlane> ripPlanes;
    for (int pass = 0; pass < passes; ++pass) {
        d.ripPass = pass;
        d.passChannels = d.rips.empty() ? (1u << d.nChannels) - 1u
                                        : d.rips[size_t(pass)].Layout().Channels();
        if (!d.rips.empty()) {
            BuildRipMap(d, d.rips[size_t(pass)], ripCells, ripCellsSize);
            BuildRipPlanes(d.rips[size_t(pass)], d.W, d.H, ripPlanes);
        }
        tbb::parallel_for(tbb::blocked_range<int>(0, (tileRows + kBand - 1) / kBand, 1),
                          [&](const tbb::blocked_range<int>& r) {
                              for (int b = r.begin(); b < r.end(); ++b)
                                  fn(d, b * kBand, std::min(tileRows, b * kBand + kBand));
                          });
        if (!d.rips.empty()) {
            d.rips[size_t(pass)].mins = nullptr;
            d.rips[size_t(pass)].planes = nullptr;
        }
    }
}

}  // namespace reliefsim::detail
