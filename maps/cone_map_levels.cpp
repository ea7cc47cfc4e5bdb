// Conservative cone ratios by depth levels and wrap-around Euclidean distance transforms
// (Felzenszwalb & Huttenlocher lower envelope): q(t) = min over levels v < d_t of
// S_v(t) / (d_t - v)^2, S_v the exact squared distance to the nearest texel with depth <=
// v.
//
// Stages: DistinctDepths and LevelIndices set up the levels; then, per level from the
// deepest down, VerticalPass (column distances to the set) and RowPass (the lower
// envelope of each row, queried for the texels still open). Why each shortcut is exact:
// docs/cone_maps.md, section "Proofs for the levels generator".
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "maps/cone_map_detail.h"

namespace reliefsim::detail {

namespace {
/// Vertical distances are stored in 16 bits (less memory traffic per level); the levels
/// path is used only for sizes below kInfDist (UseLevels).
constexpr int32_t kInfDist = 0xFFFF;
constexpr int64_t kInfS = int64_t(1) << 62;
/// Columns per block of the vertical pass.
constexpr int kColBlock = 32;

/// Distinct depths, ascending. This path sees at most a few hundred (UseLevels), so a
/// small sorted table with a last-value cache replaces sorting all N depths (that and the
/// level lookup were ~30 ms of serial work at 1024²); many distinct values fall back to
/// the sort. Either way the table holds exactly the distinct depths.
std::vector<float> DistinctDepths(const DepthField& hf) {
    const size_t N = hf.depth.size();
    std::vector<float> levels;
    float last = std::numeric_limits<float>::quiet_NaN();
    for (size_t t = 0; t < N && levels.size() <= 4096; ++t) {
        const float d = hf.depth[t];
        if (d == last) continue;
        last = d;
        const auto it = std::lower_bound(levels.begin(), levels.end(), d);
        if (it == levels.end() || *it != d) levels.insert(it, d);
    }
    if (levels.size() > 4096) {
        levels = hf.depth;
        std::sort(levels.begin(), levels.end());
        levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
    }
    return levels;
}

/// Level index of every texel: the position of its depth in `levels` (in parallel, with
/// a last-value cache).
std::vector<uint16_t> LevelIndices(const DepthField& hf,
                                   const std::vector<float>& levels) {
    const size_t N = hf.depth.size();
    std::vector<uint16_t> lev(N);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, N, size_t(1) << 14),
        [&](const tbb::blocked_range<size_t>& r) {
            float last = std::numeric_limits<float>::quiet_NaN();
            uint16_t lastLev = 0;
            for (size_t t = r.begin(); t < r.end(); ++t) {
                const float d = hf.depth[t];
                if (!(d == last)) {
                    last = d;
                    lastLev = uint16_t(std::lower_bound(levels.begin(), levels.end(), d) -
                                       levels.begin());
                }
                lev[t] = lastLev;
            }
        });
    return lev;
}

/// Row-pass buffers, one set per worker thread for all levels: allocating (and zeroing)
/// them per task and level zeroed ~2 GB at 1024². Entries are written before they are
/// read (index <= k), so reuse across rows, levels and tasks is safe.
struct RowBuffers {
    std::vector<int> vpos;                ///< position of each envelope parabola
    std::vector<double> zNum, zDen, fpv;  ///< breakpoints zNum / zDen; f + wx p^2
    std::vector<int64_t> fv;              ///< f = wy vdist^2 of each parabola
};

/// The state of the sweep over levels, shared by its stages.
struct LevelSweep {
    const DepthField& hf;
    const Geometry& g;
    int W = 0, H = 0;
    int L = 0;                        ///< number of levels
    int nCB = 0;                      ///< column blocks of kColBlock
    std::vector<float> levels;        ///< distinct depths, ascending
    std::vector<uint16_t> lev;        ///< level index per texel
    std::vector<uint16_t> vdist;      ///< vertical wrap distance to the set {lev <= l}
    std::vector<uint8_t> done;        ///< texels whose q can no longer improve
    std::vector<uint8_t> hasLevel;    ///< [l * nCB + b]: block b holds a texel at level l
    std::vector<int32_t> levelCount;  ///< [l * H + j]: texels of row j at level l
    std::vector<int32_t> nOpen;       ///< per row: texels with lev > l and not done
    double dTop = 0;                  ///< the shallowest depth, levels[0]
    LevelSweep(const DepthField& hf, const Geometry& g)
        : hf(hf), g(g), W(hf.width), H(hf.height) {}
};

