// A study of how many (apex, destination) pairs an exact generator of the Listing's
// relaxed cone map (GPU Gems 3, Listing 18-2) must settle one by one, whatever per-pair
// bound it uses short of marching (docs/cone_maps.md, "The floor of per-pair bounds").
//
// For sampled apexes (texel a at depth s, apex = its own depth), the Listing's minimum m
// is found with the pair function of the brute force (RelaxedPairRatio, float arithmetic
// as the listing) over every destination above the apex whose distance bound can still
// lower it; at n <= 256 it is checked against the generator's map. Then, seeded with m,
// the pairs are counted that
//   - lie above the apex (d < s): every destination the definition ranges over that can
//     give a ratio below 1;
//   - pass the distance bound: |v| / (s - d) < m (v the uv offset; the march moves away
//     from the apex and down, so the ratio is at least this);
//   - pass the continuous-exit bound: the ratio at the first point past the destination
//     where the ray leaves the solid, in real numbers (cells walked in order along the
//     exact ray, nearest-texel cells, wrapped), and at least one march step past the
//     destination, is below m. The listing's march samples points on that ray and stops
//     at the first one above its cell, which cannot come before the continuous exit, and
//     the ratio only grows along the ray; so this is the tightest bound any per-pair test
//     that does not march can have (less the float rounding this model ignores). The
//     pairs it leaves are those whose value depends on where the march's steps fall.
// Double arithmetic for the counts; they are per apex, averaged over the apexes. At n <=
// 256 every pair that passes the distance bound is also marched by the brute force's pair
// function, which must not be below its continuous-exit bound (a check of the model).
//   relaxed_floor_study [--map shapes|noise|bumps|steps|rocks|stones] [--max-size N]
//                       [--apexes K]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "bench/bench_maps.h"
#include "maps/cone_map.h"
#include "maps/cone_map_detail.h"
#include "texture/procedural.h"

