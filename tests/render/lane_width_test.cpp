// The fragment driver at every lane width: identical frames, and the executed lane cost
// against an oracle built from the rasterizer's own triangle ids.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>

#include "raster/mesh.h"
#include "raster/rasterizer.h"
#include "raster/viewport_pieces.h"
#include "render/batch.h"
#include "render/frame.h"
#include "texture/procedural.h"

using namespace reliefsim;

namespace {

template <class T>
bool SameBytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() &&
           std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

void ExpectSameFrame(const RenderOutput& a, const RenderOutput& b,
                     const std::string& what) {
    const FrameRecord &x = a.record, &y = b.record;
    EXPECT_TRUE(SameBytes(x.hitU, y.hitU)) << what;
    EXPECT_TRUE(SameBytes(x.hitV, y.hitV)) << what;
    EXPECT_TRUE(SameBytes(x.hitDepth, y.hitDepth)) << what;
    EXPECT_TRUE(SameBytes(x.nCoarse, y.nCoarse)) << what;
    EXPECT_TRUE(SameBytes(x.nRefine, y.nRefine)) << what;
    EXPECT_TRUE(SameBytes(x.nFetches, y.nFetches)) << what;
    EXPECT_TRUE(SameBytes(x.nTexelReads, y.nTexelReads)) << what;
    EXPECT_TRUE(SameBytes(x.flags, y.flags)) << what;
    EXPECT_TRUE(SameBytes(a.color, b.color)) << what;
    EXPECT_EQ(x.nHelperFetches, y.nHelperFetches) << what;
    EXPECT_EQ(a.laneCost.group4x2, b.laneCost.group4x2) << what;
    EXPECT_EQ(a.laneCost.warp32, b.laneCost.warp32) << what;
}

// Sum over (bw x bh block, triangle) with a covered pixel of bw*bh x the largest fetch
// count among its covered pixels: what a SIMD group of those lanes executes.
// Which triangle of the scene's plane covers each pixel, straight from the rasterizer.
struct TriangleIds {
    static constexpr bool kReadsAttributes = false;
    int width;
    std::vector<int> id;
    void ShadeQuad(const QuadFragment& q, int) {
        for (int k = 0; k < 4; ++k)
            if ((q.coveredMask >> k) & 1u)
                id[size_t((q.pixel0.y + (k >> 1)) * width + q.pixel0.x + (k & 1))] =
                    int(q.triangle);
    }
};

uint64_t OracleCost(const FrameRecord& r, const std::vector<int>& tri, int bw, int bh) {
    std::map<std::pair<int, int>, uint32_t> worst;  // (block, triangle) -> trips
    for (int y = 0; y < r.height; ++y)
        for (int x = 0; x < r.width; ++x) {
            const size_t i = r.Index(x, y);
            if (!r.Covered(i)) continue;
            const int block = (y / bh) * ((r.width + bw - 1) / bw) + x / bw;
            uint32_t& m = worst[{block, tri[i]}];
            m = std::max(m, r.nFetches[i]);
        }
    uint64_t total = 0;
    for (const auto& [key, trips] : worst) total += uint64_t(trips) * uint64_t(bw * bh);
    return total;
}

}  // namespace

TEST(LaneWidth, EveryWidthRendersTheSameFrame) {
    const DepthField noise = MakeBuiltinMap("noise", 64, 64);
    const DepthField steps = MakeBuiltinMap("steps", 48, 48);  // not a power of two
    struct Variant {
        const DepthField* map;
        Filter filter;
        WrapMode wrap;
        std::vector<std::string> set;
    };
    const std::vector<Variant> variants = {
        {&noise, Filter::Bilinear, WrapMode::Repeat, {}},
        {&steps, Filter::Bilinear, WrapMode::Repeat, {"early_exit=0"}},
        {&steps, Filter::Bilinear, WrapMode::Clamp, {"budget=9"}},
        {&noise, Filter::Nearest, WrapMode::Repeat, {}},
        {&noise, Filter::Min4, WrapMode::Clamp, {}},
    };
    for (const KernelInfo* m : Methods()) {
        for (const Variant& v : variants) {
            // The hierarchical tracers refuse clamp (MaxMip.ClampWrapIsOneError).
            if (m->readsPyramid && v.wrap != WrapMode::Repeat) continue;
            RenderSettings s;
            s.method = std::string(m->name);
            s.set = v.set;
            s.width = 77;  // odd sizes: partial packs and quads half outside the image
            s.height = 53;
            s.viewAngle = 63.0f;
            s.azimuth = 20.0f;
            s.tiling = 2.0f;
            s.sampler.filter = v.filter;
            s.sampler.wrap = v.wrap;
            s.threads = 1;
            s.lanes = 1;
            const RenderOutput reference = Render(*v.map, s);
            for (const LaneWidthInfo& w : LaneWidths()) {
                if (!w.supported) continue;
                for (int threads : {1, 2}) {
                    s.lanes = w.width;
                    s.threads = threads;
                    ExpectSameFrame(reference, Render(*v.map, s),
                                    s.method + " lanes " + std::to_string(w.width) +
                                        " threads " + std::to_string(threads));
                }
            }
        }
    }
}

