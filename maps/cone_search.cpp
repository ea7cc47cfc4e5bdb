// The lane search: preparation (min-depth pyramids, limiting flags), the choice of
// instruction set and the parallel loop over bands of tile rows.
#include "maps/cone_search.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
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
