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

/// `v` rounded to a float at most `v`.
float FloatBelow(double v) {
    float r = float(v);
    if (double(r) > v) r = std::nextafter(r, -std::numeric_limits<float>::infinity());
    return r;
}

/// The lower planes of the quadtree's cells (ConeSearchData::LowerPlane), levels 1..top,
/// each from its children's (level 0: the texels, flat). The slope is the children's
/// finite difference across the cell where both columns (rows) of children exist, else
/// their mean slope; the height at the centre is the mean of the children's planes there,
/// lowered until the plane lies under each child's plane at the child's corners, hence
/// under every texel (any plane is valid: the lowering makes it so). In double; q0 is
/// rounded down to a float against the float slopes, with a guard far above double
/// rounding.
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
        // The texel box of cell c at level k along an axis of n texels.
        const auto lo = [](int c, int k) { return double(c << k); };
        const auto hi = [](int c, int k, int n) {
            return double(std::min((c + 1) << k, n) - 1);
        };
        tbb::parallel_for(
            tbb::blocked_range<int>(0, h, 16), [&](const tbb::blocked_range<int>& r) {
                for (int j = r.begin(); j < r.end(); ++j)
                    for (int i = 0; i < w; ++i) {
                        const double cx = 0.5 * (lo(i, l) + hi(i, l, W)),
                                     cy = 0.5 * (lo(j, l) + hi(j, l, H));
                        struct Child {
                            double q0, gx, gy, cx, cy, x0, x1, y0, y1;
                            bool in;
                        } ch[2][2];
                        for (int b = 0; b < 2; ++b)
                            for (int a = 0; a < 2; ++a) {
                                Child& c = ch[b][a];
                                const int ci = 2 * i + a, cj = 2 * j + b;
                                c.in = ci < pw && cj < ph;
                                if (!c.in) continue;
                                c.x0 = lo(ci, l - 1);
                                c.x1 = hi(ci, l - 1, W);
                                c.y0 = lo(cj, l - 1);
                                c.y1 = hi(cj, l - 1, H);
                                c.cx = 0.5 * (c.x0 + c.x1);
                                c.cy = 0.5 * (c.y0 + c.y1);
                                if (src) {
                                    const LowerPlane& p =
                                        src[size_t(cj) * size_t(pw) + size_t(ci)];
                                    c.q0 = p.q0;
                                    c.gx = p.gx;
                                    c.gy = p.gy;
                                } else {
                                    c.q0 = depth[size_t(cj) * size_t(W) + size_t(ci)];
                                    c.gx = c.gy = 0;
                                }
                            }
                        // Slopes.
                        double gx = 0, gy = 0, sgx = 0, sgy = 0;
                        int nx = 0, ny = 0, n = 0;
                        for (int b = 0; b < 2; ++b)
                            if (ch[b][0].in && ch[b][1].in) {
                                gx += (ch[b][1].q0 - ch[b][0].q0) /
                                      (ch[b][1].cx - ch[b][0].cx);
                                ++nx;
                            }
                        for (int a = 0; a < 2; ++a)
                            if (ch[0][a].in && ch[1][a].in) {
                                gy += (ch[1][a].q0 - ch[0][a].q0) /
                                      (ch[1][a].cy - ch[0][a].cy);
                                ++ny;
                            }
                        double p0 = 0;
                        for (const auto& row : ch)
                            for (const Child& c : row)
                                if (c.in) {
                                    sgx += c.gx;
                                    sgy += c.gy;
                                    p0 += c.q0 + c.gx * (cx - c.cx) + c.gy * (cy - c.cy);
                                    ++n;
                                }
                        const float fgx = float(nx ? gx / nx : sgx / n),
                                    fgy = float(ny ? gy / ny : sgy / n);
                        p0 /= n;
                        // Lower it under every child's plane over the child's box.
                        double e = -std::numeric_limits<double>::infinity(), mag = 0;
                        for (const auto& row : ch)
                            for (const Child& c : row) {
                                if (!c.in) continue;
                                for (const double X : {c.x0, c.x1})
                                    for (const double Y : {c.y0, c.y1}) {
                                        const double up = double(fgx) * (X - cx) +
                                                          double(fgy) * (Y - cy);
                                        const double down =
                                            c.gx * (X - c.cx) + c.gy * (Y - c.cy);
                                        e = std::max(e, p0 + up - (c.q0 + down));
                                        mag = std::max(mag, std::abs(p0) + std::abs(up) +
                                                                std::abs(c.q0) +
                                                                std::abs(down));
                                    }
                            }
                        dst[size_t(j) * size_t(w) + size_t(i)] = {
                            FloatBelow(p0 - e - 0x1p-40 * (1 + mag)), fgx, fgy,
                            d.pyramids[d.levelOff[size_t(l)] + size_t(j) * size_t(w) +
                                       size_t(i)]};
                    }
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
        d.pyramids.resize(off);
        BuildMinPyramid(d, hf.depth.data(), d.pyramids.data());
        d.dmin = d.pyramids[off - 1];
        BuildLowerPlanes(d, hf.depth.data());
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
    for (int pass = 0; pass < passes; ++pass) {
        d.ripPass = pass;
        d.passChannels = d.rips.empty() ? (1u << d.nChannels) - 1u
                                        : d.rips[size_t(pass)].Layout().Channels();
        if (!d.rips.empty()) BuildRipMap(d, d.rips[size_t(pass)], ripCells, ripCellsSize);
        tbb::parallel_for(tbb::blocked_range<int>(0, (tileRows + kBand - 1) / kBand, 1),
                          [&](const tbb::blocked_range<int>& r) {
                              for (int b = r.begin(); b < r.end(); ++b)
                                  fn(d, b * kBand, std::min(tileRows, b * kBand + kBand));
                          });
        if (!d.rips.empty()) d.rips[size_t(pass)].mins = nullptr;
    }
}

}  // namespace reliefsim::detail
