// The render pipeline end to end: determinism, analytic scenes, outputs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "metrics/lane_groups.h"
#include "raster/viewport_pieces.h"
#include "render/outputs.h"
#include "render/trace.h"
#include "texture/procedural.h"

using namespace reliefsim;
namespace fs = std::filesystem;

namespace {

RenderSettings Small(const std::string& method) {
    RenderSettings s;
    s.method = method;
    s.width = 150;  // not a multiple of the tile or quad size
    s.height = 97;
    s.viewAngle = 55.0f;
    s.azimuth = 20.0f;
    return s;
}

nlohmann::json WithoutTiming(nlohmann::json j) {
    j.erase("timing");
    return j;
}

void ExpectSameRecord(const FrameRecord& a, const FrameRecord& b) {
    EXPECT_EQ(a.hitU, b.hitU);
    EXPECT_EQ(a.hitV, b.hitV);
    EXPECT_EQ(a.hitDepth, b.hitDepth);
    EXPECT_EQ(a.nCoarse, b.nCoarse);
    EXPECT_EQ(a.nRefine, b.nRefine);
    EXPECT_EQ(a.nFetches, b.nFetches);
    EXPECT_EQ(a.nTexelReads, b.nTexelReads);
    EXPECT_EQ(a.flags, b.flags);
    EXPECT_EQ(a.nHelperLanes, b.nHelperLanes);
    EXPECT_EQ(a.nHelperFetches, b.nHelperFetches);
}

}  // namespace

TEST(Render, IdenticalForOneAndTwoThreadsAndReruns) {
    DepthField f = MakeBuiltinMap("builtin:shapes:128");
    for (const char* method : {"linear", "relief", "secant", "interval", "pom"}) {
        RenderSettings s = Small(method);
        s.threads = 1;
        RenderOutput one = Render(f, s);
        s.threads = 2;
        RenderOutput two = Render(f, s);
        RenderOutput again = Render(f, s);
        ExpectSameRecord(one.record, two.record);
        ExpectSameRecord(two.record, again.record);
        EXPECT_EQ(one.color, two.color) << method;
        EXPECT_EQ(WithoutTiming(MetricsJson(one, s, f)),
                  WithoutTiming(MetricsJson(two, s, f)))
            << method;
        EXPECT_GT(one.summary.coveredPixels, 1000u);
    }
}

TEST(Render, FlatMapHitsItsDepthEverywhere) {
    DepthField f = MakeBuiltinMap("flat", 64, 64);
    RenderSettings s = Small("relief");
    s.set = {"linear_steps=8", "refine_steps=5"};
    RenderOutput out = Render(f, s);
    const FrameRecord& r = out.record;
    for (size_t i = 0; i < r.flags.size(); ++i) {
        if (!r.Covered(i)) continue;
        EXPECT_NEAR(r.hitDepth[i], 0.5f, (1.0f / 8.0f) / 64.0f + 1e-6f);
        EXPECT_EQ(r.nFetches[i], 5u + 5u);  // t = 0..4/8, then 5 binary steps
    }
    EXPECT_LT(out.summary.msePaper, 1e-5);
    EXPECT_EQ(out.summary.budgetExhaustedPixels, 0u);
}

TEST(Render, HelperLanesExecuteAndAreCountedSeparately) {
    DepthField f = MakeBuiltinMap("builtin:bumps:64");
    RenderOutput out = Render(f, Small("linear"));
    EXPECT_GT(out.record.nHelperLanes, 0u);
    EXPECT_GT(out.record.nHelperFetches, 0u);
    EXPECT_EQ(out.nQuads * 4, out.summary.coveredPixels + out.record.nHelperLanes);
}

TEST(Render, BudgetFlagsPixels) {
    DepthField f = MakeBuiltinMap("builtin:shapes:64");
    RenderSettings s = Small("relief");
    s.set = {"budget=4"};
    RenderOutput out = Render(f, s);
    EXPECT_GT(out.summary.budgetExhaustedPixels, 0u);
    EXPECT_LE(out.summary.maxFetches, 4u);
}

TEST(Render, WritesAllOutputsWithContractKeys) {
    fs::path dir = fs::path(::testing::TempDir()) / "rs_render_outputs";
    fs::remove_all(dir);
    DepthField f = MakeBuiltinMap("builtin:shapes:64");
    RenderSettings s = Small("relief");
    RenderOutput out = Render(f, s);
    WriteRenderOutputs(dir.string(), out, s, f);
    for (const char* name :
         {"color.png", "iterations.png", "fetches.png", "record.exr", "metrics.json"})
        EXPECT_TRUE(fs::exists(dir / name)) << name;
    std::ifstream in(dir / "metrics.json");
    nlohmann::json j;
    in >> j;
    for (const char* key :
         {"method", "params", "width", "height", "covered_pixels", "avg_iterations",
          "avg_fetches", "max_fetches", "total_fetches", "budget_exhausted_pixels",
          "mse_paper", "timing"})
        EXPECT_TRUE(j.contains(key)) << key;
    EXPECT_EQ(j["params"]["linear_steps"], 32);
    EXPECT_EQ(j["covered_pixels"], out.summary.coveredPixels);
    // no temporary (".NAME.rs-XXXXXX") left beside the outputs or their folder
    for (const fs::path& d : {dir, dir.parent_path()})
        for (const auto& e : fs::directory_iterator(d))
            EXPECT_EQ(e.path().filename().string().find(".rs-"), std::string::npos)
                << e.path();
}

