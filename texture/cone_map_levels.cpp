// Conservative cone ratios by depth levels and wrap-around Euclidean distance transforms
// (Felzenszwalb & Huttenlocher lower envelope): q(t) = min over levels v < d_t of
// S_v(t) / (d_t - v)^2, S_v the exact squared distance to the nearest texel with depth <= v.
#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "texture/cone_map_detail.h"

namespace reliefsim::detail {

namespace {
/// Vertical distances are stored in 16 bits (less memory traffic per level); the levels path
/// is used only for sizes below kInfDist (UseLevels).
constexpr int32_t kInfDist = 0xFFFF;
constexpr int64_t kInfS = int64_t(1) << 62;
}  // namespace

void ConservativeQByLevels(const HeightField& hf, const Geometry& g, std::vector<double>& q) {
    const int W = hf.width, H = hf.height;
    const size_t N = size_t(W) * size_t(H);
    std::vector<float> levels(hf.depth);
    std::sort(levels.begin(), levels.end());
    levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
    std::vector<uint16_t> lev(N);
    for (size_t t = 0; t < N; ++t)
        lev[t] = uint16_t(std::lower_bound(levels.begin(), levels.end(), hf.depth[t]) -
                          levels.begin());
    q.assign(N, kInfQ);
    std::vector<uint16_t> vdist(N);
    const int L = int(levels.size());
    // Levels from the deepest down: the sets shrink, so S_v(t) only grows from one level to
    // the next, and a texel whose S already gives CandidateQ(S, d_t, dmin) >= q[t] can never
    // improve again (S grows and no blocker is above dmin): it is marked done, and rows with
    // no texel left to improve skip the level.
    std::vector<uint8_t> done(N, 0);
    const double dTop = double(levels[0]);
    for (int l = L - 2; l >= 0; --l) {
        const float v = levels[size_t(l)];
        // Vertical wrap distance to the set {lev <= l}, per column; columns in blocks.
        tbb::parallel_for(tbb::blocked_range<int>(0, W, 64), [&](const tbb::blocked_range<int>& r) {
            const int i0 = r.begin(), i1 = r.end();
            const int n = i1 - i0;
            std::vector<int32_t> run(size_t(n), kInfDist);
            // Wrap: entering row 0 from above, the run is the distance from row H-1 up to the
            // column's last texel of the set; entering row H-1 from below (upward sweep), the
            // distance down to its first texel. One branch-free pass finds both.
            std::vector<int32_t> first(size_t(n), H), last(size_t(n), -1);
            for (int j = 0; j < H; ++j) {
                const uint16_t* lr = &lev[size_t(j) * size_t(W)] + i0;
                for (int i = 0; i < n; ++i) {
                    const bool in = lr[i] <= l;
                    last[size_t(i)] = in ? j : last[size_t(i)];
                    first[size_t(i)] = (in && first[size_t(i)] == H) ? j : first[size_t(i)];
                }
            }
            for (int i = 0; i < n; ++i)
                run[size_t(i)] = last[size_t(i)] < 0 ? kInfDist : H - 1 - last[size_t(i)];
            for (int j = 0; j < H; ++j) {
                const uint16_t* lr = &lev[size_t(j) * size_t(W)];
                uint16_t* out = &vdist[size_t(j) * size_t(W)];
                for (int i = i0; i < i1; ++i) {
                    const int32_t d = lr[i] <= l ? 0 : std::min(run[size_t(i - i0)] + 1, kInfDist);
                    run[size_t(i - i0)] = d;
                    out[i] = uint16_t(d);
                }
            }
            // Upward sweep.
            for (int i = 0; i < n; ++i)
                run[size_t(i)] = first[size_t(i)] >= H ? kInfDist : first[size_t(i)];
            for (int j = H - 1; j >= 0; --j) {
                const uint16_t* lr = &lev[size_t(j) * size_t(W)];
                uint16_t* out = &vdist[size_t(j) * size_t(W)];
                for (int i = i0; i < i1; ++i) {
                    const int32_t d = lr[i] <= l ? 0 : std::min(run[size_t(i - i0)] + 1, kInfDist);
                    run[size_t(i - i0)] = d;
                    out[i] = uint16_t(std::min(int32_t(out[i]), d));
                }
            }
        });
        // Row pass: lower envelope of parabolas wx*(x - p)^2 + f(p) over the wrap-extended row.
        tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& r) {
            const int ext = g.halfX;
            const int n = W + 2 * ext;
            std::vector<int> vpos(size_t(n) + 1);
            // Breakpoints as exact fractions zNum / zDen (zDen > 0): every product below stays
            // under 2^53, so the envelope is built without rounding (no ties misresolved).
            std::vector<double> zNum(size_t(n) + 2), zDen(size_t(n) + 2);
            std::vector<int64_t> fv(size_t(n) + 1);
            std::vector<double> fpv(size_t(n) + 1);  // f + wx p^2 of each envelope parabola
            const double wx = double(g.wx);
            for (int j = r.begin(); j < r.end(); ++j) {
                const size_t row = size_t(j) * size_t(W);
                bool any = false;
                // When every f is finite, S(i) <= f(i) <= fMax, so parabolas further than
                // sqrt(fMax / wx) from [0, W) never reach the envelope: shorten the wrap.
                int32_t vMax = 0;
                for (int i = 0; i < W; ++i) {
                    any |= lev[row + size_t(i)] > l && !done[row + size_t(i)];
                    vMax = std::max(vMax, int32_t(vdist[row + size_t(i)]));
                }
                if (!any) continue;
                int e0 = ext;
                if (vMax < kInfDist) {
                    const double reach = std::sqrt(double(vMax) * double(vMax) * double(g.wy) / wx);
                    e0 = std::min(ext, int(std::ceil(reach)) + 1);
                }
                int k = -1;
                for (int p = -e0; p < W + e0; ++p) {
                    // e0 <= W/2, so one adjustment wraps p (no modulo in this loop).
                    const int pw = p < 0 ? p + W : (p >= W ? p - W : p);
                    const int32_t vd = vdist[row + size_t(pw)];
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
                        if (k > 0 && num * zDen[size_t(k)] <= zNum[size_t(k)] * den) --k;
                        else break;
                    }
                    ++k;
                    vpos[size_t(k)] = p;
                    fv[size_t(k)] = f;
                    fpv[size_t(k)] = fp;
                    zNum[size_t(k)] = num;
                    zDen[size_t(k)] = den;
                }
                if (k < 0) continue;
                const int last = k;
                int e = 0;
                for (int i = 0; i < W; ++i) {
                    // advance while z[e+1] < i
                    while (e < last && zNum[size_t(e) + 1] < double(i) * zDen[size_t(e) + 1]) ++e;
                    const size_t t = row + size_t(i);
                    if (lev[t] <= l || done[t]) continue;
                    const int64_t dx = i - vpos[size_t(e)];
                    const int64_t S = dx * dx * g.wx + fv[size_t(e)];
                    // Cheap filter with a safe margin; the exact candidate is computed only
                    // when it can win, so the minimum is the brute force's.
                    const double dd = double(hf.depth[t]) - double(v);
                    if (!(double(S) < q[t] * (dd * dd) * (1.0 + 1e-12))) {
                        // The margin makes "done" certain: S / D^2 >= q despite rounding.
                        const double D = double(hf.depth[t]) - dTop;
                        if (double(S) >= q[t] * (D * D) * (1.0 + 1e-12)) done[t] = 1;
                        continue;
                    }
                    const double c = CandidateQ(S, hf.depth[t], v);
                    if (c < q[t]) q[t] = c;
                }
            }
        });
    }
}

}  // namespace reliefsim::detail
