// Cone-family generators: fast exact versions (levels + distance transforms, tiled pruned
// searches), their brute-force oracles, the relaxed Listing 18-2 definition and adaptive ACM.
#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "texture/cone_map.h"
#include "texture/cone_map_detail.h"

namespace reliefsim {

namespace detail {

namespace {

/// Nearest-texel index of a float texel coordinate f = u * n, wrapped: the listing's point
/// sampling with repeat. Same result as fmod on the float (exact) for every f; the integer path
/// is only taken where the conversion cannot overflow.
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

RS_INLINE float NearestWrap(const HeightField& hf, float u, float v) {
    const int i = WrapFloorIndex(u * float(hf.width), hf.width);
    const int j = WrapFloorIndex(v * float(hf.height), hf.height);
    return hf.depth[size_t(j) * size_t(hf.width) + size_t(i)];
}

/// n_z of the cone side normal from a ratio r: r / sqrt(1 + r^2); 1 for an unbounded cone.
float ConeNormalFromRatio(double r) {
    if (!(r < double(kConeRatioCap))) return 1.0f;
    return RoundDownStrict(r / std::sqrt(1.0 + r * r));
}

template <class F>
void ForEachRow(int H, F&& f) {
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 1), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j < r.end(); ++j) f(j);
    });
}

bool UseLevels(const HeightField& hf) {
    // The levels path stores vertical distances in 16 bits.
    if (hf.height >= 0xFFFF || hf.width >= 0xFFFF) return false;
    if (!hf.depth8.empty()) return true;
    std::vector<float> v(hf.depth);
    std::sort(v.begin(), v.end());
    return std::unique(v.begin(), v.end()) - v.begin() <= 300;
}

}  // namespace

float RelaxedPairRatio(const HeightField& hf, int ti, int tj, int dx, int dy, int steps,
                       float best) {
    const float W = float(hf.width), H = float(hf.height);
    const float sx = (float(ti) + 0.5f) / W, sy = (float(tj) + 0.5f) / H;
    const float dstx = sx + float(dx) / W, dsty = sy + float(dy) / H;
    const float dstz = NearestWrap(hf, dstx, dsty);
    if (!(dstz > 0.0f)) return std::numeric_limits<float>::infinity();  // NaN in the listing
    const float src = hf.At(ti, tj);
    // Exit point deeper than the source: the march only goes deeper (step z >= 0), ratio 1.
    if (!(dstz < src)) return 1.0f;
    float vx = dstx - sx, vy = dsty - sy, vz = dstz;
    // Early out, provably exact (no margin): every float operation below is monotone, the
    // march moves away from the source in x and y (the step has the sign of vx, vy) and down
    // in z (pz >= dstz), so |ex| >= |vx|, |ey| >= |vy| and 0 < src - pz <= src - dstz, hence
    // the listing's float ratio is >= this float bound, or it is 1 (pz >= src).
    // (best = +inf, the brute force's default, never prunes.)
    if (best < std::numeric_limits<float>::infinity()) {
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
    const float fs = float(steps);
    const float stx = vx / fs, sty = vy / fs, stz = vz / fs;
    float px = dstx + stx, py = dsty + sty, pz = dstz + stz;
    // The same monotonicity bounds the ratio by the current point during the march: the
    // exit point lies further out and deeper, so once the current point's ratio reaches
    // `best` (or pz reaches src: ratio 1) the result can no longer lower the minimum.
    const bool prune = best < std::numeric_limits<float>::infinity();
    if (pz >= src) return 1.0f;
    for (int i = 1; i < steps; ++i) {
        if (NearestWrap(hf, px, py) <= pz) {
            px += stx;
            py += sty;
            pz += stz;
            if (pz >= src) return 1.0f;
            if (prune) {
                // fl(sqrt(cx^2 + cy^2) / (src - pz)) >= best, tested without sqrt or division:
                // in double the squares, the sum and (src - pz)^2 are exact or within 2^-50,
                // and the 2^-20 factor exceeds the float rounding of that quotient (< 2^-22),
                // so this implies the float bound >= best.
                const double cx = double(px - sx), cy = double(py - sy);
                const double den = double(src - pz);
                if (cx * cx + cy * cy >= double(best) * double(best) * den * den * (1.0 + 0x1p-20))
                    return best;
            }
        } else {
            break;  // the listing keeps sampling the same point from here on: same result
        }
    }
    const float ex = px - sx, ey = py - sy;
    return std::sqrt(ex * ex + ey * ey) / (src - pz);
}

double RelaxedTileLowerBound(int64_t minS, double scale, float src, float dminTile) {
    // |vx - dx/W| <= 3 * 2^-24 (three roundings of values below 2 in magnitude), so the float
    // |v| >= uv distance - 2^-21 (sqrt 2 * 3 * 2^-24 < 2^-21); the float sqrt, products, sum,
    // difference and division lose at most 2^-22 relatively. The slack 2^-20 used here also
    // covers the double rounding of this expression.
    const double dist = std::sqrt(double(minS)) / scale - 0x1p-20;
    if (!(dist > 0)) return 0;
    return dist * (1.0 - 0x1p-20) / ((double(src) - double(dminTile)) * (1.0 + 0x1p-20));
}

}  // namespace detail

