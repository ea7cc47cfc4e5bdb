// Cone maps conservative for the bilinear surface (maps/cone_map_bilinear.h). The far
// cells are searched as the texel maps are (maps/cone_map_detail.h TiledSearch, or every
// offset for the brute force) over two derived fields: apexes at each cell's deepest
// corner and blockers at each cell's shallowest, with the offsets between cells (their
// gap as distance, their sector masks by Minkowski difference).
#include "maps/cone_map_bilinear.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/param_name.h"
#include "maps/cone_map_detail.h"

namespace reliefsim {

using namespace detail;

bool HasBilinearBounds(ConeKind kind) {
    switch (kind) {
        case ConeKind::Cone:
        case ConeKind::ConeNormal:
        case ConeKind::Quad:
        case ConeKind::Acm4:
        case ConeKind::Acm8:
            return true;
        default:
            return false;
    }
}

namespace {

/// Per cell (i, j) (corners: texels i..i+1 x j..j+1, wrapped), over the field: the
/// deepest and the shallowest corner, and the largest squared gradient norm of its
/// bilinear patch in depth per uv (at a corner: the patch's partial derivatives are
/// linear in the other coordinate, so the squared norm, a sum of squares of them, is
/// convex and peaks at a corner).
struct Cells {
    DepthField deepest, shallowest;
    std::vector<double> grad2;
};

Cells MakeCells(const DepthField& hf) {
    const int W = hf.width, H = hf.height;
    Cells c;
    c.deepest.width = c.shallowest.width = W;
    c.deepest.height = c.shallowest.height = H;
    c.deepest.name = c.shallowest.name = hf.name;
    c.deepest.depth.resize(hf.depth.size());
    c.shallowest.depth.resize(hf.depth.size());
    c.grad2.resize(hf.depth.size());
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const int i1 = Wrap(i + 1, W), j1 = Wrap(j + 1, H);
            const float d00 = hf.At(i, j), d10 = hf.At(i1, j), d01 = hf.At(i, j1),
                        d11 = hf.At(i1, j1);
            const size_t at = size_t(j) * size_t(W) + size_t(i);
            c.deepest.depth[at] = std::max({d00, d10, d01, d11});
            c.shallowest.depth[at] = std::min({d00, d10, d01, d11});
            // d/du = W * (difference along x), d/dv = H * (difference along y), exact in
            // double.
            const double gx0 = double(W) * (double(d10) - double(d00)),
                         gx1 = double(W) * (double(d11) - double(d01));
            const double gy0 = double(H) * (double(d01) - double(d00)),
                         gy1 = double(H) * (double(d11) - double(d10));
            const double gx = std::max(gx0 * gx0, gx1 * gx1),
                         gy = std::max(gy0 * gy0, gy1 * gy1);
            // Each corner pairs one x difference with one y difference; all four pairs
            // occur, so the largest sum is the sum of the largest squares.
            c.grad2[at] = gx + gy;
        }
    return c;
}

ConeMap BilinearMap(const DepthField& hf, ConeKind kind, const ConeMapParams& p,
                    bool brute) {
    ValidateConeMapParams(p);
    if (!HasBilinearBounds(kind))
        throw Error(ParamName("cone_bounds") + " bilinear: applies to " +
                    ParamName("kind") + " cone, cone-normal, quad, acm4 and acm8, not " +
                    std::string(ToString(kind)));
    if (p.relaxed || p.normal || p.adaptive)
        throw Error(ParamName("cone_bounds") +
                    " bilinear: the exact conservative maps only (not relaxed, normal or "
                    "adaptive)");
    CheckedMinDepth(hf);
    const int W = hf.width, H = hf.height;
    const Geometry g = MakeGeometry(W, H);
    const Cells cells = MakeCells(hf);
    const float dmin = CheckedMinDepth(cells.shallowest);
    const ConeKind sectors = kind == ConeKind::ConeNormal ? ConeKind::Cone : kind;
    const int nS = SectorCount(sectors);

    TiledOffsets to;
    std::vector<Offset> offs;
    SearchWindows win;
    if (brute)
        offs = MakeOffsets(g, sectors, /*cells=*/true);
    else {
        to = MakeTiledOffsets(g, sectors, /*cells=*/true);
        MakeSearchWindows(cells.shallowest, win);
    }
    const auto acceptAll = [](int, int, const Offset&) { return true; };
    // R per cell and sector, as a ratio in double (+inf: unbounded).
    std::vector<double> R(size_t(W) * size_t(H) * size_t(nS));
    tbb::parallel_for(
        tbb::blocked_range<int>(0, H, 1), [&](const tbb::blocked_range<int>& r) {
            for (int j = r.begin(); j < r.end(); ++j)
                for (int i = 0; i < W; ++i) {
                    const size_t at = size_t(j) * size_t(W) + size_t(i);
                    double best[kMaxSectors * 2];
                    std::fill(best, best + kMaxSectors * 2, kInfQ);
                    const float apex = cells.deepest.depth[at];
                    if (brute)
                        BruteSearch(cells.shallowest, offs, i, j, apex, nS, best,
                                    acceptAll);
                    else
                        TiledSearch(cells.shallowest, to, win, dmin, i, j, apex, nS, best,
                                    acceptAll);
                    // The near cells: the steepest patch of the 3x3 cells around.
                    double l2 = 0.0;
                    for (int sy = -1; sy <= 1; ++sy)
                        for (int sx = -1; sx <= 1; ++sx)
                            l2 = std::max(
                                l2, cells.grad2[size_t(Wrap(j + sy, H)) * size_t(W) +
                                                size_t(Wrap(i + sx, W))]);
                    const double nearR = l2 > 0.0 ? 1.0 / std::sqrt(l2) : kInfQ;
                    for (int k = 0; k < nS; ++k) {
                        const double farR =
                            best[k] < kInfQ ? std::sqrt(best[k]) / g.scale : kInfQ;
                        R[at * size_t(nS) + size_t(k)] = std::min(nearR, farR);
                    }
                }
        });
    // A texel: the least R of the four cells it is a corner of.
    const int C = nS;
    ConeMap m;
    m.kind = kind;
    m.width = W;
    m.height = H;
    m.channels = C;
    m.values.resize(size_t(W) * size_t(H) * size_t(C));
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            for (int k = 0; k < C; ++k) {
                double r = kInfQ;
                for (int cy = -1; cy <= 0; ++cy)
                    for (int cx = -1; cx <= 0; ++cx)
                        r = std::min(r, R[(size_t(Wrap(j + cy, H)) * size_t(W) +
                                           size_t(Wrap(i + cx, W))) *
                                              size_t(nS) +
                                          size_t(k)]);
                float& out =
                    m.values[(size_t(j) * size_t(W) + size_t(i)) * size_t(C) + size_t(k)];
                if (kind == ConeKind::ConeNormal)
                    out = ConeNormalFromRatio(r);
                else
                    out = r < double(kConeRatioCap) ? RoundDownStrict(r) : kConeRatioCap;
            }
    return m;
}

}  // namespace

ConeMap GenerateBilinearConeMap(const DepthField& hf, ConeKind kind,
                                const ConeMapParams& params) {
    return BilinearMap(hf, kind, params, false);
}

ConeMap GenerateBilinearConeMapBruteForce(const DepthField& hf, ConeKind kind,
                                          const ConeMapParams& params) {
    return BilinearMap(hf, kind, params, true);
}

}  // namespace reliefsim
