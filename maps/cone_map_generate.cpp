// Cone-family generators: the fast exact versions (the lane search of maps/cone_search.h
// for every conservative kind and relaxed-exact; the pruned Listing search for relaxed
// cones), their brute-force oracles and the plain tiled search of the ACM paper.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/param_name.h"
#include "maps/cone_map.h"
#include "maps/cone_map_detail.h"
#include "maps/cone_search.h"

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

    if (mode == Mode::Fast) {
        // The lane search (maps/cone_search.h): one search per stacked cone, else one,
        // each making ConeSearchPasses passes over the tile rows.
        const int passes = (kind == ConeKind::Stacked ? C : 1) *
                           ConeSearchPasses(sectors, hf.width, hf.height);
        ProgressCounter progress(
            p.progress, int64_t(passes) * ((hf.height + kLaneTile - 1) / kLaneTile));
        ConeSearchJob job;
        job.field = &hf;
        job.sectors = sectors;
        job.limiting = limiting;
        job.output = kind == ConeKind::ConeNormal ? ConeSearchOutput::ConeNormal
                                                  : ConeSearchOutput::Ratio;
        job.out = m.values.data();
        job.outStride = C;
        if (kind != ConeKind::Stacked) {
            job.apex = hf.depth.data();
            RunConeSearch(job, &progress);
            return m;
        }
        std::vector<float> apex(hf.depth.size());
        for (int c = 0; c < C; ++c) {
            for (size_t t = 0; t < apex.size(); ++t)
                apex[t] = StackedApex(hf.depth[t], c, C);
            job.apex = apex.data();
            job.outBase = c;
            RunConeSearch(job, &progress);
        }
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
        throw Error(ParamName("normal") + ": applies to " + ParamName("kind") +
                    " stacked only (" + ParamName("kind") +
                    " cone-normal stores "
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
            throw Error(ParamName("kind") + " " + std::string(ToString(kind)) +
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
