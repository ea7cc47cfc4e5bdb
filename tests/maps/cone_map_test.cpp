// Cone-map generators: fast == brute force bit for bit, conservativeness, encodings,
// adaptive, safety pass, cache, mip pyramids, bad input.
#include "maps/cone_map.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <numbers>

#include "core/error.h"
#include "maps/cone_map_detail.h"
#include "maps/cone_search.h"
#include "maps/map_cache.h"
#include "maps/mip_pyramid.h"
#include "tests/common/fields.h"
#include "tests/common/test_files.h"
#include "texture/image_io.h"
#include "texture/procedural.h"
#include "texture/sampler.h"

namespace reliefsim {
namespace {

DepthField RandomField(int w, int h, uint64_t seed, bool smooth) {
    return testing::MakeField(
        w, h,
        [&](int i, int j) {
            const uint64_t r =
                Mix64(seed * 1000003ull + uint64_t(j) * uint64_t(w) + uint64_t(i));
            float v = float(r >> 40) * (1.0f / 16777216.0f);
            if (smooth) {  // blobs: mostly flat regions with some random texels on top
                v = (v < 0.9f) ? 0.5f + 0.4f * std::sin(float(i) * 0.3f) *
                                            std::cos(float(j) * 0.2f)
                               : v * 0.5f;
                v = std::clamp(v, 0.0f, 1.0f);
            }
            return v;
        },
        "random");
}

void ExpectBitEqual(const ConeMap& a, const ConeMap& b, const std::string& what) {
    ASSERT_EQ(a.values.size(), b.values.size()) << what;
    size_t bad = 0, first = 0;
    for (size_t i = 0; i < a.values.size(); ++i)
        if (std::memcmp(&a.values[i], &b.values[i], sizeof(float)) != 0) {
            if (!bad) first = i;
            ++bad;
        }
    EXPECT_EQ(bad, 0u) << what << ": first mismatch at value " << first << ": "
                       << (bad ? a.values[first] : 0.0f) << " vs "
                       << (bad ? b.values[first] : 0.0f);
}

std::vector<DepthField> Fields(int n) {
    std::vector<DepthField> v;
    v.push_back(RandomField(n, n, 7, false));
    v.push_back(RandomField(n, n, 8, true));
    v.push_back(QuantizeToUnorm8(RandomField(n, n, 9, true)));
    v.push_back(MakeBuiltinMap("shapes", n, n));
    v.push_back(QuantizeToUnorm8(MakeBuiltinMap("bumps", n, n)));
    v.push_back(MakeBuiltinMap("steps", n, n));
    return v;
}

TEST(ConeMap, FastEqualsBruteForceAt32) {
    for (const DepthField& hf : Fields(32))
        for (ConeKind k :
             {ConeKind::Cone, ConeKind::Quad, ConeKind::Acm4, ConeKind::Acm8,
              ConeKind::RelaxedExact, ConeKind::Stacked, ConeKind::ConeNormal})
            ExpectBitEqual(GenerateConeMap(hf, k), GenerateConeMapBruteForce(hf, k),
                           hf.name + " " + std::string(ToString(k)));
}

TEST(ConeMap, FastEqualsBruteForceAt64) {
    for (const DepthField& hf : Fields(64))
        for (ConeKind k : {ConeKind::Cone, ConeKind::Acm4, ConeKind::RelaxedExact})
            ExpectBitEqual(GenerateConeMap(hf, k), GenerateConeMapBruteForce(hf, k),
                           hf.name + " " + std::string(ToString(k)));
}

TEST(ConeMap, FastEqualsBruteForceAt128) {
    const DepthField a = QuantizeToUnorm8(MakeBuiltinMap("shapes", 128, 128));
    ExpectBitEqual(GenerateConeMap(a, ConeKind::Cone),
                   GenerateConeMapBruteForce(a, ConeKind::Cone), "shapes 8-bit 128");
    const DepthField b = RandomField(128, 128, 11, true);
    ExpectBitEqual(GenerateConeMap(b, ConeKind::Quad),
                   GenerateConeMapBruteForce(b, ConeKind::Quad), "random float 128 quad");
}

/// Smooth maps, where cones touch the surface tangentially and the first-order cell bound
/// (docs/cone_maps.md, "The first-order cell bound") is at its tightest: a bowl (a
/// paraboloid: every cone from inside it touches its rim's slope), travelling sinusoids,
/// a slanted plane (ties along every row), and a coarse random grid upsampled bilinearly.
std::vector<DepthField> SmoothFields(int w, int h) {
    std::vector<DepthField> v;
    DepthField bowl, plane;
    for (DepthField* f : {&bowl, &plane}) {
        f->width = w;
        f->height = h;
        f->depth.resize(size_t(w) * size_t(h));
    }
    bowl.name = "bowl";
    plane.name = "slanted plane";
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const double x = (i + 0.5) / w - 0.5, y = (j + 0.5) / h - 0.5;
            const size_t at = size_t(j) * size_t(w) + size_t(i);
            bowl.depth[at] = float(0.9 - 1.6 * (x * x + y * y));
            plane.depth[at] = float(0.1 + 0.8 * (i + 0.5) / w);
        }
    DepthField up = UpsampleBilinear(RandomField(8, 8, 21, false), w, h);
    up.name = "upsampled random";
    v.push_back(bowl);
    v.push_back(MakeSinusoidMap(w, h, 0.7f));
    v.push_back(plane);
    v.push_back(up);
    return v;
}

TEST(ConeMap, SmoothMapsMatchBruteForce) {
    for (auto [w, h] : {std::pair{64, 64}, std::pair{48, 30}})
        for (const DepthField& hf : SmoothFields(w, h))
            for (ConeKind k : {ConeKind::Cone, ConeKind::Quad, ConeKind::ConeNormal,
                               ConeKind::Stacked, ConeKind::Acm4, ConeKind::Acm8})
                ExpectBitEqual(GenerateConeMap(hf, k), GenerateConeMapBruteForce(hf, k),
                               hf.name + " " + std::to_string(w) + "x" +
                                   std::to_string(h) + " " + std::string(ToString(k)));
}

TEST(ConeMap, NonSquareAndOddSizesMatchBruteForce) {
    for (auto [w, h] :
         {std::pair{24, 40}, std::pair{33, 17}, std::pair{1, 9}, std::pair{5, 5},
          std::pair{37, 37}, std::pair{1, 1}, std::pair{2, 1}}) {
        const DepthField hf = RandomField(w, h, 3, true);
        for (ConeKind k :
             {ConeKind::Cone, ConeKind::Acm8, ConeKind::Quad, ConeKind::RelaxedExact})
            ExpectBitEqual(GenerateConeMap(hf, k), GenerateConeMapBruteForce(hf, k),
                           std::to_string(w) + "x" + std::to_string(h) + " " +
                               std::string(ToString(k)));
        ExpectBitEqual(GenerateConeMap(QuantizeToUnorm8(hf), ConeKind::Cone),
                       GenerateConeMapBruteForce(QuantizeToUnorm8(hf), ConeKind::Cone),
                       "8-bit levels");
    }
}

TEST(ConeMap, LaneSearchOnLargeAndWideMapsMatchesPlainSearch) {
    // Sizes beyond the brute force's reach, with rows and columns that are not multiples
    // of the lane tile, several pyramid levels and wrap images: equal to the exact plain
    // search, which the brute-force tests cover. Non-square sizes exercise the weighted
    // geometry (and acm8 on non-square maps, which has no sheared rip-maps).
    for (auto [w, h] : {std::pair{301, 38}, std::pair{97, 130}, std::pair{192, 192}}) {
        for (const DepthField& hf : {QuantizeToUnorm8(MakeBuiltinMap("shapes", w, h)),
                                     RandomField(w, h, 13, true), SmoothFields(w, h)[3]})
            for (ConeKind k :
                 {ConeKind::Cone, ConeKind::Quad, ConeKind::Acm4, ConeKind::Acm8})
                ExpectBitEqual(GenerateConeMap(hf, k),
                               GenerateSectorMapPlainSearch(hf, k),
                               hf.name + " " + std::to_string(w) + "x" +
                                   std::to_string(h) + " " + std::string(ToString(k)));
    }
}

TEST(ConeMap, LaneSearchIsTheSameOnEveryInstructionSet) {
    // The lane search runs with AVX-512, AVX2 or SSE4.1 (RS_CONE_SEARCH_ISA forces one of
    // those the CPU has); every one gives the same map bit for bit.
    const char* old = std::getenv("RS_CONE_SEARCH_ISA");
    const std::string saved = old ? old : "";
    const std::vector<DepthField> fields = {
        RandomField(70, 53, 5, false),
        QuantizeToUnorm8(MakeBuiltinMap("shapes", 96, 96))};
    for (const DepthField& hf : fields)
        for (ConeKind k : {ConeKind::Cone, ConeKind::Quad, ConeKind::Acm4, ConeKind::Acm8,
                           ConeKind::RelaxedExact, ConeKind::Stacked}) {
            setenv("RS_CONE_SEARCH_ISA", "sse4.1", 1);
            ASSERT_STREQ(detail::ConeSearchIsa(), "sse4.1");
            const ConeMap ref = GenerateConeMap(hf, k);
            for (const char* isa : {"avx2", "avx512"}) {
                setenv("RS_CONE_SEARCH_ISA", isa, 1);
                if (std::string(detail::ConeSearchIsa()) != isa)
                    continue;  // CPU lacks it
                ExpectBitEqual(GenerateConeMap(hf, k), ref,
                               hf.name + " " + std::string(ToString(k)) + " " + isa);
            }
        }
    if (old)
        setenv("RS_CONE_SEARCH_ISA", saved.c_str(), 1);
    else
        unsetenv("RS_CONE_SEARCH_ISA");
}

TEST(ConeMap, RelaxedFastEqualsListingBruteForce) {
    ConeMapParams p;
    p.searchSteps = 32;
    for (const DepthField& hf :
         {MakeBuiltinMap("shapes", 32, 32), RandomField(32, 32, 5, true),
          QuantizeToUnorm8(MakeBuiltinMap("bumps", 24, 24))})
        ExpectBitEqual(GenerateConeMap(hf, ConeKind::Relaxed, p),
                       GenerateConeMapBruteForce(hf, ConeKind::Relaxed, p),
                       hf.name + " relaxed");
    p.searchSteps = 128;
    for (const DepthField& hf : {MakeBuiltinMap("steps", 32, 32),
                                 QuantizeToUnorm8(MakeBuiltinMap("shapes", 48, 48)),
                                 RandomField(40, 40, 6, false),
                                 QuantizeToUnorm8(MakeBuiltinMap("noise", 40, 40)),
                                 RandomField(36, 20, 12, true)})
        ExpectBitEqual(GenerateConeMap(hf, ConeKind::Relaxed, p),
                       GenerateConeMapBruteForce(hf, ConeKind::Relaxed, p),
                       hf.name + " relaxed 128 " + std::to_string(hf.width));
    // Maps smaller than the exit field's window (at least 8 texels each way) and its
    // 32x32 super-tiles: the window wraps around the map several times.
    for (const DepthField& hf :
         {RandomField(9, 5, 13, true), RandomField(2, 7, 14, false),
          RandomField(1, 3, 15, true), RandomField(17, 1, 16, false)})
        ExpectBitEqual(GenerateConeMap(hf, ConeKind::Relaxed, p),
                       GenerateConeMapBruteForce(hf, ConeKind::Relaxed, p),
                       hf.name + " relaxed 128 " + std::to_string(hf.width) + "x" +
                           std::to_string(hf.height));
}

/// A plateau at depth 0.5 with a few deeper and higher texels: most nearest deeper cells
/// lie beyond the exit field's search window, whose edge then bounds the march.
DepthField PlateauField(int n) {
    DepthField hf;
    hf.width = hf.height = n;
    hf.name = "plateau";
    hf.depth.assign(size_t(n) * size_t(n), 0.5f);
    hf.depth[size_t(3 * n + 5)] = 1.0f;
    hf.depth[size_t((n - 2) * n + n / 2)] = 0.9f;
    hf.depth[size_t((n / 2) * n + n / 3)] = 0.1f;
    hf.depth[size_t((n / 3) * n + n - 1)] = 0.2f;
    return hf;
}

TEST(ConeMap, RelaxedFastEqualsListingBruteForceAt64And128) {
    // The sizes with the Listing's 128 steps: every built-in, float and 8-bit, at
    // 64²; an 8-bit built-in and a random float map at 128².
    for (const char* name : {"shapes", "bumps", "steps", "noise"})
        for (bool q : {false, true}) {
            const DepthField f = MakeBuiltinMap(name, 64, 64);
            const DepthField hf = q ? QuantizeToUnorm8(f) : f;
            ExpectBitEqual(GenerateConeMap(hf, ConeKind::Relaxed),
                           GenerateConeMapBruteForce(hf, ConeKind::Relaxed),
                           std::string(name) + (q ? " u8" : " float") + " 64");
        }
    for (const DepthField& hf : {QuantizeToUnorm8(MakeBuiltinMap("shapes", 128, 128)),
                                 RandomField(128, 128, 31, true)})
        ExpectBitEqual(GenerateConeMap(hf, ConeKind::Relaxed),
                       GenerateConeMapBruteForce(hf, ConeKind::Relaxed),
                       hf.name + " 128");
}

TEST(ConeMap, RelaxedWindowsAheadMatchBruteForce) {
    // Smooth periodic maps, whose marches travel far through cells no deeper than the
    // ray: the search proves that travel with the depth maxima of windows up to 128x128
    // ahead of the destination (AheadPrunes), and the brute force checks every pair it
    // skips.
    const auto waves = [](int w, int h, double amp, int periods) {
        return testing::MakeField(
            w, h,
            [=](int i, int j) {
                const double tau = 2.0 * std::numbers::pi * periods;
                return float(0.5 + amp * std::sin(tau * (i + 0.5) / w) *
                                       std::cos(tau * (j + 0.5) / h));
            },
            "waves");
    };
    // A ribbon whose only pair below 1 travels 40 texels: the apex column (x = 10, depth
    // 1) sees one destination column (x = 23, depth 0.1) across cells at depth 0 (never
    // destinations: the listing's NaN; never deeper than the ray), and its march stops in
    // the trench at x = 63..70 (depth 1), 40 texels on, at ratio ~0.70. The windows ahead
    // prove a travel of 31.5 texels (the 32x32 window holds no deeper cell) but not more
    // (the 64x64 one holds the trench); along x and y, forwards and mirrored.
    const auto ribbon = [](bool alongY, bool mirrored) {
        const int n = 128, across = 4;
        return testing::MakeField(
            alongY ? across : n, alongY ? n : across,
            [=](int i, int j) {
                int x = alongY ? j : i;
                if (mirrored) x = n - 1 - x;
                if (x == 10) return 1.0f;
                if (x == 23) return 0.1f;
                if (x >= 63 && x <= 70) return 1.0f;
                return 0.0f;
            },
            "ribbon");
    };
    const ConeMap far = GenerateConeMap(ribbon(false, false), ConeKind::Relaxed);
    EXPECT_NEAR(far.values[10], 0.70, 0.02);  // the apex column's only pair below 1
    for (bool alongY : {false, true})
        for (bool mirrored : {false, true}) {
            const DepthField hf = ribbon(alongY, mirrored);
            ExpectBitEqual(GenerateConeMap(hf, ConeKind::Relaxed),
                           GenerateConeMapBruteForce(hf, ConeKind::Relaxed),
                           std::string("ribbon") + (alongY ? " along y" : " along x") +
                               (mirrored ? " mirrored" : ""));
        }
    // As generated, and with the windows ahead tried on every pair the exit bound keeps
    // (the search tries them on one pair in 16 where they have rarely pruned).
    for (const DepthField& hf :
         {waves(64, 64, 0.3, 1), waves(96, 80, 0.1, 1), waves(72, 72, 0.4, 2)}) {
        const ConeMap brute = GenerateConeMapBruteForce(hf, ConeKind::Relaxed);
        for (const bool every : {false, true})
            ExpectBitEqual(detail::RelaxedListingMap(hf, ConeMapParams{}, false,
                                                     ConeKind::Relaxed, true, every),
                           brute,
                           hf.name + " " + std::to_string(hf.width) + "x" +
                               std::to_string(hf.height) + (every ? " every pair" : ""));
    }
}

TEST(ConeMap, RelaxedProvenTravelIsTight) {
    // The travel the search proves before marching a pair is tight: a ribbon (256x4, apex
    // column at x = 10, depth 1) with one destination d texels on whose march stops in a
    // trench starting exactly k cells past it (so its true travel is just over k - 1/2
    // texels, what a clear k-window proves), and a competing destination the other way,
    // nearer, found first, whose pair (it stops on the next cell, a wall) gives the least
    // ratio above the trench pair's. Overstating the proven travel by a small fraction of
    // a texel would prune the trench pair and leave the competitor's ratio. k = 8 is
    // within the exit field's window (32 texels), k = 32 and 64 only in the windows
    // ahead; along x and y, forwards and mirrored. Cells at depth 0 are never
    // destinations (the listing's NaN) and never deeper than a ray. 1024 steps: a ratio
    // moves by one step's depth, (1 - b) / steps, where the number of steps to a stop
    // changes; at 128 that jump (~1.3%) leaves no competitor close enough.
    constexpr int n = 256, across = 4, src = 1, steps = 1024;
    ConeMapParams p;
    p.searchSteps = steps;
    struct Case {
        int k, d;
        float b;
    };
    for (const Case c : {Case{8, 14, 0.35f}, Case{32, 14, 0.22f}, Case{64, 14, 0.11f}})
        for (const bool alongY : {false, true})
            for (const bool mirrored : {false, true}) {
                // Ribbon coordinate x (0..n) to the map's texel, and offsets along it.
                const auto texel = [&](int x) {
                    const int t = mirrored ? Wrap(2 * src - x, n) : x;
                    return alongY ? std::pair{0, t} : std::pair{t, 0};
                };
                const auto offset = [&](int dx) {
                    const int t = mirrored ? -dx : dx;
                    return alongY ? std::pair{0, t} : std::pair{t, 0};
                };
                const auto ribbon = [&](int d2, float b2) {
                    return testing::MakeField(
                        alongY ? across : n, alongY ? n : across,
                        [&](int i, int j) {
                            int x = alongY ? j : i;
                            if (mirrored) x = Wrap(2 * src - x, n);
                            if (x == src) return 1.0f;
                            if (x == src + c.d) return c.b;
                            if (x >= src + c.d + c.k && x < src + c.d + c.k + 8)
                                return 1.0f;
                            if (x == src + d2) return b2;
                            if (x == src + d2 + 1) return 1.0f;
                            return 0.0f;
                        },
                        "ribbon");
                };
                const std::string what = "trench " + std::to_string(c.k) + " cells on" +
                                         (alongY ? " along y" : " along x") +
                                         (mirrored ? " mirrored" : "");
                // Named, not structured bindings: C++20 lets a lambda capture those, but
                // clang 14 does not.
                const std::pair<int, int> st = texel(src);
                const int si = st.first, sj = st.second;
                const auto ratio = [&](int d2, float b2, int dx) {
                    const auto [ox, oy] = offset(dx);
                    return detail::RelaxedPairRatio(ribbon(d2, b2), si, sj, ox, oy, steps,
                                                    1.0f);
                };
                const float trench = ratio(2, 0.5f, c.d);
                ASSERT_LT(trench, 1.0f) << what;
                // The competitor: for each distance nearer than the trench pair's
                // destination, bisection on its depth to the least ratio above the trench
                // pair's (the ratio jumps where the listing's stopping sample changes:
                // the least of several distances).
                float competitor = std::numeric_limits<float>::infinity(), b2 = 0;
                int d2 = 0;
                for (int e = 2; e <= c.d - 8; ++e) {
                    float lo = 0.3f, hi = 0.999f;
                    ASSERT_LE(ratio(e, lo, e), trench) << what;
                    ASSERT_GT(ratio(e, hi, e), trench) << what;
                    for (int it = 0; it < 64 && std::nextafter(lo, hi) < hi; ++it) {
                        const float mid = 0.5f * (lo + hi);
                        (ratio(e, mid, e) > trench ? hi : lo) = mid;
                    }
                    if (ratio(e, hi, e) < competitor) {
                        competitor = ratio(e, hi, e);
                        b2 = hi;
                        d2 = e;
                    }
                }
                const DepthField hf = ribbon(d2, b2);
                ASSERT_GT(competitor, trench) << what;
                ASSERT_LT(competitor, trench * 1.003f) << what;
                // As generated, and with the windows ahead tried on every pair (the
                // search tries them on one pair in 16 where they have rarely pruned).
                const ConeMap brute = GenerateConeMapBruteForce(hf, ConeKind::Relaxed, p);
                for (const bool every : {false, true}) {
                    const ConeMap m = detail::RelaxedListingMap(
                        hf, p, false, ConeKind::Relaxed, true, every);
                    EXPECT_EQ(m.values[size_t(sj) * size_t(hf.width) + size_t(si)],
                              trench)
                        << what << (every ? " every pair" : "");
                    ExpectBitEqual(m, brute, what + (every ? " every pair" : ""));
                }
            }
}

TEST(ConeMap, RelaxedVariantsMatchTheirBruteForce) {
    // Every path of the pruned relaxed search against the listing evaluated for every
    // pair: steps not a power of two (divisions), 1 step (no loop), 4096 steps, the
    // window edge of the exit field (plateau), zero depths (the listing's NaN), stacked
    // and cone-normal output.
    ConeMapParams p;
    for (int steps : {37, 1, 4096}) {
        p.searchSteps = steps;
        const DepthField hf = steps == 4096
                                  ? QuantizeToUnorm8(MakeBuiltinMap("shapes", 16, 16))
                                  : QuantizeToUnorm8(MakeBuiltinMap("noise", 24, 24));
        ExpectBitEqual(GenerateConeMap(hf, ConeKind::Relaxed, p),
                       GenerateConeMapBruteForce(hf, ConeKind::Relaxed, p),
                       "relaxed steps " + std::to_string(steps));
    }
    p.searchSteps = 128;
    DepthField zeros = RandomField(28, 28, 21, false);
    for (size_t t = 0; t < zeros.depth.size(); t += 7) zeros.depth[t] = 0.0f;
    for (const DepthField& hf : {PlateauField(48), zeros})
        ExpectBitEqual(GenerateConeMap(hf, ConeKind::Relaxed, p),
                       GenerateConeMapBruteForce(hf, ConeKind::Relaxed, p), hf.name);
    p.relaxed = true;
    p.stackedCount = 3;
    for (ConeKind k : {ConeKind::Stacked, ConeKind::ConeNormal}) {
        const DepthField hf = QuantizeToUnorm8(MakeBuiltinMap("shapes", 32, 32));
        const ConeMap fast = GenerateConeMap(hf, k, p);
        EXPECT_EQ(fast.channels, k == ConeKind::Stacked ? 3 : 1);
        ExpectBitEqual(fast, GenerateConeMapBruteForce(hf, k, p),
                       "relaxed " + std::string(ToString(k)));
    }
}

TEST(ConeMap, StackedNormalIsNzOfEachStackedCone) {
    // --normal stores n_z = r / sqrt(1 + r^2) of each stacked cone (1 when unbounded),
    // rounded down: never wider than the ratio it comes from; fast equals brute force.
    const DepthField hf = MakeBuiltinMap("shapes", 32, 32);
    ConeMapParams p;
    const ConeMap ratios = GenerateConeMap(hf, ConeKind::Stacked, p);
    p.normal = true;
    const ConeMap normals = GenerateConeMap(hf, ConeKind::Stacked, p);
    ExpectBitEqual(normals, GenerateConeMapBruteForce(hf, ConeKind::Stacked, p),
                   "stacked --normal");
    ASSERT_EQ(normals.values.size(), ratios.values.size());
    size_t unbounded = 0;
    for (size_t i = 0; i < ratios.values.size(); ++i) {
        const double r = double(ratios.values[i]), n = double(normals.values[i]);
        if (r >= double(kConeRatioCap)) {
            EXPECT_EQ(n, 1.0) << i;
            ++unbounded;
            continue;
        }
        EXPECT_LE(n, r / std::sqrt(1.0 + r * r)) << i;
        EXPECT_NEAR(n, r / std::sqrt(1.0 + r * r), 1e-6) << i;
    }
    EXPECT_GT(unbounded, 0u);  // the highest cones of the tallest texels
    EXPECT_THROW(GenerateConeMap(hf, ConeKind::Cone, p), Error);  // stacked only
}

TEST(ConeMap, RelaxedSearchWithoutExitFieldMatchesBruteForce) {
    // Large maps with many steps (e.g. > 2040 texels a side at 4096 steps) search without
    // the exit-field bound; the same code path, forced on small maps.
    ConeMapParams p;
    p.searchSteps = 64;
    for (const DepthField& hf : {QuantizeToUnorm8(MakeBuiltinMap("shapes", 40, 40)),
                                 RandomField(32, 24, 17, true)}) {
        const ConeMap brute = GenerateConeMapBruteForce(hf, ConeKind::Relaxed, p);
        ExpectBitEqual(detail::RelaxedListingMap(hf, p, false, ConeKind::Relaxed, false),
                       brute, hf.name + " without exit field");
        ExpectBitEqual(detail::RelaxedListingMap(hf, p, false, ConeKind::Relaxed, true),
                       brute, hf.name + " with exit field");
    }
}

TEST(ConeMap, RelaxedSearchIsTheSameOnEveryInstructionSet) {
    // The pruned relaxed search runs its bounds, its exit field's build and its marches
    // with AVX-512 where the lane search does (RS_CONE_SEARCH_ISA), else scalar: both
    // equal the listing evaluated for every pair, on every path: power-of-two steps
    // (products) and others (divisions), one step, 4096 steps, zero depths (NaN), a
    // plateau (the exit field's window edge), without the exit field, stacked channels,
    // and destinations so shallow that the march's first step lands far outside the map
    // (texel coordinates outside [-n, 2n) and beyond 2^30, sampled by the scalar wrap).
    const char* old = std::getenv("RS_CONE_SEARCH_ISA");
    const std::string saved = old ? old : "";
    DepthField zeros = RandomField(28, 28, 21, false);
    for (size_t t = 0; t < zeros.depth.size(); t += 7) zeros.depth[t] = 0.0f;
    DepthField shallow = RandomField(32, 32, 8, false);
    for (size_t t = 0; t < shallow.depth.size(); t += 5)
        shallow.depth[t] = t % 2 ? 1e-6f : 1e-30f;
    shallow.name = "shallow";
    // Depths k/8 with 8 steps: the march's z (b + i (1 - b) / 8) is exact and often equal
    // to a sampled depth, where the listing goes on (depth <= z).
    DepthField dyadic = RandomField(32, 32, 4, false);
    for (float& d : dyadic.depth) d = d < 0.4f ? 0.5f : d < 0.8f ? 0.625f : 1.0f;
    dyadic.name = "dyadic";
    struct Case {
        DepthField hf;
        int steps;
        ConeKind kind;
        bool exitField;
    };
    const std::vector<Case> cases = {
        {QuantizeToUnorm8(MakeBuiltinMap("shapes", 48, 48)), 128, ConeKind::Relaxed,
         true},
        {RandomField(40, 36, 6, true), 128, ConeKind::Relaxed, true},
        {MakeBuiltinMap("noise", 40, 40), 37, ConeKind::Relaxed, true},
        {QuantizeToUnorm8(MakeBuiltinMap("bumps", 24, 24)), 1, ConeKind::Relaxed, true},
        {QuantizeToUnorm8(MakeBuiltinMap("shapes", 16, 16)), 4096, ConeKind::Relaxed,
         true},
        {zeros, 128, ConeKind::Relaxed, true},
        {PlateauField(48), 128, ConeKind::Relaxed, true},
        {shallow, 128, ConeKind::Relaxed, true},
        {dyadic, 8, ConeKind::Relaxed, true},
        {RandomField(32, 24, 17, true), 64, ConeKind::Relaxed, false},
        {QuantizeToUnorm8(MakeBuiltinMap("shapes", 32, 32)), 128, ConeKind::Stacked,
         true},
    };
    size_t compared = 0;
    for (const Case& c : cases) {
        ConeMapParams p;
        p.searchSteps = c.steps;
        if (c.kind == ConeKind::Stacked) {
            p.relaxed = true;
            p.stackedCount = 3;
        }
        const std::string what = c.hf.name + " steps " + std::to_string(c.steps);
        const ConeMap brute = GenerateConeMapBruteForce(c.hf, c.kind, p);
        for (const char* isa : {"sse4.1", "avx512"}) {
            setenv("RS_CONE_SEARCH_ISA", isa, 1);
            if (std::string(detail::ConeSearchIsa()) != isa) continue;  // CPU lacks it
            ++compared;
            const ConeMap fast =
                c.kind == ConeKind::Relaxed
                    ? detail::RelaxedListingMap(c.hf, p, false, c.kind, c.exitField)
                    : GenerateConeMap(c.hf, c.kind, p);
            ExpectBitEqual(fast, brute, what + " " + isa);
        }
    }
    EXPECT_GE(compared, cases.size());  // sse4.1 runs everywhere
    if (old)
        setenv("RS_CONE_SEARCH_ISA", saved.c_str(), 1);
    else
        unsetenv("RS_CONE_SEARCH_ISA");
}

TEST(ConeMap, RelaxedExitFieldScanEqualsEveryCell) {
    // The exit field's scan visits super-tiles and tiles in order of distance and skips
    // those whose depth maxima hold no deeper cell, and sectors whose code no cell of the
    // tile can lower; taking every cell of the window, in no order, gives the same codes,
    // scalar, AVX2 and AVX-512: float, 8-bit and random depths, zero depths, a plateau,
    // non-square maps, maps larger than a super-tile's window and maps smaller than the
    // window (wrapping more than once), steps that divide (37) and powers of two.
    const char* old = std::getenv("RS_CONE_SEARCH_ISA");
    const std::string saved = old ? old : "";
    DepthField zeros = RandomField(28, 28, 21, false);
    for (size_t t = 0; t < zeros.depth.size(); t += 7) zeros.depth[t] = 0.0f;
    const std::vector<std::pair<DepthField, int>> cases = {
        {RandomField(40, 36, 6, true), 128},
        {RandomField(7, 5, 3, false), 128},
        {MakeBuiltinMap("noise", 96, 80), 37},
        {QuantizeToUnorm8(MakeBuiltinMap("shapes", 128, 128)), 128},
        {MakeBuiltinMap("shapes", 200, 184), 128},
        {zeros, 8},
        {PlateauField(48), 128},
    };
    size_t compared = 0;
    for (const auto& [hf, steps] : cases) {
        const std::string what = hf.name + " " + std::to_string(hf.width) + "x" +
                                 std::to_string(hf.height) + " steps " +
                                 std::to_string(steps);
        const std::vector<uint8_t> every = detail::RelaxedExitField(hf, steps, false);
        ASSERT_EQ(every.size(), hf.depth.size() * 16) << what;
        // Not a field of one value: distances were found inside the window.
        size_t found = 0;
        for (uint8_t c : every) found += c > 0 && c < 254 ? 1 : 0;
        EXPECT_GT(found, 0u) << what;
        for (const char* isa : {"sse4.1", "avx2", "avx512"}) {
            setenv("RS_CONE_SEARCH_ISA", isa, 1);
            if (std::string(detail::ConeSearchIsa()) != isa) continue;  // CPU lacks it
            ++compared;
            const std::vector<uint8_t> scan = detail::RelaxedExitField(hf, steps, true);
            ASSERT_EQ(scan.size(), every.size()) << what;
            size_t differ = 0, first = scan.size();
            for (size_t t = 0; t < scan.size(); ++t)
                if (scan[t] != every[t]) {
                    ++differ;
                    first = std::min(first, t);
                }
            EXPECT_EQ(differ, 0u) << what << " " << isa << ": first at texel "
                                  << first / 16 << " sector " << first % 16;
        }
    }
    EXPECT_GE(compared, cases.size());  // sse4.1 runs everywhere
    if (old)
        setenv("RS_CONE_SEARCH_ISA", saved.c_str(), 1);
    else
        unsetenv("RS_CONE_SEARCH_ISA");
}

TEST(ConeMap, StackedRelaxedChannelsWidenUpwards) {
    // Channel 0 (apex on the surface) is the relaxed map itself; a higher apex (channel
    // k) sees fewer destinations above it and a shorter height to every exit point, so
    // its ratio is never smaller.
    const DepthField hf = QuantizeToUnorm8(MakeBuiltinMap("shapes", 48, 48));
    ConeMapParams p;
    p.relaxed = true;
    p.stackedCount = 4;
    const ConeMap st = GenerateConeMap(hf, ConeKind::Stacked, p);
    const ConeMap rel = GenerateConeMap(hf, ConeKind::Relaxed, p);
    size_t widened = 0;
    for (int j = 0; j < hf.height; ++j)
        for (int i = 0; i < hf.width; ++i) {
            ASSERT_EQ(st.At(i, j, 0), rel.At(i, j)) << i << "," << j;
            for (int c = 1; c < 4; ++c) {
                ASSERT_GE(st.At(i, j, c), st.At(i, j, c - 1))
                    << i << "," << j << " cone " << c;
                widened += st.At(i, j, c) > st.At(i, j, c - 1);
            }
        }
    EXPECT_GT(widened, size_t(hf.width * hf.height));  // the stack adds information
}

TEST(ConeMap, RelaxedIsNeverNarrowerThanConservative) {
    // A destination is a texel above the apex and the listing's exit point lies beyond it
    // and deeper, so every relaxed ratio is at least the conservative bound of that
    // texel.
    for (const DepthField& hf : {QuantizeToUnorm8(MakeBuiltinMap("bumps", 64, 64)),
                                 RandomField(40, 40, 3, true)}) {
        const ConeMap cone = GenerateConeMap(hf, ConeKind::Cone);
        const ConeMap rel = GenerateConeMap(hf, ConeKind::Relaxed);
        for (size_t t = 0; t < cone.values.size(); ++t)
            ASSERT_GE(rel.values[t], std::min(cone.values[t], 1.0f))
                << hf.name << " texel " << t;
    }
}

TEST(ConeMap, ProgressIsReportedInGrowingWholePercents) {
    // The lane search (acm8 on a square map: one pass per rip-map) and the relaxed
    // search each report up to 100 growing fractions ending at 1; the map does not
    // depend on whether progress is reported.
    const DepthField hf = QuantizeToUnorm8(MakeBuiltinMap("shapes", 96, 96));
    for (ConeKind k :
         {ConeKind::Cone, ConeKind::Acm4, ConeKind::Acm8, ConeKind::Relaxed}) {
        std::vector<double> seen;
        ConeMapParams p;
        p.searchSteps = 32;
        p.progress = [&](double f) { seen.push_back(f); };  // serialised by the generator
        const ConeMap with = GenerateConeMap(hf, k, p);
        p.progress = nullptr;
        ExpectBitEqual(with, GenerateConeMap(hf, k, p),
                       std::string(ToString(k)) + " progress");
        ASSERT_FALSE(seen.empty()) << ToString(k);
        EXPECT_LE(seen.size(), 100u) << ToString(k);
        EXPECT_EQ(seen.back(), 1.0) << ToString(k);
        for (size_t i = 1; i < seen.size(); ++i)
            EXPECT_GT(seen[i], seen[i - 1]) << ToString(k);
    }
}

TEST(ConeMap, RelaxedWorkedExampleOfTheDocs) {
    // docs/cone_maps.md, "Worked example: relaxed vs relaxed-exact": a 16x16 map whose
    // depth depends on the column only; apex texel i = 1.
    DepthField hf;
    hf.width = hf.height = 16;
    hf.name = "example";
    const float col[16] = {0.75f, 0.75f, 0.5f, 0.25f, 0.25f, 0.25f, 0.25f, 1,
                           1,     1,     1,    1,     1,     1,     1,     0.75f};
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) hf.depth.push_back(col[i]);
    EXPECT_FLOAT_EQ(GenerateConeMap(hf, ConeKind::Cone).At(1, 5),
                    0.25f);  // (1/16) / 0.25
    EXPECT_FLOAT_EQ(GenerateConeMap(hf, ConeKind::RelaxedExact).At(1, 5),
                    0.625f);  // (5/16) / 0.5
    ConeMapParams p;
    // The march from destination i = 6 stops k steps out, in texel 7 (closed form in the
    // docs): (u_k - 1.5/16) / (0.75 - z_k) with u_k = 6.5/16 + k du, z_k = 0.25 + k dz.
    auto listing = [](int steps, int k) {
        const double du = (0.3125 / 0.25) * 0.75 / steps, dz = 0.75 / steps;
        return (6.5 / 16 + k * du - 1.5 / 16) / (0.75 - (0.25 + k * dz));
    };
    p.searchSteps = 128;
    EXPECT_NEAR(GenerateConeMap(hf, ConeKind::Relaxed, p).At(1, 5), listing(128, 5),
                1e-5);
    EXPECT_NEAR(GenerateConeMap(hf, ConeKind::Relaxed, p).At(1, 5), 0.7417, 5e-5);
    p.searchSteps = 16;
    EXPECT_NEAR(GenerateConeMap(hf, ConeKind::Relaxed, p).At(1, 5), listing(16, 1), 1e-5);
    EXPECT_NEAR(GenerateConeMap(hf, ConeKind::Relaxed, p).At(1, 5), 0.8190, 5e-5);
    p.searchSteps = 4;
    EXPECT_EQ(GenerateConeMap(hf, ConeKind::Relaxed, p).At(1, 5), 1.0f);
}