/// hasLevel: which column blocks hold a texel of each level (VerticalPass skips the
/// others; proof: docs/cone_maps.md, section "Skipping column blocks").
void MarkBlocksHoldingLevels(LevelSweep& s) {
    const size_t N = s.lev.size();
    s.hasLevel.assign(size_t(s.L) * size_t(s.nCB), 0);
    for (size_t t = 0; t < N; ++t)
        s.hasLevel[size_t(s.lev[t]) * size_t(s.nCB) +
                   (t % size_t(s.W)) / size_t(kColBlock)] = 1;
}

/// levelCount: texels per level and row. A row gains the texels of level l + 1 when level
/// l starts and loses the texels marked done; rows without an open texel skip the level.
void CountTexelsPerLevelAndRow(LevelSweep& s) {
    const int W = s.W, H = s.H;
    s.levelCount.assign(size_t(s.L) * size_t(H), 0);
    s.nOpen.assign(size_t(H), 0);
    tbb::parallel_for(
        tbb::blocked_range<int>(0, H, 16), [&](const tbb::blocked_range<int>& r) {
            for (int j = r.begin(); j < r.end(); ++j)
                for (int i = 0; i < W; ++i)
                    ++s.levelCount[size_t(s.lev[size_t(j) * size_t(W) + size_t(i)]) *
                                       size_t(H) +
                                   size_t(j)];
        });
}

/// Vertical wrap distance to the set {lev <= l} of the columns [i0, i1), into vdist: a
/// downward and an upward sweep, each entering the column with the distance across the
/// wrap. Entering row 0 from above, the run is the distance from row H-1 up to the
/// column's last texel of the set; entering row H-1 from below, the distance down to its
/// first texel. One branch-free pass finds both.
void VerticalDistancesOfBlock(LevelSweep& s, int l, int i0, int i1) {
    const int W = s.W, H = s.H;
    const int n = i1 - i0;
    std::vector<int32_t> run(size_t(n), kInfDist);
    std::vector<int32_t> first(size_t(n), H), last(size_t(n), -1);
    for (int j = 0; j < H; ++j) {
        const uint16_t* lr = &s.lev[size_t(j) * size_t(W)] + i0;
        for (int i = 0; i < n; ++i) {
            const bool in = lr[i] <= l;
            last[size_t(i)] = in ? j : last[size_t(i)];
            first[size_t(i)] = (in && first[size_t(i)] == H) ? j : first[size_t(i)];
        }
    }
    for (int i = 0; i < n; ++i)
        run[size_t(i)] = last[size_t(i)] < 0 ? kInfDist : H - 1 - last[size_t(i)];
    for (int j = 0; j < H; ++j) {
        const uint16_t* lr = &s.lev[size_t(j) * size_t(W)];
        uint16_t* out = &s.vdist[size_t(j) * size_t(W)];
        for (int i = i0; i < i1; ++i) {
            const int32_t d =
                lr[i] <= l ? 0 : std::min(run[size_t(i - i0)] + 1, kInfDist);
            run[size_t(i - i0)] = d;
            out[i] = uint16_t(d);
        }
    }
    // Upward sweep.
    for (int i = 0; i < n; ++i)
        run[size_t(i)] = first[size_t(i)] >= H ? kInfDist : first[size_t(i)];
    for (int j = H - 1; j >= 0; --j) {
        const uint16_t* lr = &s.lev[size_t(j) * size_t(W)];
        uint16_t* out = &s.vdist[size_t(j) * size_t(W)];
        for (int i = i0; i < i1; ++i) {
            const int32_t d =
                lr[i] <= l ? 0 : std::min(run[size_t(i - i0)] + 1, kInfDist);
            run[size_t(i - i0)] = d;
            out[i] = uint16_t(std::min(int32_t(out[i]), d));
        }
    }
}

