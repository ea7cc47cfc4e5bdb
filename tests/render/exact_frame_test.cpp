// `render --method exact`: the exact reference as the frame's fragment stage
// (render/exact_batch.h), against its own definition and against a converged kernel.
#include <gtest/gtest.h>

#include <cmath>

#include "metrics/exact.h"
#include "metrics/lane_groups.h"
#include "raster/viewport_pieces.h"
#include "render/frame.h"
#include "render/trace.h"
#include "texture/procedural.h"

using namespace reliefsim;

namespace {

RenderSettings Settings(const char* method) {
    RenderSettings s;
    s.method = method;
    s.width = 96;
    s.height = 64;
    s.viewAngle = 60.0f;
    s.threads = 1;
    return s;
}

/// Depth 1 with a one-texel ridge of depth 0 across it (texel column 32 of 64).
DepthField Ridge() {
    DepthField ridge;
    ridge.width = ridge.height = 64;
    ridge.name = "ridge";
    ridge.depth.assign(64 * 64, 1.0f);
    for (int j = 0; j < 64; ++j) ridge.depth[size_t(j) * 64 + 32] = 0.0f;
    return ridge;
}

}  // namespace

// Each covered pixel holds ExactSurface::FirstHit of its ray, rounded to float, and the
// depth the sampler returns at that uv equals the ray depth there (the paper's MSE is
// float rounding only).
TEST(ExactFrame, RecordHoldsTheFirstHitOfEachPixelsRay) {
    const DepthField field = MakeBuiltinMap("builtin:shapes:64");
    for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Clamp}) {
        RenderSettings s = Settings("exact");
        s.sampler.wrap = wrap;
        s.tiling = 2.0f;
        const RenderOutput out = Render(field, s);
        const ExactSurface surface(field, wrap);
        const ViewUniforms view = MakeViewUniforms(s);
        int covered = 0;
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const size_t i = out.record.Index(x, y);
                if (!out.record.Covered(i)) continue;
                ++covered;
                const MarchInput in = PixelToRay(view, x, y);
                const ExactHit hit =
                    surface.FirstHit(in.uvEntry.x, in.uvEntry.y, in.dirUv.x, in.dirUv.y);
                ASSERT_EQ(out.record.hitDepth[i], float(hit.t)) << x << "," << y;
                ASSERT_EQ(out.record.hitU[i], float(hit.u));
                ASSERT_EQ(out.record.hitV[i], float(hit.v));
                ASSERT_EQ(out.record.nFetches[i], 0u);
            }
        EXPECT_GT(covered, s.width * s.height / 2);
        EXPECT_LT(out.summary.msePaper, 1e-10);
    }
}

TEST(ExactFrame, SameOutputsForEveryThreadCountAndLaneWidth) {
    const DepthField field = MakeBuiltinMap("builtin:noise:64");
    RenderSettings s = Settings("exact");
    const RenderOutput a = Render(field, s);
    s.threads = 2;
    s.lanes = 4;
    const RenderOutput b = Render(field, s);
    EXPECT_EQ(a.record.hitDepth, b.record.hitDepth);
    EXPECT_EQ(a.record.nCoarse, b.record.nCoarse);
    EXPECT_EQ(a.color, b.color);
}

// A kernel given many steps converges on the exact hit where it does not skip geometry:
// relief mapping with 512 linear and 16 binary steps on the smooth bumps is within 2e-3
// of the exact depth on 99% of the pixels, and never before it by more than its float
// arithmetic (the sampler's float weights and uv; measured 1.1e-6 at worst).
TEST(ExactFrame, ConvergedReliefMappingAgreesWithTheReference) {
    const DepthField field = MakeBuiltinMap("builtin:bumps:64");
    const RenderOutput exact = Render(field, Settings("exact"));
    RenderSettings s = Settings("relief");
    s.set = {"linear_steps=512", "refine_steps=16"};
    const RenderOutput relief = Render(field, s);
    int covered = 0, close = 0;
    for (size_t i = 0; i < exact.record.hitDepth.size(); ++i) {
        if (!exact.record.Covered(i)) continue;
        ++covered;
        const double d =
            double(relief.record.hitDepth[i]) - double(exact.record.hitDepth[i]);
        if (std::abs(d) <= 2e-3) ++close;
        EXPECT_GT(d, -1e-5);
    }
    EXPECT_GE(close, covered * 99 / 100);
}