/// Exact real-number check: no texel above the apex lies strictly inside the stored cone.
void ExpectConservative(const DepthField& hf, const ConeMap& m) {
    const int W = hf.width, H = hf.height;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const auto r = static_cast<long double>(m.At(i, j));
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    const float db = hf.At(x, y), dt = hf.At(i, j);
                    if (!(db < dt)) continue;
                    const int dx = std::min(std::abs(x - i), W - std::abs(x - i));
                    const int dy = std::min(std::abs(y - j), H - std::abs(y - j));
                    const long double dist =
                        std::sqrt((long double)(dx)*dx / ((long double)W * W) +
                                  (long double)(dy)*dy / ((long double)H * H));
                    ASSERT_LE(
                        r * (static_cast<long double>(dt) - static_cast<long double>(db)),
                        dist)
                        << "texel " << i << "," << j << " blocker " << x << "," << y
                        << " r " << double(r) << " dt " << dt << " db " << db;
                }
        }
}

TEST(ConeMap, ConservativeAfterEncoding) {
    const DepthField hf = QuantizeToUnorm8(MakeBuiltinMap("shapes", 32, 32));
    const ConeMap exact = GenerateConeMap(hf, ConeKind::Cone);
    ExpectConservative(hf, exact);
    for (ConeEncoding e : {ConeEncoding::U8, ConeEncoding::U8Sqrt, ConeEncoding::U16})
        ExpectConservative(hf, QuantizeConeMap(exact, e));
    const DepthField rnd = RandomField(24, 24, 2, false);
    ExpectConservative(rnd, GenerateConeMap(rnd, ConeKind::Cone));
}

