// Cone-family generators: fast exact versions (levels + distance transforms, tiled pruned
// searches), their brute-force oracles, the relaxed Listing 18-2 definition and adaptive
// ACM.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "maps/cone_map.h"
#include "maps/cone_map_detail.h"

namespace reliefsim {

namespace detail {

namespace {

template <class F>
void ForEachRow(int H, F&& f) {
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 1),
                      [&](const tbb::blocked_range<int>& r) {
                          for (int j = r.begin(); j < r.end(); ++j) f(j);
                      });
}

bool UseLevels(const DepthField& hf) {
    // The levels path stores vertical distances in 16 bits.
    if (hf.height >= 0xFFFF || hf.width >= 0xFFFF) return false;
    if (!hf.depth8.empty()) return true;
    std::vector<float> v(hf.depth);
    std::sort(v.begin(), v.end());
    return std::unique(v.begin(), v.end()) - v.begin() <= 300;
}

}  // namespace

}  // namespace detail

namespace {

using namespace detail;

enum class Mode { Fast, Brute, Plain };

ConeMap MakeMap(const DepthField& hf, ConeKind kind, int channels) {
    ConeMap m;
    m.kind = kind;
    m.width = hf.width;
    m.height = hf.height;
    m.channels = channels;
    m.values.assign(size_t(hf.width) * size_t(hf.height) * size_t(channels), 0.0f);
    return m;
}

/// Conservative / sector / relaxed-exact / stacked: q per texel and channel.
ConeMap SearchMap(const DepthField& hf, ConeKind kind, const ConeMapParams& p,
                  Mode mode) {
    const float dmin = CheckedMinDepth(hf);
    const Geometry g = MakeGeometry(hf.width, hf.height);
    const ConeKind sectors =
        (kind == ConeKind::Quad || kind == ConeKind::Acm4 || kind == ConeKind::Acm8)
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
        ConservativeQByLevels(hf, g, q, p.progress);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, q.size(), size_t(1) << 14),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t t = r.begin(); t < r.end(); ++t)
                                  m.values[t] =
                                      kind == ConeKind::ConeNormal
                                          ? ConeNormalFromRatio(std::sqrt(q[t]) / g.scale)
                                          : RatioFromQ(q[t], g.scale);
                          });
        return m;
    }

    TiledOffsets to;
    std::vector<Offset> offs;
    SearchWindows win;
    if (mode == Mode::Brute)
        offs = MakeOffsets(g, sectors);
    else {
        to = MakeTiledOffsets(g, sectors);
        MakeSearchWindows(hf, win);
    }
    auto accept = [&](int bx, int by, const Offset& o) {
        return !limiting || IsLimiting(hf, bx, by, o.dx, o.dy);
    };
    ProgressCounter progress(p.progress, hf.height);
    ForEachRow(hf.height, [&](int j) {
        for (int i = 0; i < W; ++i) {
            const float d = hf.At(i, j);
            double best[kMaxSectors * 2];
            for (int c = 0; c < C; ++c) {
                const int nSearch = kind == ConeKind::Stacked ? 1 : nS;
                const float apex = kind == ConeKind::Stacked ? StackedApex(d, c, C) : d;
                if (kind != ConeKind::Stacked && c > 0) break;
                std::fill(best, best + kMaxSectors * 2, kInfQ);
                if (mode == Mode::Brute)
                    BruteSearch(hf, offs, i, j, apex, nSearch, best, accept);
                else
                    TiledSearch(hf, to, win, dmin, i, j, apex, nSearch, best, accept);
                float* out = &m.values[(size_t(j) * size_t(W) + size_t(i)) * size_t(C)];
                if (kind == ConeKind::Stacked)
                    out[c] = RatioFromQ(best[0], g.scale);
                else if (kind == ConeKind::ConeNormal)
                    out[0] = ConeNormalFromRatio(std::sqrt(best[0]) / g.scale);
                else
                    for (int k = 0; k < nS; ++k) out[k] = RatioFromQ(best[k], g.scale);
            }
        }
        progress.Add(1);
    });
    return m;
}

}  // namespace

ConeMap GenerateConeMapImpl(const DepthField& hf, ConeKind kind, const ConeMapParams& p,
                            Mode mode) {
    ValidateConeMapParams(p);
    if (p.normal && kind != ConeKind::Stacked)
        throw Error(
            "--normal: applies to --kind stacked only (--kind cone-normal stores "
            "n_z of one cone)");
    switch (kind) {
        case ConeKind::Relaxed:
            return RelaxedListingMap(hf, p, mode == Mode::Brute, kind);
        case ConeKind::ConeNormal:
            if (p.relaxed) return RelaxedListingMap(hf, p, mode == Mode::Brute, kind);
            return SearchMap(hf, kind, p, mode);
        case ConeKind::Stacked: {
            ConeMap m = p.relaxed ? RelaxedListingMap(hf, p, mode == Mode::Brute, kind)
                                  : SearchMap(hf, kind, p, mode);
            // n_z of each stored (rounded-down) ratio, rounded down again: never wider.
            if (p.normal)
                for (float& v : m.values) v = ConeNormalFromRatio(double(v));
            return m;
        }
        case ConeKind::MinMip:
        case ConeKind::MaxMip:
            throw Error("--kind " + std::string(ToString(kind)) +
                        ": a mip pyramid, not a cone map; use BuildMipPyramid "
                        "(maps/mip_pyramid.h)");
        default:
            return SearchMap(hf, kind, p, mode);
    }
}

ConeMap GenerateConeMap(const DepthField& hf, ConeKind kind, const ConeMapParams& p) {
    if (p.adaptive && (kind == ConeKind::Cone || kind == ConeKind::Quad ||
                       kind == ConeKind::Acm4 || kind == ConeKind::Acm8)) {
        ValidateConeMapParams(p);
        return GenerateAdaptiveSectorMap(hf, kind, p.threshold, p.adaptiveLevels);
    }
    return GenerateConeMapImpl(hf, kind, p, Mode::Fast);
}

ConeMap GenerateConeMapBruteForce(const DepthField& hf, ConeKind kind,
                                  const ConeMapParams& p) {
    return GenerateConeMapImpl(hf, kind, p, Mode::Brute);
}

ConeMap GenerateSectorMapPlainSearch(const DepthField& hf, ConeKind kind) {
    return SearchMap(hf, kind, {}, Mode::Plain);
}

}  // namespace reliefsim