TEST(ExactFrame, TraceEqualsTheFrameRecord) {
    const DepthField field = MakeBuiltinMap("builtin:steps:64");
    const RenderSettings s = Settings("exact");
    const RenderOutput out = Render(field, s);
    for (auto [x, y] : {std::pair{48, 32}, std::pair{10, 50}, std::pair{90, 5}}) {
        const PixelTrace t = TracePixel(field, s, x, y);
        const size_t i = out.record.Index(x, y);
        if (!out.record.Covered(i)) continue;
        EXPECT_TRUE(t.exact);
        EXPECT_TRUE(t.fetches.empty());
        EXPECT_EQ(t.result.depthHit, out.record.hitDepth[i]);
        EXPECT_EQ(t.result.nCoarse, out.record.nCoarse[i]);
    }
}

// The reference pass of a kernel's frame holds the exact frame's hits and colours.
TEST(ReferencePass, EqualsTheExactFrame) {
    const DepthField field = MakeBuiltinMap("builtin:shapes:64");
    const RenderOutput exact = Render(field, Settings("exact"));
    RenderSettings s = Settings("relief");
    s.threads = 2;
    const RenderOutput relief = Render(field, s);
    ASSERT_TRUE(relief.hasReference);
    for (size_t i = 0; i < exact.record.hitDepth.size(); ++i) {
        if (!exact.record.Covered(i)) continue;
        ASSERT_EQ(relief.reference.depth[i], exact.record.hitDepth[i]) << i;
        ASSERT_EQ(relief.reference.u[i], exact.record.hitU[i]);
        for (size_t c = 0; c < 3; ++c)
            ASSERT_EQ(relief.reference.rgb[3 * i + c], exact.color[3 * i + c]);
    }
    EXPECT_EQ(exact.referenceSummary.missedGeometryPixels, 0u);
    EXPECT_EQ(exact.referenceSummary.pastFirstHitPixels, 0u);
    EXPECT_EQ(exact.referenceSummary.mseExactDepth, 0.0);
}

// A one-texel ridge (depth 0) across a floor at depth 1: 4 linear steps jump over it
// for many rays (missed geometry), 1024 steps cannot (a step moves 0.01 texel and the
// ridge's base is 2 texels wide), and on a flat field the overshoot of 2 steps is never
// missed geometry.
TEST(ReferencePass, MissedGeometryOnARidge) {
    const DepthField ridge = Ridge();
    RenderSettings s = Settings("linear");
    s.azimuth = 90.0f;  // rays cross the ridge
    s.set = {"linear_steps=4"};
    const RenderOutput coarse = Render(ridge, s);
    EXPECT_GT(coarse.referenceSummary.missedGeometryPixels, 20u);
    s.set = {"linear_steps=1024"};
    EXPECT_EQ(Render(ridge, s).referenceSummary.missedGeometryPixels, 0u);
    DepthField flat = ridge;
    flat.depth.assign(64 * 64, 0.4f);
    s.set = {"linear_steps=2"};
    const RenderOutput f = Render(flat, s);
    EXPECT_EQ(f.referenceSummary.missedGeometryPixels, 0u);
    EXPECT_GT(f.referenceSummary.depthErrorMean, 0.0);  // it overshoots by up to a step
    // Over the plane at 0.4 two linear steps answer t = 0.5 (past the hit at 0.4) on
    // every pixel; cone stepping only approaches the plane from above and never passes.
    EXPECT_EQ(f.referenceSummary.pastFirstHitShare, 1.0);
    RenderSettings c = Settings("csm");
    c.maps.useCache = false;
    c.maps.encoding = ConeEncoding::Float;
    const RenderOutput cone = Render(flat, c);
    EXPECT_EQ(cone.referenceSummary.pastFirstHitPixels, 0u);
    // It reaches the plane (the float map's unbounded cones step almost all the way at
    // once), from above.
    EXPECT_GT(cone.referenceSummary.depthErrorMean, -1e-4);
    EXPECT_LE(cone.referenceSummary.depthErrorMaxAbs, 1e-4);
}