TEST(ConeMap, EncodingNeverWidens) {
    for (uint64_t s = 0; s < 20000; ++s) {
        const float r = float(Mix64(s) >> 40) * (1.3f / 16777216.0f);
        for (ConeEncoding e :
             {ConeEncoding::U8, ConeEncoding::U8Sqrt, ConeEncoding::U16}) {
            const uint16_t c = EncodeRatio(r, e);
            ASSERT_LE(DecodeRatio(c, e), r) << r << " " << ToString(e);
            if (r <= 1.0f && c < (e == ConeEncoding::U16 ? 65535 : 255)) {
                ASSERT_GT(DecodeRatio(uint16_t(c + 1), e), r)
                    << "not the nearest code below";
            }
        }
    }
}

TEST(ConeMap, BilinearSafetyPassStaysConservative) {
    const DepthField hf = MakeBuiltinMap("shapes", 64, 64);
    const ConeMap exact = GenerateConeMap(hf, ConeKind::Cone);
    const ConeMap safe = QuantizeConeMap(BilinearSafetyPass(exact), ConeEncoding::U8);
    DepthField tex;  // the map as a texture for the project's bilinear sampler
    tex.width = safe.width;
    tex.height = safe.height;
    tex.depth = safe.values;
    for (uint64_t s = 0; s < 20000; ++s) {
        const float u = float(Mix64(2 * s) >> 40) / 16777216.0f;
        const float v = float(Mix64(2 * s + 1) >> 40) / 16777216.0f;
        // Footprint texels and their exact ratios.
        const float x = u * 64.0f - 0.5f, y = v * 64.0f - 0.5f;
        const int i0 = int(std::floor(x)), j0 = int(std::floor(y));
        float lo = kConeRatioCap;
        float hiSafe = 0;
        for (int d = 0; d < 4; ++d) {
            const int i = (i0 + (d & 1) + 64) % 64, j = (j0 + (d >> 1) + 64) % 64;
            lo = std::min(lo, exact.At(i, j));
            hiSafe = std::max(hiSafe, safe.At(i, j));
        }
        // Any weighted mean of the four safe values is <= their max <= the smallest exact
        // one.
        ASSERT_LE(hiSafe, lo) << u << "," << v;
    }
}