// The light-ray kernels (--shadow) run on the lanes of the view kernel's pack: every
// width and thread count gives the same light rays, visibility and shading.
TEST(LaneWidth, EveryWidthCastsTheSameShadows) {
    const DepthField shapes = MakeBuiltinMap("shapes", 64, 64);
    const std::pair<ShadowKind, const char*> cases[] = {
        {ShadowKind::Hard, "relief"}, {ShadowKind::Hard, "csm"},
        {ShadowKind::Hard, "pom"},    {ShadowKind::Soft, "relief"},
        {ShadowKind::Soft, "csm"},    {ShadowKind::Soft, "pom"},
        {ShadowKind::Cone, "cns"}};
    for (const auto& [kind, method] : cases) {
        {
            RenderSettings s;
            s.method = method;
            s.width = 77, s.height = 53;
            s.viewAngle = 50.0f;
            s.shadow = kind;
            s.shadowSteps = 11;
            s.threads = 1, s.lanes = 1;
            const RenderOutput reference = Render(shapes, s);
            ASSERT_EQ(reference.shadowFetches.size(), size_t(77 * 53));
            for (const LaneWidthInfo& w : LaneWidths()) {
                if (!w.supported) continue;
                for (int threads : {1, 2}) {
                    s.lanes = w.width, s.threads = threads;
                    const RenderOutput r = Render(shapes, s);
                    const std::string what = std::string(method) + " lanes " +
                                             std::to_string(w.width) + " threads " +
                                             std::to_string(threads);
                    ExpectSameFrame(reference, r, what);
                    EXPECT_EQ(r.shadowFetches, reference.shadowFetches) << what;
                    EXPECT_EQ(
                        0, std::memcmp(r.visibility.data(), reference.visibility.data(),
                                       r.visibility.size() * sizeof(float)))
                        << what;
                    EXPECT_EQ(0, std::memcmp(r.color.data(), reference.color.data(),
                                             r.color.size() * sizeof(float)))
                        << what;
                }
            }
        }
    }
}

TEST(LaneWidth, ExecutedLaneCostMatchesTheGroupOracle) {
    const DepthField field = MakeBuiltinMap("shapes", 128, 128);
    for (float angle : {0.0f, 40.0f, 70.0f}) {
        RenderSettings s;
        s.width = 150;
        s.height = 98;
        s.viewAngle = angle;
        s.azimuth = 33.0f;
        s.distance = 2.5f;  // the whole plane in view: no clipping, so its two triangles
                            // are the groups' triangles (the clipper's pieces would be)
        const RenderOutput out = Render(field, s);
        const Camera camera = SceneCamera(s);
        ASSERT_EQ(
            ClipMeshToViewport(MakePlane(s.tiling), camera.clipFromWorld).indices.size(),
            6u);
        TriangleIds ids{s.width, std::vector<int>(size_t(s.width * s.height), -1)};
        RasterizeFrame(MakePlane(s.tiling), camera, s.width, s.height, ids);
        const std::vector<int>& piece = ids.id;
        EXPECT_EQ(out.laneCost.quad, OracleCost(out.record, piece, 2, 2)) << angle;
        EXPECT_EQ(out.laneCost.group4x2, OracleCost(out.record, piece, 4, 2)) << angle;
        EXPECT_EQ(out.laneCost.warp32, OracleCost(out.record, piece, 8, 4)) << angle;
        EXPECT_EQ(out.laneCost.wave64, OracleCost(out.record, piece, 8, 8)) << angle;
        // Split by triangle, groups cost at least the block model of the summary.
        EXPECT_GE(out.laneCost.group4x2, out.summary.laneFetches4x2) << angle;
        EXPECT_GT(out.laneCost.quad, 0u);
    }
}