/// Vertical pass of level l: the column distances of every block whose set changed from
/// level l + 1 (the first level processed computes every block).
void VerticalPass(LevelSweep& s, int l) {
    tbb::parallel_for(
        tbb::blocked_range<int>(0, s.nCB, 1), [&](const tbb::blocked_range<int>& rb) {
            for (int cb = rb.begin(); cb < rb.end(); ++cb) {
                if (l < s.L - 2 &&
                    !s.hasLevel[size_t(l + 1) * size_t(s.nCB) + size_t(cb)])
                    continue;
                const int i0 = cb * kColBlock, i1 = std::min(s.W, i0 + kColBlock);
                VerticalDistancesOfBlock(s, l, i0, i1);
            }
        });
}

/// Pushes the parabolas of positions [p0, p1) (texel p + off of the row `vr`) onto the
/// lower envelope buf[0..k], popping those they hide; k is the index of the top one (-1:
/// empty). Breakpoints are exact fractions zNum / zDen (zDen > 0), compared without
/// rounding (proof: docs/cone_maps.md, section "Exact breakpoints").
RS_INLINE void PushParabolas(const uint16_t* vr, int p0, int p1, int off, double wx,
                             int64_t wy, RowBuffers& buf, int& k) {
    for (int p = p0; p < p1; ++p) {
        const int32_t vd = vr[p + off];
        if (vd >= kInfDist) continue;
        const int64_t f = int64_t(vd) * vd * wy;
        const double fp = double(f) + wx * double(p) * double(p);
        double num = 0, den = 1;
        while (k >= 0) {
            const int vq = buf.vpos[size_t(k)];
            const double fq = buf.fpv[size_t(k)];
            num = fp - fq;
            den = 2.0 * wx * double(p - vq);
            // pop while s <= z[k] (z[0] = -inf)
            if (k > 0 && num * buf.zDen[size_t(k)] <= buf.zNum[size_t(k)] * den)
                --k;
            else
                break;
        }
        ++k;
        buf.vpos[size_t(k)] = p;
        buf.fv[size_t(k)] = f;
        buf.fpv[size_t(k)] = fp;
        buf.zNum[size_t(k)] = num;
        buf.zDen[size_t(k)] = den;
    }
}

/// Queries the envelope buf[0..last] at positions [x0, x1) (texel x + off of row `row`),
/// lowering q of every open texel of the row and marking done the texels that can no
/// longer improve; e is the current parabola (advanced monotonically), nDone counts the
/// texels marked. The cheap filter has a safe margin; the exact candidate is computed
/// only when it can win, so the minimum is the brute force's (proof: docs/cone_maps.md,
/// section "Texels marked done").
RS_INLINE void QueryEnvelope(LevelSweep& s, std::vector<double>& q, int l, float v,
                             size_t row, int x0, int x1, int off, const RowBuffers& buf,
                             int last, int& e, int& nDone) {
    for (int x = x0; x < x1; ++x) {
        // advance while z[e+1] < x
        while (e < last && buf.zNum[size_t(e) + 1] < double(x) * buf.zDen[size_t(e) + 1])
            ++e;
        const size_t t = row + size_t(x + off);
        if (s.lev[t] <= l || s.done[t]) continue;
        const int64_t dx = x - buf.vpos[size_t(e)];
        const int64_t S = dx * dx * s.g.wx + buf.fv[size_t(e)];
        const double d = double(s.hf.depth[t]);
        const double dd = d - double(v);
        if (!(double(S) < q[t] * (dd * dd) * (1.0 + 1e-12))) {
            // The margin makes "done" certain: S / D^2 >= q despite rounding.
            const double D = d - s.dTop;
            if (double(S) >= q[t] * (D * D) * (1.0 + 1e-12)) {
                s.done[t] = 1;
                ++nDone;
            }
            continue;
        }
        const double cq = CandidateQ(S, s.hf.depth[t], v);
        if (cq < q[t]) q[t] = cq;
    }
}