TEST(ConeMap, AdaptiveNeverWider) {
    for (const DepthField& hf :
         {MakeBuiltinMap("shapes", 64, 64), MakeBuiltinMap("bumps", 64, 64),
          RandomField(64, 64, 4, true), RandomField(48, 40, 4, false)})
        for (ConeKind k :
             {ConeKind::Cone, ConeKind::Quad, ConeKind::Acm4, ConeKind::Acm8}) {
            const ConeMap exact = GenerateConeMap(hf, k);
            for (float th : {0.0f, 0.05f, 1.0f})
                for (int levels : {1, 3}) {
                    AdaptiveStats st;
                    const ConeMap a = GenerateAdaptiveSectorMap(hf, k, th, levels, &st);
                    for (size_t t = 0; t < a.values.size(); ++t) {
                        ASSERT_LE(a.values[t], exact.values[t])
                            << hf.name << " " << ToString(k) << " th " << th << " at "
                            << t;
                    }
                    if (th == 0.0f) {
                        EXPECT_GT(st.nSearched, 0);
                    }
                }
        }
}

TEST(ConeMap, AdaptiveWithZeroLevelsIsExact) {
    const DepthField hf = MakeBuiltinMap("shapes", 32, 32);
    ExpectBitEqual(GenerateAdaptiveSectorMap(hf, ConeKind::Acm4, 0.5f, 0),
                   GenerateConeMap(hf, ConeKind::Acm4), "levels 0");
}