namespace {

using namespace detail;

enum class Mode { Fast, Brute, Plain };

/// Apex depth of stacked cone k of K: d * (K - k) / K (k = 0: the surface point).
float StackedApex(float d, int k, int K) { return d * (float(K - k) / float(K)); }

ConeMap MakeMap(const HeightField& hf, ConeKind kind, int channels) {
    ConeMap m;
    m.kind = kind;
    m.width = hf.width;
    m.height = hf.height;
    m.channels = channels;
    m.values.assign(size_t(hf.width) * size_t(hf.height) * size_t(channels), 0.0f);
    return m;
}

/// Conservative / sector / relaxed-exact / stacked: q per texel and channel.
ConeMap SearchMap(const HeightField& hf, ConeKind kind, const ConeMapParams& p, Mode mode) {
    const float dmin = CheckedMinDepth(hf);
    const Geometry g = MakeGeometry(hf.width, hf.height);
    const ConeKind sectors = (kind == ConeKind::Quad || kind == ConeKind::Acm4 ||
                              kind == ConeKind::Acm8)
                                 ? kind
                                 : ConeKind::Cone;
    const int nS = SectorCount(sectors);
    const int C = kind == ConeKind::Stacked ? p.stackedCount : nS;
    const bool limiting = kind == ConeKind::RelaxedExact;
    const ConeKind outKind = kind;
    ConeMap m = MakeMap(hf, outKind, C);
    const int W = hf.width;

    if (mode == Mode::Fast && (kind == ConeKind::Cone || kind == ConeKind::ConeNormal) &&
        UseLevels(hf)) {
        std::vector<double> q;
        ConservativeQByLevels(hf, g, q);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, q.size(), size_t(1) << 14),
                          [&](const tbb::blocked_range<size_t>& r) {
            for (size_t t = r.begin(); t < r.end(); ++t)
                m.values[t] = kind == ConeKind::ConeNormal
                                  ? ConeNormalFromRatio(std::sqrt(q[t]) / g.scale)
                                  : RatioFromQ(q[t], g.scale);
        });
        return m;
    }

    TiledOffsets to;
    std::vector<Offset> offs;
    std::vector<float> win;
    if (mode == Mode::Brute) offs = MakeOffsets(g, sectors);
    else {
        to = MakeTiledOffsets(g, sectors);
        win = WindowMin(hf);
    }
    auto accept = [&](int bx, int by, const Offset& o) {
        return !limiting || IsLimiting(hf, bx, by, o.dx, o.dy);
    };
    ForEachRow(hf.height, [&](int j) {
        for (int i = 0; i < W; ++i) {
            const float d = hf.At(i, j);
            double best[kMaxSectors * 2];
            for (int c = 0; c < C; ++c) {
                const int nSearch = kind == ConeKind::Stacked ? 1 : nS;
                const float apex = kind == ConeKind::Stacked ? StackedApex(d, c, C) : d;
                if (kind != ConeKind::Stacked && c > 0) break;
                std::fill(best, best + kMaxSectors * 2, kInfQ);
                if (mode == Mode::Brute) BruteSearch(hf, offs, i, j, apex, nSearch, best, accept);
                else TiledSearch(hf, to, win, dmin, i, j, apex, nSearch, best, accept);
                float* out = &m.values[(size_t(j) * size_t(W) + size_t(i)) * size_t(C)];
                if (kind == ConeKind::Stacked) out[c] = RatioFromQ(best[0], g.scale);
                else if (kind == ConeKind::ConeNormal)
                    out[0] = ConeNormalFromRatio(std::sqrt(best[0]) / g.scale);
                else
                    for (int k = 0; k < nS; ++k) out[k] = RatioFromQ(best[k], g.scale);
            }
        }
    });
    return m;
}

