// Record comparison and the lane-cost check on constructed data (no EGL, no GL).
#include "metrics/record_compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/error.h"

namespace reliefsim {
namespace {

/// A 4x2 record with every pixel covered except (3, 1); values differ per pixel.
FrameRecord MakeRecord() {
    FrameRecord r;
    r.Resize(4, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            const size_t i = r.Index(x, y);
            if (x == 3 && y == 1) continue;
            r.flags[i] = kFlagCovered;
            r.hitU[i] = 0.1f * float(x + 1);
            r.hitV[i] = 0.2f * float(y + 1);
            r.hitDepth[i] = 0.05f * float(i + 1);
            r.nCoarse[i] = uint16_t(8 + i);
            r.nRefine[i] = uint16_t(i % 3);
            r.nFetches[i] = uint32_t(10 + i);
        }
    return r;
}

TEST(RecordCompare, UlpDistanceCountsRepresentableFloats) {
    EXPECT_EQ(UlpDistance(1.0f, 1.0f), 0u);
    EXPECT_EQ(UlpDistance(-2.5f, -2.5f), 0u);
    EXPECT_EQ(UlpDistance(0.0f, -0.0f), 1u);
    EXPECT_EQ(UlpDistance(-0.0f, 0.0f), 1u);
    EXPECT_EQ(UlpDistance(1.0f, std::nextafter(1.0f, 2.0f)), 1u);
    EXPECT_EQ(UlpDistance(std::nextafter(1.0f, 0.0f), 1.0f), 1u);
    EXPECT_EQ(UlpDistance(-1.0f, std::nextafter(-1.0f, -2.0f)), 1u);
    // Across zero: -denorm_min, -0, +0, +denorm_min are consecutive.
    const float tiny = std::nextafter(0.0f, 1.0f);
    EXPECT_EQ(UlpDistance(-tiny, tiny), 3u);
    EXPECT_EQ(UlpDistance(tiny, -tiny), 3u);
    EXPECT_EQ(UlpDistance(-tiny, 0.0f), 2u);
}

TEST(RecordCompare, IdenticalRecordsAreAllIdentical) {
    const FrameRecord a = MakeRecord();
    const RecordComparison c = CompareRecords(a, a);
    EXPECT_TRUE(c.AllIdentical());
    EXPECT_EQ(c.pixels, 7u);
    EXPECT_EQ(c.cpuOnly, 0u);
    EXPECT_EQ(c.glOnly, 0u);
    EXPECT_EQ(c.flagsDiffer, 0u);
    EXPECT_EQ(c.hitUv.identical, 7u);
    EXPECT_EQ(c.fetches.fraction, 1.0);
    EXPECT_TRUE(c.firstDiffs.empty());
    EXPECT_EQ(c.mask[a.Index(3, 1)], 0u);
    EXPECT_EQ(c.mask[a.Index(0, 0)], 1u);
}

TEST(RecordCompare, OneDifferingFieldIsCountedAndListed) {
    const FrameRecord a = MakeRecord();
    FrameRecord b = a;
    const size_t i = a.Index(2, 1);
    b.hitDepth[i] = std::nextafter(b.hitDepth[i], 2.0f);
    b.hitDepth[i] = std::nextafter(b.hitDepth[i], 2.0f);  // 2 ulps
    const RecordComparison c = CompareRecords(a, b);
    EXPECT_FALSE(c.AllIdentical());
    EXPECT_EQ(c.pixels, 7u);
    EXPECT_EQ(c.hitDepth.identical, 6u);
    EXPECT_EQ(c.hitDepth.maxDiff, 2u);
    EXPECT_DOUBLE_EQ(c.hitDepth.fraction, 6.0 / 7.0);
    EXPECT_EQ(c.hitUv.identical, 7u);
    EXPECT_EQ(c.iterations.identical, 7u);
    EXPECT_EQ(c.fetches.identical, 7u);
    ASSERT_EQ(c.firstDiffs.size(), 1u);
    EXPECT_EQ(c.firstDiffs[0], glm::ivec2(2, 1));
    EXPECT_EQ(c.diffMap[i], 1.0f);
    EXPECT_EQ(c.diffMap[a.Index(0, 0)], 0.0f);

    // Counts: the iteration diff is of the sum; fetches by absolute difference.
    FrameRecord d = a;
    d.nRefine[a.Index(1, 0)] += 3;
    d.nFetches[a.Index(1, 0)] -= 4;
    const RecordComparison e = CompareRecords(a, d);
    EXPECT_EQ(e.iterations.identical, 6u);
    EXPECT_EQ(e.iterations.maxDiff, 3u);
    EXPECT_EQ(e.fetches.maxDiff, 4u);
    EXPECT_EQ(e.diffMap[a.Index(1, 0)], 2.0f);
}

TEST(RecordCompare, CoverageDifferencesAreCpuOnlyOrGlOnly) {
    const FrameRecord cpu = MakeRecord();
    FrameRecord gl = cpu;
    gl.flags[cpu.Index(0, 0)] = 0;             // covered only by the C++ frame loop
    gl.flags[cpu.Index(3, 1)] = kFlagCovered;  // covered only by GL
    const RecordComparison c = CompareRecords(cpu, gl);
    EXPECT_FALSE(c.AllIdentical());
    EXPECT_EQ(c.cpuOnly, 1u);
    EXPECT_EQ(c.glOnly, 1u);
    EXPECT_EQ(c.pixels, 6u);  // compared: covered in both
    EXPECT_EQ(c.diffMap[cpu.Index(0, 0)], 5.0f);
    EXPECT_EQ(c.diffMap[cpu.Index(3, 1)], 5.0f);
    ASSERT_EQ(c.firstDiffs.size(), 2u);
    EXPECT_EQ(c.firstDiffs[0], glm::ivec2(0, 0));
    EXPECT_EQ(c.firstDiffs[1], glm::ivec2(3, 1));
}

TEST(RecordCompare, FlagDifferencesAreCounted) {
    const FrameRecord a = MakeRecord();
    FrameRecord b = a;
    b.flags[a.Index(1, 1)] |= kFlagNoHit;
    const RecordComparison c = CompareRecords(a, b);
    EXPECT_EQ(c.flagsDiffer, 1u);
    EXPECT_FALSE(c.AllIdentical());
}

TEST(RecordCompare, SizesDifferIsAnError) {
    const FrameRecord a = MakeRecord();
    FrameRecord b;
    b.Resize(4, 3);
    try {
        CompareRecords(a, b);
        ADD_FAILURE() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("4x2 vs 4x3"), std::string::npos)
            << e.what();
    }
}

// An 8x2 frame: two 4x2 blocks, two triangles. Block 0 is all triangle 0; block 1 has
// triangle 0 in columns 4-5 and triangle 1 in columns 6-7, with pixel (7, 1) uncovered
// (its large fetch count must not count).
struct LaneFrame {
    int width = 8, height = 2;
    std::vector<uint32_t> fetches = {3, 5, 2, 7, 1, 4, 6, 2,  //
                                     4, 1, 1, 2, 9, 3, 5, 99};
    std::vector<int16_t> triangle = {0, 0, 0, 0, 0, 0, 1, 1,  //
                                     0, 0, 0, 0, 0, 0, 1, -1};
    // Model trips per (block, triangle), index block * 2 + triangle:
    // (0, 0) = max(3,5,2,7,4,1,1,2) = 7; (0, 1) unused; (1, 0) = max(1,4,9,3) = 9;
    // (1, 1) = max(6,2,5) = 6.
    LaneTrips Measured() const {
        LaneTrips t;
        t.blocksX = 2;
        t.blocksY = 1;
        t.nTriangles = 2;
        t.groupTrips = {7, 0, 9, 6};
        t.groupRuns = 3;
        return t;
    }
};

TEST(LaneCost, ModelIsMaxPerBlockAndTriangle) {
    const LaneFrame f;
    const LaneCostCheck c =
        CheckLaneCost(f.fetches, f.triangle, f.width, f.height, f.Measured(), 123);
    EXPECT_TRUE(c.Equal());
    EXPECT_EQ(c.lanesPerGroup, 8u);
    EXPECT_EQ(c.modelGroups, 3u);
    EXPECT_EQ(c.measuredGroups, 3u);
    EXPECT_EQ(c.modelLaneFetches, 8u * (7u + 9u + 6u));
    EXPECT_EQ(c.measuredLaneFetches, 8u * (7u + 9u + 6u));
    EXPECT_EQ(c.summaryLaneFetches, 123u);
    EXPECT_EQ(c.groupsMismatched, 0u);
    EXPECT_TRUE(c.firstMismatches.empty());
}

TEST(LaneCost, MismatchedGroupIsCountedAndListed) {
    const LaneFrame f;
    LaneTrips measured = f.Measured();
    measured.groupTrips[3] = 8;  // block (1, 0), triangle 1: model 6
    const LaneCostCheck c =
        CheckLaneCost(f.fetches, f.triangle, f.width, f.height, measured, 0);
    EXPECT_FALSE(c.Equal());
    EXPECT_EQ(c.groupsMismatched, 1u);
    EXPECT_EQ(c.modelLaneFetches, 8u * 22u);
    EXPECT_EQ(c.measuredLaneFetches, 8u * 24u);
    ASSERT_EQ(c.firstMismatches.size(), 1u);
    const LaneCostCheck::Mismatch& m = c.firstMismatches[0];
    EXPECT_EQ(m.blockX, 1);
    EXPECT_EQ(m.blockY, 0);
    EXPECT_EQ(m.triangle, 1);
    EXPECT_EQ(m.modelTrips, 6u);
    EXPECT_EQ(m.measuredTrips, 8u);

    // A group run the model does not have (a block split once more) is a count mismatch.
    LaneTrips extraRun = f.Measured();
    extraRun.groupRuns = 4;
    const LaneCostCheck d =
        CheckLaneCost(f.fetches, f.triangle, f.width, f.height, extraRun, 0);
    EXPECT_EQ(d.groupsMismatched, 0u);
    EXPECT_FALSE(d.Equal());
}

TEST(LaneCost, GroupOutsideTheMeasurementIsAnError) {
    const LaneFrame f;
    LaneTrips small = f.Measured();
    small.groupTrips.resize(3);  // (block 1, triangle 1) is missing
    EXPECT_THROW(CheckLaneCost(f.fetches, f.triangle, f.width, f.height, small, 0),
                 Error);
    std::vector<uint32_t> shortFetches(4, 0);
    EXPECT_THROW(
        CheckLaneCost(shortFetches, f.triangle, f.width, f.height, f.Measured(), 0),
        Error);
}

}  // namespace
}  // namespace reliefsim
