// Metrics against the exact reference, on hand-made records whose answers are known.
#include "metrics/reference_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "metrics/exact.h"
#include "metrics/lane_groups.h"

using namespace reliefsim;

namespace {

struct Frame {
    FrameRecord record;
    std::vector<float> color;
    ReferenceRecord ref;
};

Frame Blank(int w, int h) {
    Frame f;
    f.record.Resize(w, h);
    const size_t n = size_t(w) * size_t(h);
    f.color.assign(3 * n, 0.5f);
    f.ref.u.assign(n, 0.0f), f.ref.v.assign(n, 0.0f), f.ref.depth.assign(n, 0.0f);
    f.ref.rgb.assign(3 * n, 0.5f);
    f.ref.missed.assign(n, 0);
    return f;
}

}  // namespace

TEST(ReferenceMetrics, ErrorsOverCoveredPixelsOnly) {
    Frame f = Blank(2, 2);
    FrameRecord& r = f.record;
    // Pixel 0: 0.25 deeper, uv off by (3, 4) texels of a 16x8 map: 5 texels.
    r.flags[0] = kFlagCovered;
    r.hitDepth[0] = 0.75f, f.ref.depth[0] = 0.5f;
    r.hitU[0] = 3.0f / 16, r.hitV[0] = 4.0f / 8;
    // Pixel 1: 0.125 shallower, same uv, missed geometry, red off by 0.5.
    r.flags[1] = kFlagCovered;
    r.hitDepth[1] = 0.375f, f.ref.depth[1] = 0.5f;
    f.ref.missed[1] = 1;
    f.color[3] = 1.0f;
    // Pixel 2: not covered, garbage everywhere.
    r.hitDepth[2] = 100.0f, f.ref.missed[2] = 1, f.color[6] = 9.0f;
    const ReferenceSummary s = SummarizeAgainstReference(r, f.color, f.ref, 16, 8);
    EXPECT_DOUBLE_EQ(s.mseExactDepth, (0.25 * 0.25 + 0.125 * 0.125) / 2);
    EXPECT_DOUBLE_EQ(s.depthErrorMean, (0.25 - 0.125) / 2);
    EXPECT_DOUBLE_EQ(s.depthErrorMaxAbs, 0.25);
    EXPECT_DOUBLE_EQ(s.uvErrorTexelsMax, 5.0);
    EXPECT_DOUBLE_EQ(s.uvErrorTexelsMean, 2.5);
    EXPECT_EQ(s.missedGeometryPixels, 1u);
    // Pixel 0 answers a point past the first hit, pixel 1 one before it.
    EXPECT_EQ(s.pastFirstHitPixels, 1u);
    EXPECT_DOUBLE_EQ(s.pastFirstHitShare, 0.5);
    // One of six channels off by 0.5: MSE 0.25 / 6.
    EXPECT_NEAR(s.psnrColor, 10 * std::log10(6 / 0.25), 1e-12);
}

TEST(ReferenceMetrics, EqualColoursHaveInfinitePsnr) {
    Frame f = Blank(3, 1);
    f.record.flags[1] = kFlagCovered;
    EXPECT_TRUE(
        std::isinf(SummarizeAgainstReference(f.record, f.color, f.ref, 4, 4).psnrColor));
}

TEST(ReferenceMetrics, MissedGeometryNeedsBothConditions) {
    EXPECT_TRUE(MissedGeometry(0.6, 0.2, 1.0 / 32, true));
    EXPECT_FALSE(MissedGeometry(0.6, 0.2, 1.0 / 32, false));  // overshoot inside
    EXPECT_FALSE(MissedGeometry(0.22, 0.2, 1.0 / 32, true));  // within one step
}

// A thin pillar: depth 1 everywhere but texel column 8 at depth 0 (16 wide, clamp). A
// ray at v = 0.5 moving +u from u = 0.3 meets the pillar's bilinear flank, then leaves it
// on the far side and comes down to the floor: between the first hit and the floor it is
// outside the relief; between the first hit and a point just inside it is not.
TEST(ReferenceMetrics, LeavesBetweenSeesTheGapBehindAThinPillar) {
    DepthField f;
    f.width = 16, f.height = 4, f.name = "pillar";
    f.depth.assign(64, 1.0f);
    for (int j = 0; j < 4; ++j) f.depth[size_t(j) * 16 + 8] = 0.0f;
    const ExactSurface s(f, WrapMode::Clamp);
    const double u0 = 0.3, du = 0.6;
    const ExactHit hit = s.FirstHit(u0, 0.5, du, 0.0);
    ASSERT_LT(hit.t, 0.5);
    ASSERT_LT(hit.u, 8.5 / 16);  // on the near flank
    EXPECT_TRUE(s.LeavesBetween(u0, 0.5, du, 0.0, hit.t, 1.0, 1e-6));
    EXPECT_FALSE(s.LeavesBetween(u0, 0.5, du, 0.0, hit.t, hit.t + 1e-3, 1e-6));
    // On a flat field nothing is left once the ray is inside.
    DepthField flat = f;
    flat.depth.assign(64, 0.3f);
    const ExactSurface fs(flat, WrapMode::Repeat);
    EXPECT_FALSE(fs.LeavesBetween(0.1, 0.2, 2.0, -1.0, 0.3, 1.0, 1e-6));
    EXPECT_TRUE(fs.LeavesBetween(0.1, 0.2, 2.0, -1.0, 0.0, 0.3, 1e-6));
}

// One 8x4 warp split by two triangles, and a group with no trips.
TEST(LaneGroupMaps, CostAndUtilisationPerGroupAndTriangle) {
    FrameRecord r;
    r.Resize(16, 4);
    std::vector<int32_t> tri(64, -1);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            const size_t i = r.Index(x, y);
            r.flags[i] = kFlagCovered;
            tri[i] = x < 4 ? 0 : 1;
            r.nFetches[i] = x < 4 ? 10 : uint32_t(1 + x);  // triangle 1: 5..8
        }
    r.flags[r.Index(8, 0)] = kFlagCovered;  // the second warp: one lane, no trips
    tri[r.Index(8, 0)] = 1;
    const LaneGroupMap m = LaneGroups(r, tri, 8, 4);
    EXPECT_EQ(m.trips[r.Index(0, 0)], 10.0f);
    EXPECT_EQ(m.trips[r.Index(7, 3)], 8.0f);
    EXPECT_FLOAT_EQ(m.utilisation[r.Index(1, 2)], 16 * 10 / (32.0f * 10));
    EXPECT_FLOAT_EQ(m.utilisation[r.Index(5, 0)], 4 * (5 + 6 + 7 + 8) / (32.0f * 8));
    EXPECT_EQ(m.utilisation[r.Index(8, 0)], 0.0f);
    EXPECT_EQ(m.totalCost, 32u * 10 + 32u * 8);
    EXPECT_THROW(LaneGroups(r, std::vector<int32_t>(3), 8, 4), Error);
}

TEST(ReferenceMetrics, PastFirstHitAllowsOnlyRounding) {
    EXPECT_TRUE(PastFirstHit(0.5, 0.4));
    EXPECT_FALSE(PastFirstHit(0.4, 0.5));         // short of the hit
    EXPECT_FALSE(PastFirstHit(0.4 + 1e-7, 0.4));  // a float rounding of t
    EXPECT_TRUE(PastFirstHit(0.4 + 4 * kPastFirstHitTolerance, 0.4));
}