TEST(ConeMap, SectorsAreAtLeastTheConservativeRatio) {
    const DepthField hf = MakeBuiltinMap("shapes", 32, 32);
    const ConeMap c = GenerateConeMap(hf, ConeKind::Cone);
    for (ConeKind k :
         {ConeKind::Quad, ConeKind::Acm4, ConeKind::Acm8, ConeKind::RelaxedExact}) {
        const ConeMap s = GenerateConeMap(hf, k);
        for (int t = 0; t < 32 * 32; ++t) {
            float mn = kConeRatioCap;
            for (int ch = 0; ch < s.channels; ++ch)
                mn = std::min(mn, s.values[size_t(t * s.channels + ch)]);
            if (k != ConeKind::RelaxedExact) {
                ASSERT_EQ(mn, c.values[size_t(t)])
                    << ToString(k);  // min over sectors = cone
            }
            if (k == ConeKind::RelaxedExact) {
                ASSERT_GE(s.values[size_t(t)], c.values[size_t(t)]);
            }
        }
    }
}

TEST(ConeMap, DeterministicForAnyThreadCount) {
    const DepthField hf = QuantizeToUnorm8(MakeBuiltinMap("noise", 96, 96));
    ConeMap one, two;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = GenerateConeMap(hf, ConeKind::Cone);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 4);
        two = GenerateConeMap(hf, ConeKind::Cone);
    }
    ExpectBitEqual(one, two, "threads");
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = GenerateConeMap(hf, ConeKind::Relaxed);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 4);
        two = GenerateConeMap(hf, ConeKind::Relaxed);
    }
    ExpectBitEqual(one, two, "relaxed threads");
}