/// Row j of level l: S(i) = min over columns p of wx * dx(i, p)^2 + f(p), f = wy *
/// vdist^2, dx the wrap distance, by the lower envelope of the parabolas. The row is cut
/// at a column c of minimal f and unrolled to positions x = 0..W (texel c + x mod W; x =
/// W is c again), one loop per contiguous part; the linear envelope of the unrolled row
/// is exactly the wrapped S (proof: docs/cone_maps.md, section "Wrap by cutting the
/// row").
void RowEnvelope(LevelSweep& s, std::vector<double>& q, int l, float v, int j,
                 RowBuffers& buf) {
    const int W = s.W, H = s.H;
    s.nOpen[size_t(j)] += s.levelCount[size_t(l + 1) * size_t(H) + size_t(j)];
    if (s.nOpen[size_t(j)] == 0) return;
    const size_t row = size_t(j) * size_t(W);
    const uint16_t* vr = &s.vdist[row];
    uint16_t vMin = 0xFFFF;
    for (int i = 0; i < W; ++i) vMin = std::min(vMin, vr[i]);
    if (vMin >= kInfDist) return;  // no texel of the set in any column
    int c = 0;
    while (vr[c] != vMin) ++c;
    // Position x is texel x + c (x < W - c) or x + c - W.
    const double wx = double(s.g.wx);
    int k = -1;
    PushParabolas(vr, 0, W - c, c, wx, s.g.wy, buf, k);
    PushParabolas(vr, W - c, W + 1, c - W, wx, s.g.wy, buf, k);
    const int last = k;
    int e = 0;
    int nDone = 0;
    QueryEnvelope(s, q, l, v, row, 0, W - c, c, buf, last, e, nDone);
    QueryEnvelope(s, q, l, v, row, W - c, W, c - W, buf, last, e, nDone);
    s.nOpen[size_t(j)] -= nDone;
}

/// Row pass of level l: RowEnvelope of every row, with the worker thread's buffers.
void RowPass(LevelSweep& s, std::vector<double>& q, int l,
             tbb::enumerable_thread_specific<RowBuffers>& rowBuffers) {
    const float v = s.levels[size_t(l)];
    tbb::parallel_for(tbb::blocked_range<int>(0, s.H, 8),
                      [&](const tbb::blocked_range<int>& r) {
                          RowBuffers& buf = rowBuffers.local();
                          for (int j = r.begin(); j < r.end(); ++j)
                              RowEnvelope(s, q, l, v, j, buf);
                      });
}

}  // namespace

void ConservativeQByLevels(const DepthField& hf, const Geometry& g,
                           std::vector<double>& q, const ConeMapProgress& progressFn) {
    LevelSweep s(hf, g);
    const size_t N = size_t(s.W) * size_t(s.H);
    s.levels = DistinctDepths(hf);
    s.lev = LevelIndices(hf, s.levels);
    q.assign(N, kInfQ);
    s.vdist.resize(N);
    s.L = int(s.levels.size());
    // Levels from the deepest down: the sets shrink, so S_v(t) only grows from one level
    // to the next, and a texel that can never improve again is marked done (proof:
    // docs/cone_maps.md, section "Texels marked done").
    s.done.assign(N, 0);
    s.dTop = double(s.levels[0]);
    // The envelope holds at most W + 1 parabolas (positions 0..W of the cut row).
    const size_t nPos = size_t(s.W) + 2;
    tbb::enumerable_thread_specific<RowBuffers> rowBuffers([nPos] {
        RowBuffers b;
        b.vpos.resize(nPos);
        b.zNum.resize(nPos);
        b.zDen.resize(nPos);
        b.fpv.resize(nPos);
        b.fv.resize(nPos);
        return b;
    });
    s.nCB = (s.W + kColBlock - 1) / kColBlock;
    MarkBlocksHoldingLevels(s);
    CountTexelsPerLevelAndRow(s);
    ProgressCounter progress(progressFn, s.L - 1);
    for (int l = s.L - 2; l >= 0; --l) {
        progress.Add(1);
        VerticalPass(s, l);
        RowPass(s, q, l, rowBuffers);
    }
}

}  // namespace reliefsim::detail
