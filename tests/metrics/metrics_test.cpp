// Frame summaries: the paper's MSE, averages, lane-cost model.
#include <gtest/gtest.h>

#include "metrics/summary.h"

using namespace reliefsim;

namespace {
DepthField Constant(float d) {
    DepthField f;
    f.width = f.height = 4;
    f.depth.assign(16, d);
    f.name = "c";
    return f;
}
}  // namespace

TEST(Summary, PaperMseOverCoveredPixelsOnly) {
    DepthField f = Constant(0.5f);
    FrameRecord r;
    r.Resize(4, 2);
    // two covered pixels with errors +0.25 and -0.125, one uncovered with garbage
    r.flags[0] = kFlagCovered;
    r.hitDepth[0] = 0.75f;
    r.flags[5] = kFlagCovered | kFlagBudgetExhausted;
    r.hitDepth[5] = 0.375f;
    r.hitDepth[3] = 100.0f;
    r.nCoarse[0] = 3;
    r.nRefine[0] = 2;
    r.nCoarse[5] = 7;
    r.nFetches[0] = 5;
    r.nFetches[5] = 7;
    FrameSummary s = Summarize(r, f, {});
    EXPECT_EQ(s.coveredPixels, 2u);
    EXPECT_DOUBLE_EQ(s.msePaper, (0.25 * 0.25 + 0.125 * 0.125) / 2.0);
    EXPECT_DOUBLE_EQ(s.sumSqPaper, 0.25 * 0.25 + 0.125 * 0.125);
    EXPECT_DOUBLE_EQ(s.avgIterations, 6.0);
    EXPECT_DOUBLE_EQ(s.avgFetches, 6.0);
    EXPECT_EQ(s.maxFetches, 7u);
    EXPECT_EQ(s.totalFetches, 12u);
    EXPECT_EQ(s.budgetExhaustedPixels, 1u);
    // pixels 0 (x0,y0) and 5 (x1,y1) share one 4x2 block: 8 lanes x max 7
    EXPECT_EQ(s.laneFetches4x2, 56u);
    EXPECT_EQ(s.laneFetches8x4, 32u * 7u);
}

TEST(Summary, EmptyFrameIsAllZero) {
    FrameRecord r;
    r.Resize(3, 3);
    FrameSummary s = Summarize(r, Constant(0.1f), {});
    EXPECT_EQ(s.coveredPixels, 0u);
    EXPECT_EQ(s.msePaper, 0.0);
    EXPECT_EQ(s.laneFetches4x2, 0u);
}