// trace shows the pixel's errors against the reference as the frame's pass computed them.
TEST(ReferencePass, TraceShowsTheFramesReferenceErrors) {
    const DepthField ridge = Ridge();
    RenderSettings s = Settings("linear");
    s.azimuth = 90.0f;
    s.set = {"linear_steps=4"};
    const RenderOutput out = Render(ridge, s);
    int missed = 0, checked = 0;
    for (int y = 0; y < s.height; y += 3)
        for (int x = 0; x < s.width; x += 3) {
            const size_t i = out.record.Index(x, y);
            if (!out.record.Covered(i)) continue;
            const PixelTrace t = TracePixel(ridge, s, x, y);
            ++checked;
            missed += t.reference.missedGeometry;
            ASSERT_EQ(t.reference.missedGeometry, out.reference.missed[i] != 0)
                << x << "," << y;
            ASSERT_EQ(float(t.reference.t), out.reference.depth[i]);
            ASSERT_EQ(t.reference.depthError,
                      double(out.record.hitDepth[i]) - double(out.reference.depth[i]));
        }
    EXPECT_GT(checked, 300);
    EXPECT_GT(missed, 0);
    EXPECT_NE(TraceJson(TracePixel(ridge, s, 40, 30)).find("\"missed_geometry\""),
              std::string::npos);
}

// --camera ortho: pixel (x, y) of a W x H frame sees uv ((x + 0.5)/W, (y + 0.5)/H), every
// pixel is covered, and every ray moves -(X, Y)/Z * depth scale uv per unit depth.
TEST(OrthoCamera, PixelToRayIsTheClosedForm) {
    RenderSettings s = Settings("relief");
    s.camera = CameraKind::Ortho;
    s.viewDir = glm::vec3(0.5f, 0.3f, -0.8f);
    s.depthScale = 0.2f;
    const ViewUniforms view = MakeViewUniforms(s);
    for (auto [x, y] : {std::pair{0, 0}, std::pair{95, 63}, std::pair{17, 40}}) {
        const MarchInput in = PixelToRay(view, x, y);
        EXPECT_EQ(in.uvEntry.x, (float(x) + 0.5f) / 96.0f);
        EXPECT_EQ(in.uvEntry.y, (float(y) + 0.5f) / 64.0f);
        EXPECT_EQ(in.dirUv.x, -(0.5f / -0.8f) * 0.2f);
        EXPECT_EQ(in.dirUv.y, -(0.3f / -0.8f) * 0.2f);
    }
    const DepthField field = MakeBuiltinMap("builtin:bumps:64");
    const RenderOutput out = Render(field, s);
    EXPECT_EQ(out.summary.coveredPixels, 96u * 64u);
    // A flat field in the ortho view is hit at its depth, at uv entry + depth * dirUv.
    DepthField flat = field;
    flat.depth.assign(flat.depth.size(), 0.25f);
    s.method = "exact";
    const RenderOutput e = Render(flat, s);
    const size_t i = e.record.Index(10, 20);
    EXPECT_EQ(e.record.hitDepth[i], 0.25f);
    EXPECT_NEAR(e.record.hitU[i], 10.5 / 96 + 0.25 * 0.125, 1e-7);
}

