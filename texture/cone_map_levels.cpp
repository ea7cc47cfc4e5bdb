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
constexpr int32_t kInfDist = 1 << 29;
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
    std::vector<int32_t> vdist(N);
    const int L = int(levels.size());
    for (int l = 0; l + 1 < L; ++l) {
        const float v = levels[size_t(l)];
        // Vertical wrap distance to the set {lev <= l}, per column; columns in blocks.
        tbb::parallel_for(tbb::blocked_range<int>(0, W, 64), [&](const tbb::blocked_range<int>& r) {
            const int i0 = r.begin(), i1 = r.end();
            std::vector<int32_t> run(size_t(i1 - i0), kInfDist);
            for (int pass = 0; pass < 2; ++pass)
                for (int j = 0; j < H; ++j) {
                    const uint16_t* lr = &lev[size_t(j) * size_t(W)];
                    int32_t* out = &vdist[size_t(j) * size_t(W)];
                    for (int i = i0; i < i1; ++i) {
                        int32_t d = lr[i] <= l ? 0 : std::min(run[size_t(i - i0)] + 1, kInfDist);
                        run[size_t(i - i0)] = d;
                        if (pass == 1) out[i] = d;
                    }
                }
            std::fill(run.begin(), run.end(), kInfDist);
            for (int pass = 0; pass < 2; ++pass)
                for (int j = H - 1; j >= 0; --j) {
                    const uint16_t* lr = &lev[size_t(j) * size_t(W)];
                    int32_t* out = &vdist[size_t(j) * size_t(W)];
                    for (int i = i0; i < i1; ++i) {
                        int32_t d = lr[i] <= l ? 0 : std::min(run[size_t(i - i0)] + 1, kInfDist);
                        run[size_t(i - i0)] = d;
                        if (pass == 1) out[i] = std::min(out[i], d);
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
            const double wx = double(g.wx);
            for (int j = r.begin(); j < r.end(); ++j) {
                const size_t row = size_t(j) * size_t(W);
                bool any = false;
                for (int i = 0; i < W; ++i) any |= lev[row + size_t(i)] > l;
                if (!any) continue;
                // When every f is finite, S(i) <= f(i) <= fMax, so parabolas further than
                // sqrt(fMax / wx) from [0, W) never reach the envelope: shorten the wrap.
                int32_t vMax = 0;
                for (int i = 0; i < W; ++i) vMax = std::max(vMax, vdist[row + size_t(i)]);
                int e0 = ext;
                if (vMax < kInfDist) {
                    const double reach = std::sqrt(double(vMax) * double(vMax) * double(g.wy) / wx);
                    e0 = std::min(ext, int(std::ceil(reach)) + 1);
                }
                int k = -1;
                for (int p = -e0; p < W + e0; ++p) {
                    const int32_t vd = vdist[row + size_t(Wrap(p, W))];
                    if (vd >= kInfDist) continue;
                    const int64_t f = int64_t(vd) * vd * g.wy;
                    const double fp = double(f) + wx * double(p) * double(p);
                    double num = 0, den = 1;
                    while (k >= 0) {
                        const int vq = vpos[size_t(k)];
                        const double fq = double(fv[size_t(k)]) + wx * double(vq) * double(vq);
                        num = fp - fq;
                        den = 2.0 * wx * double(p - vq);
                        // pop while s <= z[k] (z[0] = -inf)
                        if (k > 0 && num * zDen[size_t(k)] <= zNum[size_t(k)] * den) --k;
                        else break;
                    }
                    ++k;
                    vpos[size_t(k)] = p;
                    fv[size_t(k)] = f;
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
                    if (lev[t] <= l) continue;
                    const int64_t dx = i - vpos[size_t(e)];
                    const int64_t S = dx * dx * g.wx + fv[size_t(e)];
                    // Cheap filter with a safe margin; the exact candidate is computed only
                    // when it can win, so the minimum is the brute force's.
                    const double dd = double(hf.depth[t]) - double(v);
                    if (!(double(S) < q[t] * (dd * dd) * (1.0 + 1e-12))) continue;
                    const double c = CandidateQ(S, hf.depth[t], v);
                    if (c < q[t]) q[t] = c;
                }
            }
        });
    }
}

}  // namespace reliefsim::detail
