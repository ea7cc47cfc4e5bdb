// Adaptive hierarchical ACM preprocessing (000 Algorithm 1) with a guarantee: every
// block's ratio bounds all texels of the block from below, so copying a parent's ratio
// never widens.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/param_name.h"
#include "maps/cone_map.h"
#include "maps/cone_map_detail.h"

namespace reliefsim {

namespace {

using namespace detail;

struct Level {
    int nx = 0, ny = 0, size = 1;  ///< blocks, block size in texels
    std::vector<float> dmin,
        dmax;               ///< per block: min depth (highest) and max depth (lowest)
    std::vector<double> q;  ///< per block and sector
};

struct BlockOffset {
    int kx, ky;
    int64_t s;     ///< exact lower bound of S over every texel pair of the two blocks
    uint8_t mask;  ///< superset of the sectors a texel pair can fall in
};

bool RayHitsRect(double bx, double by, double x0, double x1, double y0, double y1) {
    double t0 = 0, t1 = 1e300;
    auto axis = [&](double b, double lo, double hi) {
        if (b == 0) return lo <= 0 && 0 <= hi;
        double a = lo / b, c = hi / b;
        if (a > c) std::swap(a, c);
        t0 = std::max(t0, a);
        t1 = std::min(t1, c);
        return true;
    };
    if (!axis(bx, x0, x1) || !axis(by, y0, y1)) return false;
    return t0 <= t1 * (1 + 1e-12) + 1e-12;
}

uint8_t RectMask(ConeKind kind, const Geometry& g, int x0, int x1, int y0, int y1) {
    const int n = SectorCount(kind);
    if (n == 1) return 1;
    if (x0 <= 0 && 0 <= x1 && y0 <= 0 && 0 <= y1) return uint8_t((1u << n) - 1u);
    uint8_t m = uint8_t(SectorMask(kind, g, x0, y0) | SectorMask(kind, g, x1, y0) |
                        SectorMask(kind, g, x0, y1) | SectorMask(kind, g, x1, y1));
    if (kind == ConeKind::Quad) return m;
    // Boundary rays of the sectors (uv directions, as texel directions (bx*W, by*H)).
    static constexpr int kB8[8][2] = {{1, 0},  {1, 1},   {0, 1},  {-1, 1},
                                      {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
    for (int b = 0; b < 8; ++b) {
        if (n == 4 && (b & 1)) continue;
        const double dx = kB8[b][0] * double(g.w), dy = kB8[b][1] * double(g.h);
        if (RayHitsRect(dx, dy, x0, x1, y0, y1)) {
            const int k = n == 4 ? b / 2 : b;  // sectors k-1 and k share boundary k
            m |= uint8_t(1u << k);
            m |= uint8_t(1u << ((k + n - 1) % n));
        }
    }
    return m;
}

std::vector<BlockOffset> MakeBlockOffsets(const Geometry& g, const Level& L,
                                          ConeKind kind) {
    std::vector<BlockOffset> v;
    const int s = L.size;
    // One image more on each side than the nearest ones: with an odd block count the
    // texel offsets at +-W/2 (both in the exact definition) need their own sector masks.
    for (int ky = -(L.ny / 2) - 1; ky <= L.ny / 2 + 1; ++ky)
        for (int kx = -(L.nx / 2) - 1; kx <= L.nx / 2 + 1; ++kx) {
            BlockOffset b{kx, ky, 0, 0};
            if (kx == 0 && ky == 0) {
                b.s =
                    std::min(g.wx, g.wy);  // two distinct texels of one block: >= 1 apart
            } else {
                const int64_t gx = std::max(0, std::abs(kx) * s - (s - 1));
                const int64_t gy = std::max(0, std::abs(ky) * s - (s - 1));
                b.s = gx * gx * g.wx + gy * gy * g.wy;
            }
            b.mask = RectMask(kind, g, kx * s - (s - 1), kx * s + (s - 1),
                              ky * s - (s - 1), ky * s + (s - 1));
            v.push_back(b);
        }
    std::stable_sort(v.begin(), v.end(), [](const BlockOffset& a, const BlockOffset& b) {
        return a.s < b.s;
    });
    return v;
}

void BlockSearch(const Level& L, const std::vector<BlockOffset>& offs, float dminGlobal,
                 int bi, int bj, int nS, double* best) {
    const size_t a = size_t(bj) * size_t(L.nx) + size_t(bi);
    const float apex = L.dmax[a];
    if (!(apex > dminGlobal)) return;
    double mb = 0;
    for (int k = 0; k < nS; ++k) mb = std::max(mb, best[k]);
    for (const BlockOffset& o : offs) {
        if (CandidateQ(o.s, apex, dminGlobal) >= mb) break;
        const size_t b =
            size_t(Wrap(bj + o.ky, L.ny)) * size_t(L.nx) + size_t(Wrap(bi + o.kx, L.nx));
        const float top = L.dmin[b];
        if (!(top < apex)) continue;
        if (LowerSectors(o.mask, CandidateQ(o.s, apex, top), nS, best)) {
            mb = 0;
            for (int k = 0; k < nS; ++k) mb = std::max(mb, best[k]);
        }
    }
}

int TrailingZeros(int v) {
    int n = 0;
    while (v > 0 && (v & 1) == 0) {
        v >>= 1;
        ++n;
    }
    return n;
}

}  // namespace

/// Everything the adaptive generator allocates, kept between calls. Offsets depend only
/// on the size, kind and level, so they are rebuilt only when one of those changes.
struct AdaptiveWorkspace::Impl {
    std::vector<Level> levels;  ///< [1..nL] used; [0] is the field itself
    std::vector<std::vector<BlockOffset>> offs;  ///< per level
    std::vector<std::array<int, 4>> offsKey;     ///< (W, H, kind, level) of offs[l]
    TiledOffsets tiled;
    std::array<int, 3> tiledKey{-1, -1, -1};
    SearchWindows win;
    std::vector<float> ratio1;                ///< level-1 block ratios as floats
    std::vector<int64_t> nCopied, nSearched;  ///< per row
};

AdaptiveWorkspace::AdaptiveWorkspace() : impl(new Impl) {}
AdaptiveWorkspace::~AdaptiveWorkspace() { delete impl; }

ConeMap GenerateAdaptiveSectorMap(const DepthField& hf, ConeKind kind, float threshold,
                                  int levels, AdaptiveStats* stats) {
    // Maps up to 512² keep one workspace per thread (tables of a few MB): a fresh one per
    // call returned its pages to the OS and page-faulted them back every call (5x slower
    // on maps where every texel is copied), and rebuilt the size-only offset tables. A
    // nested call on the same thread (TBB work stealing inside our parallel loops) gets a
    // fresh workspace.
    thread_local AdaptiveWorkspace cached;
    thread_local bool busy = false;
    ConeMap m;
    if (busy || int64_t(hf.width) * hf.height > 512 * 512) {
        AdaptiveWorkspace ws;
        GenerateAdaptiveSectorMap(hf, kind, threshold, levels, ws, m, stats);
        return m;
    }
    busy = true;
    try {
        GenerateAdaptiveSectorMap(hf, kind, threshold, levels, cached, m, stats);
    } catch (...) {
        busy = false;
        throw;
    }
    busy = false;
    return m;
}

void GenerateAdaptiveSectorMap(const DepthField& hf, ConeKind kind, float threshold,
                               int levels, AdaptiveWorkspace& workspace, ConeMap& m,
                               AdaptiveStats* stats) {
    if (!(kind == ConeKind::Cone || kind == ConeKind::Quad || kind == ConeKind::Acm4 ||
          kind == ConeKind::Acm8))
        throw Error(ParamName("adaptive") +
                    ": applies to kinds \"cone\", \"quad\", \"acm4\", \"acm8\"; got "
                    "\"" +
                    std::string(ToString(kind)) + "\"");
    if (!(threshold >= 0.0f && threshold <= 1.0f))
        throw Error(ParamName("threshold") + ": must be a depth difference in [0, 1]");
    const float dmin = CheckedMinDepth(hf);
    const Geometry g = MakeGeometry(hf.width, hf.height);
    const int nS = SectorCount(kind);
    const int W = hf.width, H = hf.height;
    AdaptiveWorkspace::Impl& ws = workspace.Get();
    // Blocks must tile the texture evenly (exact gaps and sectors): sizes divisible by
    // 2^l.
    const int nL = std::max(0, std::min({levels, TrailingZeros(W), TrailingZeros(H)}));

    if (ws.levels.size() < size_t(nL) + 1) ws.levels.resize(size_t(nL) + 1);
    if (ws.offs.size() < size_t(nL) + 1) {
        ws.offs.resize(size_t(nL) + 1);
        ws.offsKey.resize(size_t(nL) + 1, {-1, -1, -1, -1});
    }
    std::vector<Level>& L = ws.levels;
    for (int l = 1; l <= nL; ++l) {
        Level& c = L[size_t(l)];
        // Level 0 is the field itself (min = max = depth): no copy.
        const float* fmin = l == 1 ? hf.depth.data() : L[size_t(l) - 1].dmin.data();
        const float* fmax = l == 1 ? hf.depth.data() : L[size_t(l) - 1].dmax.data();
        const int fnx = l == 1 ? W : L[size_t(l) - 1].nx;
        c.nx = (W >> l);
        c.ny = (H >> l);
        c.size = 1 << l;
        c.dmin.resize(size_t(c.nx) * size_t(c.ny));
        c.dmax.resize(c.dmin.size());
        for (int j = 0; j < c.ny; ++j)
            for (int i = 0; i < c.nx; ++i) {
                float mn = 2, mx = -1;
                for (int d = 0; d < 4; ++d) {
                    const size_t t =
                        size_t(2 * j + (d >> 1)) * size_t(fnx) + size_t(2 * i + (d & 1));
                    mn = std::min(mn, fmin[t]);
                    mx = std::max(mx, fmax[t]);
                }
                c.dmin[size_t(j) * size_t(c.nx) + size_t(i)] = mn;
                c.dmax[size_t(j) * size_t(c.nx) + size_t(i)] = mx;
            }
    }
    ws.nCopied.assign(size_t(H), 0);
    ws.nSearched.assign(size_t(H), 0);
    for (int l = nL; l >= 1; --l) {
        Level& c = L[size_t(l)];
        c.q.assign(c.dmin.size() * size_t(nS), kInfQ);
        const std::array<int, 4> key{W, H, int(kind), l};
        if (ws.offsKey[size_t(l)] != key) {
            ws.offs[size_t(l)] = MakeBlockOffsets(g, c, kind);
            ws.offsKey[size_t(l)] = key;
        }
        const std::vector<BlockOffset>& offs = ws.offs[size_t(l)];
        const Level* parent = l < nL ? &L[size_t(l) + 1] : nullptr;
        tbb::parallel_for(
            tbb::blocked_range<int>(0, c.ny), [&](const tbb::blocked_range<int>& r) {
                for (int j = r.begin(); j < r.end(); ++j)
                    for (int i = 0; i < c.nx; ++i) {
                        double* best =
                            &c.q[(size_t(j) * size_t(c.nx) + size_t(i)) * size_t(nS)];
                        if (parent) {
                            const size_t pb =
                                size_t(j / 2) * size_t(parent->nx) + size_t(i / 2);
                            std::copy_n(&parent->q[pb * size_t(nS)], nS, best);
                            if (std::abs(c.dmin[size_t(j) * size_t(c.nx) + size_t(i)] -
                                         parent->dmin[pb]) <= threshold)
                                continue;
                        }
                        BlockSearch(c, offs, dmin, i, j, nS, best);
                    }
            });
    }
    m.kind = kind;
    m.width = W;
    m.height = H;
    m.channels = nS;
    m.values.resize(size_t(W) * size_t(H) * size_t(nS));
    const Level* parent = nL >= 1 ? &L[1] : nullptr;
    // A copied texel stores its parent's ratio: convert each level-1 block once.
    if (parent) {
        ws.ratio1.resize(parent->q.size());
        for (size_t t = 0; t < parent->q.size(); ++t)
            ws.ratio1[t] = RatioFromQ(parent->q[t], g.scale);
    }
    // Offsets and window minima only when some texel is searched (dynamic maps often copy
    // all).
    bool anySearch = !parent;
    for (int j = 0; j < H && !anySearch; ++j)
        for (int i = 0; i < W; ++i) {
            const size_t pb = size_t(j / 2) * size_t(parent->nx) + size_t(i / 2);
            if (!(std::abs(hf.At(i, j) - parent->dmin[pb]) <= threshold)) {
                anySearch = true;
                break;
            }
        }
    if (anySearch) {
        const std::array<int, 3> key{W, H, int(kind)};
        if (ws.tiledKey != key) {
            ws.tiled = MakeTiledOffsets(g, kind);
            ws.tiledKey = key;
        }
        MakeSearchWindows(hf, ws.win);
    }
    const TiledOffsets& to = ws.tiled;
    const SearchWindows& win = ws.win;
    tbb::parallel_for(
        tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& r) {
            for (int j = r.begin(); j < r.end(); ++j)
                for (int i = 0; i < W; ++i) {
                    float* out =
                        &m.values[(size_t(j) * size_t(W) + size_t(i)) * size_t(nS)];
                    const float d = hf.At(i, j);
                    double best[kMaxSectors];
                    std::fill(best, best + kMaxSectors, kInfQ);
                    if (parent) {
                        const size_t pb =
                            size_t(j / 2) * size_t(parent->nx) + size_t(i / 2);
                        if (std::abs(d - parent->dmin[pb]) <= threshold) {
                            ++ws.nCopied[size_t(j)];
                            std::copy_n(&ws.ratio1[pb * size_t(nS)], nS, out);
                            continue;
                        }
                        std::copy_n(&parent->q[pb * size_t(nS)], nS, best);
                    }
                    ++ws.nSearched[size_t(j)];
                    TiledSearch(hf, to, win, dmin, i, j, d, nS, best,
                                [](int, int, const Offset&) { return true; });
                    for (int k = 0; k < nS; ++k) out[k] = RatioFromQ(best[k], g.scale);
                }
        });
    if (stats) {
        stats->nCopied = stats->nSearched = 0;
        for (int j = 0; j < H; ++j) {
            stats->nCopied += ws.nCopied[size_t(j)];
            stats->nSearched += ws.nSearched[size_t(j)];
        }
    }
}

}  // namespace reliefsim