TEST(OrthoCamera, RefusesBadDirectionsAndTiling) {
    RenderSettings s = Settings("relief");
    s.camera = CameraKind::Ortho;
    s.viewDir = glm::vec3(0.0f, 0.0f, 1.0f);
    EXPECT_THROW(ValidateSettings(s), Error);
    s.viewDir = glm::vec3(1.0f, 0.0f, 0.0f);
    EXPECT_THROW(ValidateSettings(s), Error);
    s.viewDir = glm::vec3(0.0f, 0.0f, -1.0f);
    s.tiling = 2.0f;
    EXPECT_THROW(ValidateSettings(s), Error);
    s.tiling = 1.0f;
    EXPECT_NO_THROW(ValidateSettings(s));
}

// The warp images' groups are the executed ones: their cost sums to lane_cost_warp32.
TEST(LaneGroupMaps, TotalEqualsTheExecutedWarpCost) {
    for (const char* method : {"linear", "relief", "secant"})
        for (float angle : {0.0f, 45.0f, 80.0f}) {
            RenderSettings s = Settings(method);
            s.viewAngle = angle;
            s.azimuth = 20.0f;
            const RenderOutput out = Render(MakeBuiltinMap("builtin:noise:64"), s);
            const Camera camera = SceneCamera(s);
            const LaneGroupMap m = LaneGroups(
                out.record, PiecePerPixel(MakePlane(s.tiling), camera, s.width, s.height),
                8, 4);
            EXPECT_EQ(m.totalCost, out.laneCost.warp32) << method << " " << angle;
        }
}

// A setting is refused exactly when the render ignores it: changing its value changes
// the frame (colour, hits, visibility) unless RefuseIgnoredSettings refuses it and
// SettingRead says it is not read, for every camera and shadow kind.
TEST(IgnoredSettings, RefusedExactlyWhenTheFrameIgnoresThem) {
    const DepthField field = MakeBuiltinMap("builtin:bumps:32");
    const std::pair<const char*, void (*)(RenderSettings&)> changes[] = {
        {"view_angle", [](RenderSettings& s) { s.viewAngle = 40.0f; }},
        {"azimuth", [](RenderSettings& s) { s.azimuth = 35.0f; }},
        {"distance", [](RenderSettings& s) { s.distance = 2.5f; }},
        {"fov", [](RenderSettings& s) { s.fovY = 30.0f; }},
        {"view_dir", [](RenderSettings& s) { s.viewDir = glm::vec3(0.4f, 0.2f, -1.0f); }},
        {"shadow_steps", [](RenderSettings& s) { s.shadowSteps = 3; }},
        {"shadow_softening", [](RenderSettings& s) { s.shadowSoftening = 0.05f; }},
        {"shadow_penumbra", [](RenderSettings& s) { s.shadowPenumbra = 0.5f; }}};
    for (CameraKind camera : {CameraKind::Orbit, CameraKind::Ortho})
        for (ShadowKind shadow :
             {ShadowKind::None, ShadowKind::Hard, ShadowKind::Soft, ShadowKind::Cone}) {
            RenderSettings s = Settings(shadow == ShadowKind::Cone ? "cns" : "relief");
            s.width = 24;
            s.height = 16;
            s.reference = false;
            s.camera = camera;
            s.shadow = shadow;
            s.lightDir = glm::vec3(0.8f, 0.3f, 0.6f);
            const RenderOutput base = Render(field, s);
            for (const auto& [key, change] : changes) {
                SCOPED_TRACE(std::string(kCameraNames.Name(camera)) + " " +
                             std::string(kShadowNames.Name(shadow)) + " " + key);
                RenderSettings t = s;
                change(t);
                const RenderOutput o = Render(field, t);
                const bool ignored = o.color == base.color &&
                                     o.visibility == base.visibility &&
                                     o.record.hitDepth == base.record.hitDepth;
                bool refused = false;
                try {
                    RefuseIgnoredSettings(s,
                                          [key = std::string(key)](std::string_view k) {
                                              return k == key;
                                          });
                } catch (const Error& e) {
                    refused = true;
                    EXPECT_NE(std::string(e.what()).find(key), std::string::npos)
                        << e.what();
                }
                EXPECT_EQ(refused, ignored);
                EXPECT_EQ(SettingRead(s, key), !ignored);
            }
        }
}
