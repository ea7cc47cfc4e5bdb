// A study of why the exact cone-map searches grow faster than N² log N, and of the cell
// bound that would bring them to it (docs/cone_maps.md, "Where the time goes": Growth).
//
// A model of the conservative cone search, in double arithmetic: for an apex s at depth
// a, the ratio is the least |t - s| / (a - d_t) (texel units) over the texels t above it
// in the window of offsets [-n/2, n/2), found by a quadtree over the least-depth pyramid
// (the nine wrap images of the root, as the generators' traversal). Each apex is searched
// once to find its ratio, then twice seeded with it (times 1 + 1e-9), so that only the
// proof that nothing nearer exists is counted:
//   - least depth: a cell is opened when its nearest offset over (a - its least depth) is
//     below the ratio (the generators' bound);
//   - first order: in addition, a cell not holding the apex is skipped when
//     min over its texels of d_t + u·(t - s) / r >= a, u the unit vector from the apex to
//     the cell's centre (|t - s| >= u·(t - s), so no texel of the cell beats r). Computed
//     here by brute force over the cell's texels (cells up to 2^8 a side), not by a
//     structure a generator would use.
// Prints, per map size, the cells tested and the leaf (2x2) texels evaluated per apex;
// exits non-zero if a seeded search does not return the apex's ratio.
//   cone_bound_study [--map rocks|stones|...] [--max-size N] [--apexes K]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "bench/bench_maps.h"
#include "maps/mip_pyramid.h"
#include "texture/procedural.h"