TEST(ConeMap, MipPyramidsReduceWrapAwareForOddSizes) {
    std::vector<float> v = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};  // 5 x 3
    const auto mn = BuildMipPyramid(v, 5, 3, 1, MipReduce::Min);
    const auto mx = BuildMipPyramid(v, 5, 3, 1, MipReduce::Max);
    ASSERT_EQ(mn.size(), 4u);  // 5x3, 3x2, 2x1, 1x1
    EXPECT_EQ(mn[1].width, 3);
    EXPECT_EQ(mn[1].height, 2);
    EXPECT_EQ(mn[1].At(2, 0), 1.0f);   // covers columns 4 and 0 (wrap)
    EXPECT_EQ(mx[1].At(2, 1), 15.0f);  // covers rows 2 and 0 (wrap)
    EXPECT_EQ(mn.back().At(0, 0), 1.0f);
    EXPECT_EQ(mx.back().At(0, 0), 15.0f);
}

TEST(ConeMap, CacheDetectsCorruptAndStaleEntries) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("rs_cone_cache_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    MapCache cache(dir.string());
    const DepthField hf = MakeBuiltinMap("shapes", 16, 16);
    int made = 0;
    auto make = [&] {
        ++made;
        return GenerateConeMap(hf, ConeKind::Cone);
    };
    bool hit = true;
    const ConeMap a = cache.GetOrCreate(hf, ConeKind::Cone, {}, make, &hit);
    EXPECT_FALSE(hit);
    const ConeMap b = cache.GetOrCreate(hf, ConeKind::Cone, {}, make, &hit);
    EXPECT_TRUE(hit);
    ExpectBitEqual(a, b, "cache round trip");
    // Corrupt one payload byte: detected, regenerated.
    const std::string path = cache.PathFor(ConeMapCacheKey(hf, ConeKind::Cone, {}));
    {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(60);
        f.put('\x7f');
    }
    cache.GetOrCreate(hf, ConeKind::Cone, {}, make, &hit);
    EXPECT_FALSE(hit);
    // Truncated file.
    std::filesystem::resize_file(path, 20);
    cache.GetOrCreate(hf, ConeKind::Cone, {}, make, &hit);
    EXPECT_FALSE(hit);
    // Other pixels or parameters: other key.
    DepthField hf2 = hf;
    hf2.depth[5] = 0.123f;
    EXPECT_NE(ConeMapCacheKey(hf, ConeKind::Cone, {}),
              ConeMapCacheKey(hf2, ConeKind::Cone, {}));
    ConeMapParams p;
    p.searchSteps = 64;
    EXPECT_NE(ConeMapCacheKey(hf, ConeKind::Relaxed, {}),
              ConeMapCacheKey(hf, ConeKind::Relaxed, p));
    EXPECT_EQ(made, 3);
    std::filesystem::remove_all(dir);
}