TEST(Render, InvalidSettingsThrowBeforeRendering) {
    DepthField f = MakeBuiltinMap("builtin:flat:8");
    RenderSettings s = Small("relief");
    s.depthScale = 0.0f;
    EXPECT_THROW(Render(f, s), Error);
    s = Small("relief");
    s.viewAngle = 90.0f;
    EXPECT_THROW(Render(f, s), Error);
    s = Small("nope");
    EXPECT_THROW(Render(f, s), Error);
}

TEST(Trace, MatchesTheFrameRecordAtEveryProbedPixel) {
    DepthField f = MakeBuiltinMap("builtin:shapes:128");
    for (const char* method : {"relief", "secant", "interval"}) {
        RenderSettings s = Small(method);
        RenderOutput out = Render(f, s);
        const FrameRecord& r = out.record;
        int checked = 0;
        for (int y = 1; y < s.height; y += 13)
            for (int x = 2; x < s.width; x += 17) {
                size_t i = r.Index(x, y);
                if (!r.Covered(i)) continue;
                PixelTrace t = TracePixel(f, s, x, y);
                EXPECT_EQ(t.result.depthHit, r.hitDepth[i]);
                EXPECT_EQ(t.result.uvHit.x, r.hitU[i]);
                EXPECT_EQ(t.counts.nFetches, r.nFetches[i]);
                EXPECT_EQ(t.fetches.size(), size_t(r.nFetches[i]));
                ++checked;
            }
        EXPECT_GT(checked, 20);
    }
    EXPECT_THROW(TracePixel(f, Small("relief"), 150, 0), Error);
}

TEST(Render, OutputCreatesMissingParentsOnlyOnSuccess) {
    fs::path base = fs::path(::testing::TempDir()) / "rs_render_parents";
    fs::remove_all(base);
    fs::create_directories(base);
    DepthField f = MakeBuiltinMap("builtin:flat:8");
    RenderSettings s = Small("linear");
    s.width = s.height = 16;
    RenderOutput out = Render(f, s);
    WriteRenderOutputs((base / "a" / "b" / "c").string(), out, s, f);
    EXPECT_TRUE(fs::exists(base / "a" / "b" / "c" / "metrics.json"));
    // an ancestor that is a file: an error, and nothing created beside it
    std::ofstream(base / "file") << "x";
    EXPECT_THROW(WriteRenderOutputs((base / "file" / "d").string(), out, s, f), Error);
    int entries = 0;
    for (const auto& e : fs::directory_iterator(base)) {
        (void)e;
        ++entries;
    }
    EXPECT_EQ(entries, 2);  // "a" and "file"
}

TEST(Render, LambertShadingFollowsTheLight) {
    // A flat plane's normal is +z: the light along the normal gives the full albedo
    // (0.15 + 0.85 cos 0), one at 45 degrees 0.15 + 0.85 cos 45 of it, whatever the
    // azimuth; a light from below the horizon of the normal is refused.
    DepthField f;
    f.width = f.height = 16;
    f.depth.assign(256, 0.25f);
    f.name = "flat";
    RenderSettings s = Small("relief");
    s.reference = false;
    s.lightDir = {0.0f, 0.0f, 1.0f};
    const RenderOutput top = Render(f, s);
    s.lightDir = {1.0f, 0.0f, 1.0f};
    const RenderOutput slanted = Render(f, s);
    s.lightDir = {0.0f, -3.0f, 3.0f};
    const RenderOutput other = Render(f, s);
    size_t covered = 0;
    for (size_t i = 0; i < top.record.hitDepth.size(); ++i) {
        if (!top.record.Covered(i)) continue;
        ++covered;
        for (int c = 0; c < 3; ++c) {
            const float a = top.color[3 * i + size_t(c)];
            ASSERT_GT(a, 0.0f);
            EXPECT_NEAR(slanted.color[3 * i + size_t(c)] / a,
                        0.15 + 0.85 * std::sqrt(0.5), 1e-5);
            EXPECT_NEAR(other.color[3 * i + size_t(c)], slanted.color[3 * i + size_t(c)],
                        1e-6);
        }
    }
    EXPECT_GT(covered, 1000u);
    s.lightDir = {0.0f, 1.0f, 0.0f};
    EXPECT_THROW(ValidateSettings(s), Error);
}