namespace reliefsim {
namespace {

constexpr int kSteps = 128;  // the listing's search_steps
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Counts {
    double above = 0;     ///< destinations above the apex
    double distance = 0;  ///< of those, passing the distance bound
    double floor = 0;     ///< of those, passing the continuous-exit bound
    double samples = 0;   ///< their march steps between the continuous exit and m
};

struct Pair {
    int dx, dy;
    double dist;  ///< uv distance
};

bool IsBuiltin(const std::string& name) {
    return name == "shapes" || name == "noise" || name == "bumps" || name == "steps";
}

/// The map at n x n: the built-in `name`, or `shared` (a ../shared/data map, loaded
/// once) resized bilinearly and stored in 8 bits (as the benchmarks' rocks 8-bit).
DepthField MapAt(const std::string& name, const std::optional<DepthField>& shared,
                 int n) {
    if (!shared) return MakeBuiltinMap(name, n, n);
    return bench::Quantize(bench::Upsample(*shared, n), 8);
}

/// The ratio of the continuous-exit bound of the pair (apex texel (i, j) at depth s,
/// offset p, destination depth d), or `best` when it is at least `best`; `exitZ` the
/// depth of that exit.
double ContinuousExitRatio(const DepthField& f, int i, int j, double s, const Pair& p,
                           double d, double best, double& exitZ) {
    const int n = f.width;
    // Texel units: the ray from the apex centre at depth 0 through the destination
    // centre at depth d is P(t) = A + t (dx, dy) at depth z = t d; the march starts at
    // t = 1 and its first step reaches z1.
    const double ax = i + 0.5, ay = j + 0.5;
    const double z1 = d + (1.0 - d) / kSteps;
    const auto ratio = [&](double z) { return p.dist * (z / d) / (s - z); };
    double t = 1.0;
    long cx = i + p.dx, cy = j + p.dy;  // the cell holding P(t)
    const int sx = p.dx > 0 ? 1 : (p.dx < 0 ? -1 : 0);
    const int sy = p.dy > 0 ? 1 : (p.dy < 0 ? -1 : 0);
    // The cells the ray meets past the destination, each at the depth where it enters
    // it; where it crosses a corner, both cells beside the corner too (the listing's
    // float point can land exactly on it).
    const auto exits = [&](long x, long y, double z) {
        return double(f.At(int(((x % n) + n) % n), int(((y % n) + n) % n))) > z;
    };
    for (;;) {
        // Next cell boundary along each axis.
        const double tx = sx ? ((sx > 0 ? cx + 1 : cx) - ax) / p.dx : kInf;
        const double ty = sy ? ((sy > 0 ? cy + 1 : cy) - ay) / p.dy : kInf;
        t = std::min(tx, ty);
        const double z = t * d;
        if (z >= s) return std::min(best, 1.0);  // the listing's 1: no exit above s
        if (ratio(z) >= best) return best;
        bool out = false;
        if (tx == ty) out = exits(cx + sx, cy, z) || exits(cx, cy + sy, z);
        if (tx <= ty) cx += sx;
        if (ty <= tx) cy += sy;
        if (out || exits(cx, cy, z)) {
            exitZ = std::max(z, z1);
            return std::min(best, ratio(exitZ));
        }
    }
}

int Run(const std::string& mapName, int maxSize, int apexes) {
    const bool builtin = IsBuiltin(mapName);
    const std::optional<DepthField> shared =
        builtin ? std::nullopt : bench::SharedMap(mapName);
    if (!builtin && !shared) {
        if (!std::filesystem::exists(RS_SHARED_DATA)) {
            std::printf("relaxed_floor_study: --map %s: skipped, %s is absent\n",
                        mapName.c_str(), RS_SHARED_DATA);
            return 0;
        }
        std::fprintf(stderr,
                     "relaxed_floor_study: --map %s: no built-in and no "
                     "%s/dxsdk-pom/%s_NM_height.tga\n",
                     mapName.c_str(), RS_SHARED_DATA, mapName.c_str());
        return 2;
    }
    std::printf(
        "map: %s at n² (%s); %d x %d apexes per size; per apex:\n", mapName.c_str(),
        builtin ? "built-in, float" : "resized bilinearly, 8-bit", apexes, apexes);
    std::printf("%6s %7s | %10s %10s %8s %8s | %s\n", "n", "apexes", "above", "distance",
                "floor", "samples", "floor x (vs n/2)");
    int failures = 0;
    double lastFloor = 0;
    for (int n = 128; n <= maxSize; n *= 2) {
        const DepthField f = MapAt(mapName, shared, n);
        const detail::Geometry g = detail::MakeGeometry(n, n);
        std::vector<Pair> offs;
        for (const detail::Offset& o : detail::MakeOffsets(g, ConeKind::Cone))
            offs.push_back(
                {o.dx, o.dy, std::sqrt(double(o.dx) * o.dx + double(o.dy) * o.dy) / n});
        std::stable_sort(offs.begin(), offs.end(),
                         [](const Pair& a, const Pair& b) { return a.dist < b.dist; });
        const double dmin = *std::min_element(f.depth.begin(), f.depth.end());
        std::optional<ConeMap> map;
        if (n <= 256) {
            map = GenerateConeMap(f, ConeKind::Relaxed);
        }
        Counts sum;
        int searched = 0;
        const int step = n / apexes;
        for (int aj = 0; aj < apexes; ++aj)
            for (int ai = 0; ai < apexes; ++ai) {
                // A grid with a deterministic jitter inside each of its cells.
                const int i = ai * step + (aj * 7) % step,
                          j = aj * step + (ai * 5) % step;
                const double s = f.At(i, j);
                if (!(s > dmin)) continue;  // nothing above the apex: ratio 1
                ++searched;
                const auto depthAt = [&](const Pair& p) {
                    return double(f.At((i + p.dx + n) % n, (j + p.dy + n) % n));
                };
                // The listing's minimum, nearest destinations first; a pair is skipped
                // when its distance bound is above the running minimum by more than
                // float rounding (the listing's ratio is at least fl|v| / (s - d)).
                float best = 1.0f;
                for (const Pair& p : offs) {
                    if (p.dist * (1 - 1e-5) >= double(best) * (s - dmin)) break;
                    const double d = depthAt(p);
                    if (!(d < s) || p.dist * (1 - 1e-5) >= double(best) * (s - d))
                        continue;
                    best = std::min(best, detail::RelaxedPairRatio(f, i, j, p.dx, p.dy,
                                                                   kSteps, float(s)));
                }
                if (map && map->values[size_t(j) * size_t(n) + size_t(i)] != best) {
                    std::fprintf(stderr,
                                 "n=%d apex (%d, %d): study %.9g, generator %.9g\n", n, i,
                                 j, double(best),
                                 double(map->values[size_t(j) * size_t(n) + size_t(i)]));
                    ++failures;
                }
                const double m = best;
                for (const Pair& p : offs) {
                    const double d = depthAt(p);
                    if (!(d < s) || !(d > 0)) continue;
                    sum.above += 1;
                    if (p.dist >= m * (s - d)) continue;
                    sum.distance += 1;
                    double exitZ = 0;
                    if (map) {
                        // The bound is below the listing's ratio (the brute force's pair
                        // function), less float rounding.
                        // A bound above 1 only bounds the listing's 1, which a march
                        // that steps over a thin exit and ends below the apex returns.
                        const double bound = std::min(
                            ContinuousExitRatio(f, i, j, s, p, d, kInf, exitZ), 1.0);
                        const double listing = detail::RelaxedPairRatio(
                            f, i, j, p.dx, p.dy, kSteps, float(s));
                        if (bound > listing * (1 + 1e-5)) {
                            std::fprintf(stderr,
                                         "n=%d apex (%d, %d) offset (%d, %d): continuous "
                                         "exit %.9g above the listing's %.9g\n",
                                         n, i, j, p.dx, p.dy, bound, listing);
                            ++failures;
                        }
                    }
                    if (!(ContinuousExitRatio(f, i, j, s, p, d, m, exitZ) < m)) continue;
                    sum.floor += 1;
                    // The steps (z_k = d + k (1 - d) / 128) from the exit to the depth
                    // where the ray's ratio reaches m: the samples that decide whether
                    // the march stops below m (at most; it may stop earlier).
                    const double zm = m * s * d / (p.dist + m * d);
                    const double dz = (1.0 - d) / kSteps;
                    sum.samples += std::max(
                        0.0, std::ceil((zm - d) / dz) - std::ceil((exitZ - d) / dz) + 1);
                }
            }
        const double k = std::max(searched, 1);
        const double floorPer = sum.floor / k;
        std::printf("%6d %7d | %10.1f %10.1f %8.1f %8.1f | ", n, searched, sum.above / k,
                    sum.distance / k, floorPer, sum.samples / std::max(sum.floor, 1.0));
        if (lastFloor > 0)
            std::printf("%.2f\n", floorPer / lastFloor);
        else
            std::printf("-\n");
        lastFloor = floorPer;
    }
    if (failures)
        std::fprintf(stderr, "relaxed_floor_study: %d checks failed\n", failures);
    return failures ? 1 : 0;
}

}  // namespace
}  // namespace reliefsim

int main(int argc, char** argv) {
    CLI::App app(
        "pairs an exact relaxed (Listing 18-2) generator settles one by one, by bound");
    std::string map = "shapes";
    int maxSize = 1024, apexes = 16;
    app.add_option("--map", map,
                   "a built-in (shapes, noise, bumps, steps) or a map of "
                   "../shared/data/dxsdk-pom (rocks, stones, ...)")
        ->capture_default_str();
    app.add_option("--max-size", maxSize, "largest n (128 .. 2048)")
        ->check(CLI::IsMember({128, 256, 512, 1024, 2048}))
        ->capture_default_str();
    app.add_option("--apexes", apexes, "apexes per side of the sampled grid")
        ->check(CLI::IsMember({1, 2, 4, 8, 16, 32, 64, 128}))
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    return reliefsim::Run(map, maxSize, apexes);
}