TEST(ConeMap, BadInputGivesOneClearError) {
    DepthField hf = MakeBuiltinMap("flat", 8, 8);
    hf.depth[3] = std::nanf("");
    EXPECT_THROW(GenerateConeMap(hf, ConeKind::Cone), Error);
    DepthField empty;
    empty.name = "empty";
    try {
        GenerateConeMap(empty, ConeKind::Cone);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("zero size"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(ParseConeKind("cones").has_value());
    EXPECT_NE(ConeKindList().find("\"relaxed-exact\""), std::string::npos);
    ConeMapParams p;
    p.searchSteps = 0;
    EXPECT_THROW(GenerateConeMap(MakeBuiltinMap("flat", 8, 8), ConeKind::Relaxed, p),
                 Error);
}

TEST(ConeMap, WriteIsAtomicAndRejectsBadExtension) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("rs_cone_out_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const ConeMap m = GenerateConeMap(MakeBuiltinMap("shapes", 16, 16), ConeKind::Acm8);
    EXPECT_THROW(WriteConeMap((dir / "a.jpg").string(), m, ConeEncoding::U8), Error);
    WriteConeMap((dir / "a.exr").string(), m, ConeEncoding::Float);
    WriteConeMap((dir / "a.png").string(), m, ConeEncoding::U8);
    size_t n = 0;
    for (auto& e : std::filesystem::directory_iterator(dir)) {
        (void)e;
        ++n;
    }
    EXPECT_EQ(n, 2u);  // no temporaries left, nothing for the bad extension
    std::filesystem::remove_all(dir);
}

TEST(ConeMap, StoredMapIsTheFloatMapItselfOrItsQuantisation) {
    const ConeMap m = GenerateConeMap(MakeBuiltinMap("shapes", 16, 16), ConeKind::Quad);
    ConeMap scratch;
    const ConeMap& f = StoredConeMap(m, ConeEncoding::Float, scratch);
    EXPECT_EQ(&f, &m);  // no copy
    EXPECT_TRUE(scratch.values.empty());
    for (const ConeEncoding e :
         {ConeEncoding::U8, ConeEncoding::U8Sqrt, ConeEncoding::U16}) {
        const ConeMap& q = StoredConeMap(m, e, scratch);
        EXPECT_EQ(&q, &scratch);
        ASSERT_EQ(q.values.size(), m.values.size());
        size_t lowered = 0;
        for (size_t i = 0; i < m.values.size(); ++i) {
            // Each value is the decoding of its own code, never above the exact ratio.
            EXPECT_EQ(q.values[i], DecodeRatio(EncodeRatio(m.values[i], e), e));
            EXPECT_LE(q.values[i], m.values[i]);
            lowered += q.values[i] < m.values[i];
        }
        EXPECT_GT(lowered, 0u);  // quantisation took place
    }
}

TEST(ConeMap, WriterGivenTheStoredMapWritesTheSameFile) {
    using reliefsim::testing::Slurp;
    const auto dir = reliefsim::testing::Scratch("rs_cone_stored_");
    const ConeMap m = GenerateConeMap(MakeBuiltinMap("shapes", 16, 16), ConeKind::Acm8);
    for (const ConeEncoding e : {ConeEncoding::Float, ConeEncoding::U8}) {
        ConeMap scratch;
        const ConeMap& stored = StoredConeMap(m, e, scratch);
        WriteConeMap((dir / "a.exr").string(), m, e);
        WriteConeMap((dir / "b.exr").string(), m, e, nullptr, &stored);
        const std::string a = Slurp(dir / "a.exr");
        EXPECT_FALSE(a.empty());
        EXPECT_EQ(a, Slurp(dir / "b.exr")) << ToString(e);
    }
    // The u8 file holds the quantised ratios, not the float ones.
    WriteConeMap((dir / "f.exr").string(), m, ConeEncoding::Float);
    EXPECT_NE(Slurp(dir / "a.exr"), Slurp(dir / "f.exr"));
    std::filesystem::remove_all(dir);
}

TEST(ConeMap, ExternalGpuGemsMapLoadsAndChecksSize) {
#ifndef RS_SHARED_DATA
    GTEST_SKIP() << "RS_SHARED_DATA not defined";
#else
    const std::string path =
        std::string(RS_SHARED_DATA) + "/gpugems3-ch18/tile1_cone.tga";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent";
    const ConeMap ext = LoadExternalConeMap(path, ConeKind::Cone, 2, 256, 256);
    EXPECT_EQ(ext.width, 256);
    const ConeMapStats s = ComputeConeMapStats(ext);
    EXPECT_GT(s.meanRatio, 0.0);
    EXPECT_LE(s.maxRatio, 1.0);
    EXPECT_THROW(LoadExternalConeMap(path, ConeKind::Cone, 2, 128, 128), Error);
#endif
}

/// The conservative cone map that the GPU Gems 3 chapter's own preprocessor made for
/// tile1. ../shared/data/README.md describes it (zeros at depth 0, about 0.8x the exact
/// ratio) as read through a premultiplying loader; read as stored it is the exact map.
TEST(ConeMap, GpuGemsTile1ConeMapIsOurExactConeMap) {
    // GPU Gems 3's tile1_cone.tga (ratio in B, 8 bit, depth in A of tile1.tga) read with
    // its texel values as stored (no alpha premultiplication: texture/image_io.cpp) is
    // our exact conservative map in u8, code for code, on every texel.
#ifndef RS_SHARED_DATA
    GTEST_SKIP() << "RS_SHARED_DATA not defined";
#else
    const std::string dir = std::string(RS_SHARED_DATA) + "/gpugems3-ch18/";
    if (!std::filesystem::exists(dir + "tile1.tga") ||
        !std::filesystem::exists(dir + "tile1_cone.tga"))
        GTEST_SKIP() << dir << " absent";
    MapLoadOptions lo;
    lo.channel = Channel::A;
    lo.stores = Stores::Depth;  // A = depth, 0 = top
    const DepthField hf = LoadHeightMapFile(dir + "tile1.tga", lo);
    ASSERT_EQ(hf.width, 256);
    const ConeMap ours =
        QuantizeConeMap(GenerateConeMap(hf, ConeKind::Cone), ConeEncoding::U8);
    const ConeMap gg =
        LoadExternalConeMap(dir + "tile1_cone.tga", ConeKind::Cone, 2, 256, 256);
    int64_t equal = 0, n = 0;
    long maxDiff = 0;
    for (int j = 0; j < hf.height; ++j)
        for (int i = 0; i < hf.width; ++i) {
            const long o = std::lround(ours.At(i, j) * 255.0f);
            const long g = std::lround(gg.At(i, j) * 255.0f);
            ++n;
            equal += o == g;
            maxDiff = std::max(maxDiff, std::abs(o - g));
        }
    std::cout << "tile1_cone: " << equal << " of " << n
              << " texels equal to our exact u8 cone map, largest difference " << maxDiff
              << " codes\n";
    EXPECT_EQ(equal, n);
#endif
}

TEST(ConeMap, GpuGemsRelaxedMapsAreListingMaps) {
    // The chapter's relaxed maps, read as stored, against our Listing 18-2 maps (128
    // search steps): most texels within 2 codes of our ratio, and far more than of the
    // ratio times the texel's depth (what the same files look like when a reader
    // premultiplies B by the depth in A: an earlier reading of these maps).
#ifndef RS_SHARED_DATA
    GTEST_SKIP() << "RS_SHARED_DATA not defined";
#else
    const std::string dir = std::string(RS_SHARED_DATA) + "/gpugems3-ch18/";
    struct Case {
        const char* map;
        const char* cone;
        double within2;  ///< least share of texels within 2 codes of ours
    };
    for (const Case& c : {Case{"tile1", "tile1_relaxedcone", 0.72},
                          Case{"rockbump", "rockbump_relaxedcone", 0.50}}) {
        const std::string hpath = dir + c.map + ".tga", cpath = dir + c.cone + ".tga";
        if (!std::filesystem::exists(hpath) || !std::filesystem::exists(cpath))
            GTEST_SKIP() << dir << " absent";
        MapLoadOptions lo;
        lo.channel = Channel::A;
        lo.stores = Stores::Depth;
        const DepthField hf = LoadHeightMapFile(hpath, lo);
        const ConeMap ours = GenerateConeMap(hf, ConeKind::Relaxed);
        const ConeMap gg =
            LoadExternalConeMap(cpath, ConeKind::Relaxed, 2, hf.width, hf.height);
        int64_t n = 0, near2 = 0, scaledNear2 = 0;
        for (int j = 0; j < hf.height; ++j)
            for (int i = 0; i < hf.width; ++i) {
                const float r = std::min(ours.At(i, j), 1.0f), d = hf.At(i, j);
                const long g = std::lround(gg.At(i, j) * 255.0f);
                ++n;
                near2 += std::abs(g - std::lround(double(r) * 255.0)) <= 2;
                scaledNear2 +=
                    std::abs(g - std::lround(double(r) * double(d) * 255.0)) <= 2;
            }
        std::cout << c.cone << ": within 2 codes of our relaxed ratio "
                  << double(near2) / double(n) << " (of ratio * depth "
                  << double(scaledNear2) / double(n) << ")\n";
        EXPECT_GE(double(near2), c.within2 * double(n)) << c.cone;
        EXPECT_LT(scaledNear2 * 2, near2) << c.cone;
    }
#endif
}

}  // namespace
}  // namespace reliefsim
