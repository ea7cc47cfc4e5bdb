// Conservative cone ratios by depth levels and wrap-around Euclidean distance transforms
// (Felzenszwalb & Huttenlocher lower envelope): q(t) = min over levels v < d_t of
// S_v(t) / (d_t - v)^2, S_v the exact squared distance to the nearest texel with depth <=
// v.
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
}  // namespace

void ConservativeQByLevels(const HeightField& hf, const Geometry& g,
                           std::vector<double>& q, const ConeMapProgress& progressFn) {
    const int W = hf.width, H = hf.height;
    const size_t N = size_t(W) * size_t(H);
    // Distinct depths, ascending. This path sees at most a few hundred (UseLevels), so a
    // small sorted table with a last-value cache replaces sorting all N depths (that and
    // the level lookup below were ~30 ms of serial work at 1024²); many distinct values
    // fall back to the sort. Either way the table holds exactly the distinct depths.
    std::vector<float> levels;
    {
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
    }
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
    q.assign(N, kInfQ);
    std::vector<uint16_t> vdist(N);
    const int L = int(levels.size());
    // Levels from the deepest down: the sets shrink, so S_v(t) only grows from one level
    // to the next, and a texel whose S already gives CandidateQ(S, d_t, dmin) >= q[t] can
    // never improve again (S grows and no blocker is above dmin): it is marked done, and
    // rows with no texel left to improve skip the level.
    std::vector<uint8_t> done(N, 0);
    const double dTop = double(levels[0]);
    // Row-pass buffers, one set per worker thread for all levels: allocating (and
    // zeroing) them per task and level zeroed ~2 GB at 1024².
    struct RowBuffers {
        std::vector<int> vpos;
        std::vector<double> zNum, zDen, fpv;
        std::vector<int64_t> fv;
    };
    // The envelope holds at most W + 1 parabolas (positions 0..W of the cut row, see
    // below).
    const size_t nPos = size_t(W) + 2;
    tbb::enumerable_thread_specific<RowBuffers> rowBuffers([nPos] {
        RowBuffers b;
        b.vpos.resize(nPos);
        b.zNum.resize(nPos);
        b.zDen.resize(nPos);
        b.fpv.resize(nPos);
        b.fv.resize(nPos);
        return b;
    });
    // Column blocks of kColBlock: hasLevel[l * nCB + b] says whether block b holds a
    // texel at level l. Going from level l + 1 to l, the set {lev <= l} loses exactly the
    // texels at level l + 1, so in a block without such a texel every column's set, and
    // hence its vertical distances, are those of the previous level: the block is
    // skipped.
    const int nCB = (W + kColBlock - 1) / kColBlock;
    std::vector<uint8_t> hasLevel(size_t(L) * size_t(nCB), 0);
    for (size_t t = 0; t < N; ++t)
        hasLevel[size_t(lev[t]) * size_t(nCB) + (t % size_t(W)) / size_t(kColBlock)] = 1;
    // Open texels per row (lev > l and not done): a row gains the texels of level l + 1
    // when level l starts and loses the texels marked done; rows without one skip the
    // level.
    std::vector<int32_t> levelCount(size_t(L) * size_t(H), 0), nOpen(size_t(H), 0);
    tbb::parallel_for(
        tbb::blocked_range<int>(0, H, 16), [&](const tbb::blocked_range<int>& r) {
            for (int j = r.begin(); j < r.end(); ++j)
                for (int i = 0; i < W; ++i)
                    ++levelCount[size_t(lev[size_t(j) * size_t(W) + size_t(i)]) *
                                     size_t(H) +
                                 size_t(j)];
        });
    ProgressCounter progress(progressFn, L - 1);
    for (int l = L - 2; l >= 0; --l) {
        progress.Add(1);
        const float v = levels[size_t(l)];
        // Vertical wrap distance to the set {lev <= l}, per column; columns in blocks.
        tbb::parallel_for(
            tbb::blocked_range<int>(0, nCB, 1), [&](const tbb::blocked_range<int>& rb) {
                for (int cb = rb.begin(); cb < rb.end(); ++cb) {
                    if (l < L - 2 && !hasLevel[size_t(l + 1) * size_t(nCB) + size_t(cb)])
                        continue;
                    const int i0 = cb * kColBlock, i1 = std::min(W, i0 + kColBlock);
                    const int n = i1 - i0;
                    std::vector<int32_t> run(size_t(n), kInfDist);
                    // Wrap: entering row 0 from above, the run is the distance from row
                    // H-1 up to the column's last texel of the set; entering row H-1 from
                    // below (upward sweep), the distance down to its first texel. One
                    // branch-free pass finds both.
                    std::vector<int32_t> first(size_t(n), H), last(size_t(n), -1);
                    for (int j = 0; j < H; ++j) {
                        const uint16_t* lr = &lev[size_t(j) * size_t(W)] + i0;
                        for (int i = 0; i < n; ++i) {
                            const bool in = lr[i] <= l;
                            last[size_t(i)] = in ? j : last[size_t(i)];
                            first[size_t(i)] =
                                (in && first[size_t(i)] == H) ? j : first[size_t(i)];
                        }
                    }
                    for (int i = 0; i < n; ++i)
                        run[size_t(i)] =
                            last[size_t(i)] < 0 ? kInfDist : H - 1 - last[size_t(i)];
                    for (int j = 0; j < H; ++j) {
                        const uint16_t* lr = &lev[size_t(j) * size_t(W)];
                        uint16_t* out = &vdist[size_t(j) * size_t(W)];
                        for (int i = i0; i < i1; ++i) {
                            const int32_t d =
                                lr[i] <= l ? 0
                                           : std::min(run[size_t(i - i0)] + 1, kInfDist);
                            run[size_t(i - i0)] = d;
                            out[i] = uint16_t(d);
                        }
                    }
                    // Upward sweep.
                    for (int i = 0; i < n; ++i)
                        run[size_t(i)] =
                            first[size_t(i)] >= H ? kInfDist : first[size_t(i)];
                    for (int j = H - 1; j >= 0; --j) {
                        const uint16_t* lr = &lev[size_t(j) * size_t(W)];
                        uint16_t* out = &vdist[size_t(j) * size_t(W)];
                        for (int i = i0; i < i1; ++i) {
                            const int32_t d =
                                lr[i] <= l ? 0
                                           : std::min(run[size_t(i - i0)] + 1, kInfDist);
                            run[size_t(i - i0)] = d;
                            out[i] = uint16_t(std::min(int32_t(out[i]), d));
                        }
                    }
                }
            });
        // Row pass: S(i) = min over columns p of wx * dx(i, p)^2 + f(p), f = wy *
        // vdist^2, dx the wrap distance, by the lower envelope of the parabolas. The wrap
        // needs no extended row: the row is cut at a column c of minimal f and unrolled
        // to positions x = 0..W (texel c + x mod W; x = W is c again). For a query x and
        // a column p, either the linear distance |x - p| is the wrap distance (the term
        // is there), or the shorter way round passes the cut, so the query is at least as
        // close to x = 0 or x = W, whose f is minimal: that term is no larger. Linear
        // distances are never below wrap distances, so the linear envelope gives exactly
        // the wrapped S (about half the parabolas of the former extension by up to W/2 on
        // both sides).
        tbb::parallel_for(
            tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& r) {
                RowBuffers& buf = rowBuffers.local();
                std::vector<int>& vpos = buf.vpos;
                // Breakpoints as exact fractions zNum / zDen (zDen > 0). Positions are in
                // [0, W], so every product below is at most 2 wx W (wx W^2 + wy H^2 /
                // 4): 2.5 W^3 < 2^53 for square maps (the former extended row reached 1.5
                // W: 10 W^3), and the envelope is built without rounding (no ties
                // misresolved). Large coprime W and H make wx, wy large and can exceed
                // 2^53 (as before). Entries are written before they are read (index <=
                // k), so reuse across rows, levels and tasks is safe.
                std::vector<double>& zNum = buf.zNum;
                std::vector<double>& zDen = buf.zDen;
                std::vector<int64_t>& fv = buf.fv;
                std::vector<double>& fpv =
                    buf.fpv;  // f + wx p^2 of each envelope parabola
                const double wx = double(g.wx);
                for (int j = r.begin(); j < r.end(); ++j) {
                    nOpen[size_t(j)] += levelCount[size_t(l + 1) * size_t(H) + size_t(j)];
                    if (nOpen[size_t(j)] == 0) continue;
                    const size_t row = size_t(j) * size_t(W);
                    const uint16_t* vr = &vdist[row];
                    uint16_t vMin = 0xFFFF;
                    for (int i = 0; i < W; ++i) vMin = std::min(vMin, vr[i]);
                    if (vMin >= kInfDist) continue;  // no texel of the set in any column
                    int c = 0;
                    while (vr[c] != vMin) ++c;
                    // Position x is texel x + c (x < W - c) or x + c - W; one loop per
                    // part.
                    int k = -1;
                    auto push = [&](int p0, int p1, int off) {
                        for (int p = p0; p < p1; ++p) {
                            const int32_t vd = vr[p + off];
                            if (vd >= kInfDist) continue;
                            const int64_t f = int64_t(vd) * vd * g.wy;
                            const double fp = double(f) + wx * double(p) * double(p);
                            double num = 0, den = 1;
                            while (k >= 0) {
                                const int vq = vpos[size_t(k)];
                                const double fq = fpv[size_t(k)];
                                num = fp - fq;
                                den = 2.0 * wx * double(p - vq);
                                // pop while s <= z[k] (z[0] = -inf)
                                if (k > 0 &&
                                    num * zDen[size_t(k)] <= zNum[size_t(k)] * den)
                                    --k;
                                else
                                    break;
                            }
                            ++k;
                            vpos[size_t(k)] = p;
                            fv[size_t(k)] = f;
                            fpv[size_t(k)] = fp;
                            zNum[size_t(k)] = num;
                            zDen[size_t(k)] = den;
                        }
                    };
                    push(0, W - c, c);
                    push(W - c, W + 1, c - W);
                    const int last = k;
                    int e = 0;
                    int nDone = 0;
                    auto query = [&](int x0, int x1, int off) {
                        for (int x = x0; x < x1; ++x) {
                            // advance while z[e+1] < x
                            while (e < last &&
                                   zNum[size_t(e) + 1] < double(x) * zDen[size_t(e) + 1])
                                ++e;
                            const size_t t = row + size_t(x + off);
                            if (lev[t] <= l || done[t]) continue;
                            const int64_t dx = x - vpos[size_t(e)];
                            const int64_t S = dx * dx * g.wx + fv[size_t(e)];
                            // Cheap filter with a safe margin; the exact candidate is
                            // computed only when it can win, so the minimum is the brute
                            // force's.
                            const double d = double(hf.depth[t]);
                            const double dd = d - double(v);
                            if (!(double(S) < q[t] * (dd * dd) * (1.0 + 1e-12))) {
                                // The margin makes "done" certain: S / D^2 >= q despite
                                // rounding.
                                const double D = d - dTop;
                                if (double(S) >= q[t] * (D * D) * (1.0 + 1e-12)) {
                                    done[t] = 1;
                                    ++nDone;
                                }
                                continue;
                            }
                            const double cq = CandidateQ(S, hf.depth[t], v);
                            if (cq < q[t]) q[t] = cq;
                        }
                    };
                    query(0, W - c, c);
                    query(W - c, W, c - W);
                    nOpen[size_t(j)] -= nDone;
                }
            });
    }
}

}  // namespace reliefsim::detail