// The heatmaps of `render --group-heatmaps` are the driver's executed lane cost: each
// group kind's totals equal metrics.json's lane_cost_*, and the groups nest (a 2x2 quad
// lies in its 4x2 group, which lies in its 8x4 warp, which lies in its 8x8 wave), so a
// pixel's trips can only grow from one to the next.
TEST(Render, GroupHeatmapsAreTheExecutedLaneCostAndNest) {
    DepthField f = MakeBuiltinMap("builtin:shapes:64");
    RenderSettings s = Small("csm");
    s.width = 72, s.height = 52;  // partial groups at the right and bottom
    const RenderOutput out = Render(f, s);
    const std::vector<int32_t> piece = PiecePerPixel(MakePlane(s.tiling), SceneCamera(s),
                                                     out.record.width, out.record.height);
    const LaneGroupMap quad = LaneGroups(out.record, piece, 2, 2);
    const LaneGroupMap g4x2 = LaneGroups(out.record, piece, 4, 2);
    const LaneGroupMap warp = LaneGroups(out.record, piece, 8, 4);
    const LaneGroupMap wave = LaneGroups(out.record, piece, 8, 8);
    EXPECT_EQ(quad.totalCost, out.laneCost.quad);
    EXPECT_EQ(g4x2.totalCost, out.laneCost.group4x2);
    EXPECT_EQ(warp.totalCost, out.laneCost.warp32);
    EXPECT_EQ(wave.totalCost, out.laneCost.wave64);
    ASSERT_EQ(std::size(kLaneGroupHeatmaps), 3u);
    EXPECT_EQ(kLaneGroupHeatmaps[1].width * kLaneGroupHeatmaps[1].height, 8);
    size_t covered = 0;
    for (size_t i = 0; i < quad.trips.size(); ++i) {
        if (!out.record.Covered(i)) continue;
        ++covered;
        EXPECT_GE(quad.trips[i], float(out.record.nFetches[i])) << i;
        EXPECT_GE(g4x2.trips[i], quad.trips[i]) << i;
        EXPECT_GE(warp.trips[i], g4x2.trips[i]) << i;
        EXPECT_GE(wave.trips[i], warp.trips[i]) << i;
    }
    EXPECT_GT(covered, 1000u);
}

// Shadows only darken: where the light is visible the colour is the unshadowed frame's,
// bit for bit; where it is blocked only the ambient term is left; the view ray's record
// is untouched, and its lane costs do not include the light rays.
TEST(Render, ShadowsDarkenOnlyWhereTheLightIsBlocked) {
    DepthField f = MakeBuiltinMap("builtin:shapes:64");
    RenderSettings s = Small("relief");
    s.width = 96, s.height = 80;
    const RenderOutput plain = Render(f, s);
    EXPECT_TRUE(plain.shadowFetches.empty());
    s.shadow = ShadowKind::Hard;
    const RenderOutput hard = Render(f, s);
    EXPECT_EQ(hard.record.nFetches, plain.record.nFetches);
    EXPECT_EQ(hard.laneCost.warp32, plain.laneCost.warp32);
    size_t blocked = 0, lit = 0;
    for (size_t i = 0; i < hard.visibility.size(); ++i) {
        if (!hard.record.Covered(i) || (hard.record.flags[i] & kFlagNoHit)) continue;
        for (size_t c = 0; c < 3; ++c) {
            if (hard.visibility[i] == 1.0f)
                EXPECT_EQ(hard.color[3 * i + c], plain.color[3 * i + c]) << i;
            else
                EXPECT_LE(hard.color[3 * i + c], plain.color[3 * i + c]) << i;
        }
        (hard.visibility[i] == 0.0f ? blocked : lit) += 1;
        EXPECT_GE(hard.shadowFetches[i], 1u);
        EXPECT_LE(hard.shadowFetches[i], uint32_t(s.shadowSteps));
    }
    EXPECT_GT(blocked, 100u);
    EXPECT_GT(lit, 1000u);
    // A light straight overhead casts no shadow on a height field.
    s.lightDir = {0.0f, 0.0f, 1.0f};
    const RenderOutput overhead = Render(f, s);
    for (size_t i = 0; i < overhead.visibility.size(); ++i) {
        if (overhead.record.Covered(i)) {
            EXPECT_EQ(overhead.visibility[i], 1.0f) << i;
        }
    }
}