TEST(LaneWidth, UnknownOrUnsupportedWidthIsRefused) {
    EXPECT_THROW(PickLaneWidth(3), Error);
    for (const LaneWidthInfo& w : LaneWidths()) {
        if (!w.supported) {
            EXPECT_THROW(PickLaneWidth(w.width), Error);
        }
    }
    EXPECT_TRUE(PickLaneWidth(0).supported);
}

namespace {

// Coordinates that exercise every branch of the wrap: random over several tiles, texel
// centres and edges, exact 0 and 1, a hair below 0 (u - floor(u) rounds to 1), large.
std::vector<glm::vec2> SamplerProbes(int w, int h) {
    std::vector<glm::vec2> uv;
    uint32_t state = 12345u;
    auto next = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24);
    };
    for (int i = 0; i < 3000; ++i)
        uv.push_back({next() * 6.0f - 3.0f, next() * 6.0f - 3.0f});
    const float edges[] = {
        0.0f,           -0.0f,           1.0f,   -1e-10f,  1e-10f, 0.5f,
        0x1.fffffep-1f, -0x1.fffffep-1f, 17.25f, -1000.5f, 3e5f};
    for (float a : edges)
        for (float b : edges) uv.push_back({a, b});
    for (int i = 0; i <= w; ++i)
        for (float d : {0.0f, 0.5f, 1e-4f, -1e-4f})
            uv.push_back(
                {(float(i) + d) / float(w), (float(i % (h + 1)) + d) / float(h)});
    return uv;
}

}  // namespace

// The lane sampler (padded texels, every lane width) returns what the scalar counted
// sampler returns, bit for bit, with its texel counts, for every filter, wrap and
// arithmetic, on power-of-two and other sizes.
TEST(LaneSampler, EqualsScalarSamplerAtEveryWidth) {
    for (auto [w, h] : {std::pair{64, 64}, {37, 23}, {1, 1}, {2, 5}}) {
        const DepthField field = QuantizeToUnorm8(MakeBuiltinMap("noise", w, h));
        const std::vector<glm::vec2> probes = SamplerProbes(w, h);
        std::vector<float> u, v;
        for (glm::vec2 p : probes) u.push_back(p.x), v.push_back(p.y);
        const int n = int(u.size());
        for (Filter f : {Filter::Nearest, Filter::Bilinear, Filter::Min4})
            for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp})
                for (Precision prec :
                     {Precision::Float, Precision::Gpu8, Precision::Llvmpipe8}) {
                    const SamplerState st{f, wrap, prec};
                    std::vector<float> want(size_t(n), 0.0f);
                    std::vector<uint32_t> wantTexels(size_t(n), 0u);
                    for (int i = 0; i < n; ++i) {
                        FetchCounts c;
                        CountingSampler s(field, st, &c);
                        want[size_t(i)] = s.Sample({u[size_t(i)], v[size_t(i)]});
                        wantTexels[size_t(i)] = c.nTexelReads;
                    }
                    const Textures tex = BindTextures(field, st);
                    for (const LaneWidthInfo& lw : LaneWidths()) {
                        if (!lw.supported) continue;
                        std::vector<float> got(size_t(n), -1.0f);
                        std::vector<uint32_t> texels(size_t(n), 0u);
                        lw.sampleLanes(tex, u.data(), v.data(), n, got.data(),
                                       texels.data());
                        const std::string what =
                            std::to_string(w) + "x" + std::to_string(h) + " " +
                            std::string(ToString(f)) + " " + std::string(ToString(wrap)) +
                            " " + std::string(ToString(prec)) + " at " +
                            std::to_string(lw.width) + " lanes";
                        EXPECT_TRUE(SameBytes(got, want)) << what;
                        EXPECT_EQ(texels, wantTexels) << what;
                    }
                }
    }
}