namespace reliefsim {
namespace {

enum class CellBound { LeastDepth, FirstOrder };

struct Counts {
    double cells = 0;       ///< cells whose bounds were tested
    double leafTexels = 0;  ///< texels evaluated in opened 2x2 leaves
};

/// The model search of apex (sx, sy) of the n x n map `f` (n a power of two), starting
/// from ratio `best`; returns the least ratio found (or `best`).
double Search(const DepthField& f, const std::vector<MipLevel>& minDepth, int sx, int sy,
              double best, CellBound bound, Counts& c) {
    constexpr int kFirstOrderMaxLevel = 8;  // brute-force first-order cells up to 256²
    const int n = f.width;
    const int top = int(minDepth.size()) - 1;
    const double a = f.At(sx, sy);
    const auto depthAt = [&](int X, int Y) {
        return double(f.At((X % n + n) % n, (Y % n + n) % n));
    };
    // The window of offsets, unwrapped.
    const int wx0 = sx - n / 2, wx1 = sx + n / 2 - 1, wy0 = sy - n / 2,
              wy1 = sy + n / 2 - 1;
    struct Cell {
        int level, X0, Y0;  ///< unwrapped corner
    };
    std::vector<Cell> stack;
    for (int ty = -1; ty <= 1; ++ty)
        for (int tx = -1; tx <= 1; ++tx) stack.push_back({top, tx * n, ty * n});
    while (!stack.empty()) {
        const Cell cell = stack.back();
        stack.pop_back();
        const int side = 1 << cell.level;
        const int X0 = std::max(cell.X0, wx0), X1 = std::min(cell.X0 + side - 1, wx1);
        const int Y0 = std::max(cell.Y0, wy0), Y1 = std::min(cell.Y0 + side - 1, wy1);
        if (X0 > X1 || Y0 > Y1) continue;
        c.cells += 1;
        const MipLevel& lv = minDepth[size_t(cell.level)];
        const double least = lv.At((cell.X0 % n + n) % n >> cell.level,
                                   (cell.Y0 % n + n) % n >> cell.level);
        if (!(least < a)) continue;
        const double ddx = std::max({0, X0 - sx, sx - X1}),
                     ddy = std::max({0, Y0 - sy, sy - Y1});
        if (std::sqrt(ddx * ddx + ddy * ddy) >= best * (a - least)) continue;
        const bool holdsApex = X0 <= sx && sx <= X1 && Y0 <= sy && sy <= Y1;
        if (bound == CellBound::FirstOrder && !holdsApex &&
            cell.level <= kFirstOrderMaxLevel) {
            double ux = 0.5 * (X0 + X1) - sx, uy = 0.5 * (Y0 + Y1) - sy;
            const double len = std::sqrt(ux * ux + uy * uy);
            ux /= len;
            uy /= len;
            double lower = INFINITY;
            for (int Y = Y0; Y <= Y1; ++Y)
                for (int X = X0; X <= X1; ++X)
                    lower = std::min(
                        lower, depthAt(X, Y) + (ux * (X - sx) + uy * (Y - sy)) / best);
            if (lower > a + 1e-9) continue;  // 1e-9: far above this sum's rounding
        }
        if (cell.level <= 1) {
            for (int Y = Y0; Y <= Y1; ++Y)
                for (int X = X0; X <= X1; ++X) {
                    if (X == sx && Y == sy) continue;
                    c.leafTexels += 1;
                    const double d = depthAt(X, Y);
                    if (!(d < a)) continue;
                    const double dx = X - sx, dy = Y - sy;
                    best = std::min(best, std::sqrt(dx * dx + dy * dy) / (a - d));
                }
            continue;
        }
        const int half = side / 2;
        for (int q = 0; q < 4; ++q)
            stack.push_back(
                {cell.level - 1, cell.X0 + (q & 1) * half, cell.Y0 + (q >> 1) * half});
    }
    return best;
}

int Run(const std::string& mapName, int maxSize, int apexes) {
    const auto shared = bench::SharedMap(mapName);
    if (!shared && std::filesystem::exists(RS_SHARED_DATA)) {
        std::fprintf(stderr,
                     "cone_bound_study: --map %s: no %s/dxsdk-pom/%s_NM_height.tga\n",
                     mapName.c_str(), RS_SHARED_DATA, mapName.c_str());
        return 2;
    }
    const DepthField base = shared ? *shared : MakeBuiltinMap("noise", 256, 256);
    std::printf("map: %s upsampled to n² float; %d x %d apexes per size\n",
                shared ? mapName.c_str() : "builtin:noise:256 (../shared absent)", apexes,
                apexes);
    std::printf("%6s %8s | %-27s | %-27s\n", "n", "apexes", "least depth: cells, leaves",
                "first order: cells, leaves");
    int failures = 0;
    for (int n = 256; n <= maxSize; n *= 2) {
        const DepthField f = bench::Upsample(base, n);
        const auto minDepth = BuildMipPyramid(f.depth, n, n, 1, MipReduce::Min);
        Counts least, first;
        int searched = 0;
        const int step = n / apexes;
        for (int j = 0; j < apexes; ++j)
            for (int i = 0; i < apexes; ++i) {
                // A grid with a deterministic jitter inside each of its cells.
                const int sx = i * step + (j * 7) % step, sy = j * step + (i * 5) % step;
                Counts unused;
                const double ratio =
                    Search(f, minDepth, sx, sy, INFINITY, CellBound::LeastDepth, unused);
                if (!std::isfinite(ratio)) continue;  // nothing above the apex
                ++searched;
                const double seed = ratio * (1 + 1e-9);
                const double r0 =
                    Search(f, minDepth, sx, sy, seed, CellBound::LeastDepth, least);
                const double r1 =
                    Search(f, minDepth, sx, sy, seed, CellBound::FirstOrder, first);
                if (r0 != ratio || r1 != ratio) {
                    std::fprintf(
                        stderr, "n=%d apex (%d, %d): ratio %.17g, seeded %.17g / %.17g\n",
                        n, sx, sy, ratio, r0, r1);
                    ++failures;
                }
            }
        const double k = std::max(searched, 1);
        std::printf("%6d %8d | %12.1f %14.1f | %12.1f %14.1f\n", n, searched,
                    least.cells / k, least.leafTexels / k, first.cells / k,
                    first.leafTexels / k);
    }
    if (failures)
        std::fprintf(stderr, "cone_bound_study: %d apexes disagree\n", failures);
    return failures ? 1 : 0;
}

}  // namespace
}  // namespace reliefsim

int main(int argc, char** argv) {
    CLI::App app(
        "cells the exact cone search opens, least-depth against first-order bounds");
    std::string map = "rocks";
    int maxSize = 2048, apexes = 32;
    app.add_option("--map", map, "a DirectX SDK map of ../shared/data/dxsdk-pom")
        ->capture_default_str();
    app.add_option("--max-size", maxSize, "largest n (256, 512, 1024 or 2048)")
        ->check(CLI::IsMember({256, 512, 1024, 2048}))
        ->capture_default_str();
    app.add_option("--apexes", apexes, "apexes per side of the sampled grid")
        ->check(CLI::IsMember({1, 2, 4, 8, 16, 32, 64, 128, 256}))
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    return reliefsim::Run(map, maxSize, apexes);
}