TEST(Render, WithoutShadingTheRecordIsTheSame) {
    // frame_vs_llvmpipe renders the record only (llvmpipe's twin shades nothing).
    const DepthField f = MakeBuiltinMap("builtin:shapes:64");
    for (const char* method : {"relief", "csm"}) {
        RenderSettings s = Small(method);
        s.reference = false;
        const RenderOutput shaded = Render(f, s);
        s.shade = false;
        const RenderOutput plain = Render(f, s);
        ExpectSameRecord(shaded.record, plain.record);
        EXPECT_EQ(shaded.laneCost.warp32, plain.laneCost.warp32);
        EXPECT_EQ(shaded.color.size(), size_t(3 * s.width * s.height));
        EXPECT_TRUE(plain.color.empty());
        s.reference = true;  // its metrics compare shaded colours
        EXPECT_THROW(Render(f, s), Error);
    }
}

// A conservative cone march only approaches the surface, so after cone_steps most rays
// stop just above it (kFlagNoHit). That point is the kernel's answer, as the papers'
// shaders shade wherever the march stopped: it is shaded (not the magenta of a miss) and
// lit. The linear family's misses stay magenta.
TEST(Render, ConeKernelsShadeAndLightWhereTheyStop) {
    const DepthField f = MakeBuiltinMap("builtin:shapes:64");
    for (const char* method : {"csm", "acm4", "cns"}) {
        RenderSettings s = Small(method);
        s.width = 96, s.height = 80;
        s.shadow = ShadowKind::Hard;
        const RenderOutput out = Render(f, s);
        size_t stopped = 0;
        for (size_t i = 0; i < out.visibility.size(); ++i) {
            if (!out.record.Covered(i) || !(out.record.flags[i] & kFlagNoHit)) continue;
            ++stopped;
            // Albedos of an answer have green / red >= 0.80 / 0.93; the miss 0.1 / 0.9.
            EXPECT_GT(out.color[3 * i + 1], 0.5f * out.color[3 * i])
                << method << " " << i;
            EXPECT_GE(out.shadowFetches[i], 1u) << method << " " << i;
        }
        EXPECT_GT(stopped, 500u) << method;
    }
    // A linear search limited to fewer fetches than it needs has misses: magenta, unlit.
    RenderSettings s = Small("linear");
    s.width = 96, s.height = 80;
    s.shadow = ShadowKind::Hard;
    s.set = {"budget=3"};
    const RenderOutput out = Render(f, s);
    size_t misses = 0;
    for (size_t i = 0; i < out.visibility.size(); ++i) {
        if (!out.record.Covered(i) || !(out.record.flags[i] & kFlagNoHit)) continue;
        ++misses;
        EXPECT_LT(out.color[3 * i + 1], 0.2f * out.color[3 * i]) << i;
        EXPECT_EQ(out.shadowFetches[i], 0u) << i;
    }
    EXPECT_GT(misses, 500u);
}

TEST(Render, AmbientOcclusionScalesOnlyTheAmbientTerm) {
    // --ao cone: the record and lane costs are the kernel's; each hit's colour loses
    // 0.15 albedo (1 - ao), nothing where ao is 1; one light fetch per hit.
    const DepthField f = MakeBuiltinMap("builtin:shapes:64");
    for (const char* method : {"csm", "cns"}) {
        RenderSettings s = Small(method);
        s.width = 96, s.height = 80;
        const RenderOutput plain = Render(f, s);
        EXPECT_TRUE(plain.ambient.empty());
        s.ao = AoKind::Cone;
        const RenderOutput ao = Render(f, s);
        ExpectSameRecord(plain.record, ao.record);
        EXPECT_EQ(plain.laneCost.warp32, ao.laneCost.warp32);
        ASSERT_EQ(ao.ambient.size(), size_t(s.width * s.height));
        size_t darker = 0;
        for (size_t i = 0; i < ao.ambient.size(); ++i) {
            // (every covered pixel: a cone march answers where it stopped)
            if (!ao.record.Covered(i)) continue;
            EXPECT_GE(ao.ambient[i], 0.0f);
            EXPECT_LE(ao.ambient[i], 1.0f);
            EXPECT_EQ(ao.shadowFetches[i], 1u);
            EXPECT_EQ(ao.visibility[i], 1.0f);
            for (size_t c = 0; c < 3; ++c) {
                if (ao.ambient[i] == 1.0f)
                    EXPECT_EQ(ao.color[3 * i + c], plain.color[3 * i + c]) << i;
                else
                    EXPECT_LT(ao.color[3 * i + c], plain.color[3 * i + c]) << i;
            }
            darker += ao.ambient[i] < 1.0f;
        }
        EXPECT_GT(darker, 1000u) << method;
    }
    // Methods without csm's or cns's map are refused.
    RenderSettings s = Small("relief");
    s.ao = AoKind::Cone;
    EXPECT_THROW(Render(f, s), Error);
    s.method = "rcs";
    EXPECT_THROW(Render(f, s), Error);
}