/// Listing 18-1/18-2 relaxed ratios (float arithmetic, cap 1 as in the listing).
ConeMap RelaxedMap(const HeightField& hf, const ConeMapParams& p, Mode mode, bool normal) {
    const float dmin = CheckedMinDepth(hf);
    if (hf.width > (1 << 20) || hf.height > (1 << 20))
        throw Error("height map \"" + hf.name + "\": " + std::to_string(hf.width) + "x" +
                    std::to_string(hf.height) +
                    " too large for the relaxed cone map; expected at most 2^20 texels a side "
                    "(the float error bounds of its pruning assume it)");
    const Geometry g = MakeGeometry(hf.width, hf.height);
    ConeMap m = MakeMap(hf, normal ? ConeKind::ConeNormal : ConeKind::Relaxed, 1);
    const int W = hf.width, H = hf.height;
    TiledOffsets to;
    std::vector<Offset> offs;
    std::vector<float> win;
    if (mode == Mode::Brute) offs = MakeOffsets(g, ConeKind::Cone);
    else {
        to = MakeTiledOffsets(g, ConeKind::Cone);
        win = WindowMin(hf);
    }
    // distLo[o] * (1 / (d - b)) is below RelaxedTileLowerBound(offset o, d, b) by a margin
    // that covers the double rounding of the product compared against it.
    std::vector<double> distLo;
    if (mode != Mode::Brute) {
        distLo.resize(to.offsets.size());
        for (size_t o = 0; o < to.offsets.size(); ++o)
            distLo[o] = std::max(0.0, std::sqrt(double(to.offsets[o].s)) / g.scale - 0x1p-20) *
                        (1.0 - 0x1p-19);
    }
    // Pruning is exact (RelaxedPairRatio's float bound, and RelaxedTileLowerBound below it
    // for whole tiles): a pair is skipped only when its listing ratio provably cannot lower
    // the running minimum; ties do not change it either (strict "<" as in the listing).
    ForEachRow(H, [&](int j) {
        for (int i = 0; i < W; ++i) {
            const float d = hf.At(i, j);
            float best = 1.0f;
            if (mode == Mode::Brute) {
                for (const Offset& o : offs) {
                    const float r = RelaxedPairRatio(hf, i, j, o.dx, o.dy, p.searchSteps);
                    if (best > r) best = r;
                }
            } else if (d > dmin) {
                for (const OffsetTile& t : to.tiles) {
                    if (RelaxedTileLowerBound(t.minS, g.scale, d, dmin) >= double(best)) break;
                    const float wmin =
                        win[size_t(Wrap(j + t.oy, H)) * size_t(W) + size_t(Wrap(i + t.ox, W))];
                    if (!(wmin < d)) continue;
                    if (RelaxedTileLowerBound(t.minS, g.scale, d, wmin) >= double(best)) continue;
                    for (int o = t.begin; o < t.end; ++o) {
                        const Offset& off = to.offsets[size_t(o)];
                        // The listing samples exactly this texel as the destination (its
                        // float texel coordinate is within W * 2^-22 < 1/2 of the centre),
                        // so RelaxedTileLowerBound with this texel's depth bounds the pair.
                        const float b = hf.depth[size_t(Wrap(j + off.dy, H)) * size_t(W) +
                                                 size_t(Wrap(i + off.dx, W))];
                        if (!(b < d) || distLo[size_t(o)] >= double(best) * (double(d) - double(b)))
                            continue;
                        const float r =
                            RelaxedPairRatio(hf, i, j, off.dx, off.dy, p.searchSteps, best);
                        if (best > r) best = r;
                    }
                }
            }
            m.values[size_t(j) * size_t(W) + size_t(i)] =
                normal ? ConeNormalFromRatio(double(best)) : best;
        }
    });
    return m;
}

}  // namespace

ConeMap GenerateConeMapImpl(const HeightField& hf, ConeKind kind, const ConeMapParams& p,
                            Mode mode) {
    ValidateConeMapParams(p);
    switch (kind) {
        case ConeKind::Relaxed: return RelaxedMap(hf, p, mode, false);
        case ConeKind::ConeNormal:
            if (p.relaxedNormal) return RelaxedMap(hf, p, mode, true);
            return SearchMap(hf, kind, p, mode);
        case ConeKind::MinMip:
        case ConeKind::MaxMip:
            throw Error("--kind " + std::string(ToString(kind)) +
                        ": a mip pyramid, not a cone map; use BuildMipPyramid (texture/mip_pyramid.h)");
        default: return SearchMap(hf, kind, p, mode);
    }
}

ConeMap GenerateConeMap(const HeightField& hf, ConeKind kind, const ConeMapParams& p) {
    if (p.adaptive && (kind == ConeKind::Cone || kind == ConeKind::Quad ||
                       kind == ConeKind::Acm4 || kind == ConeKind::Acm8)) {
        ValidateConeMapParams(p);
        return GenerateAdaptiveSectorMap(hf, kind, p.threshold, p.adaptiveLevels);
    }
    return GenerateConeMapImpl(hf, kind, p, Mode::Fast);
}

ConeMap GenerateConeMapBruteForce(const HeightField& hf, ConeKind kind, const ConeMapParams& p) {
    return GenerateConeMapImpl(hf, kind, p, Mode::Brute);
}

ConeMap GenerateSectorMapPlainSearch(const HeightField& hf, ConeKind kind) {
    return SearchMap(hf, kind, {}, Mode::Plain);
}

}  // namespace reliefsim
