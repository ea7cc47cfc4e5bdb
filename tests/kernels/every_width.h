// The kernel tests' runner: a ray through the driver's single-lane reference and through
// every other lane width this CPU runs (as lane 0 of a pack), which must agree bit for
// bit (hit u, hit depth, fetches, refine iterations).
#pragma once

#include <gtest/gtest.h>

#include <bit>

#include "render/batch.h"

namespace reliefsim::test {

inline RayRun MarchEveryWidth(const BatchJob& job, const MarchInput& in) {
    const RayRun one = MarchRay(job, in);
    for (const LaneWidthInfo& w : LaneWidths()) {
        if (!w.supported) continue;
        const RayRun r = MarchRayAt(w, job, in);
        EXPECT_EQ(std::bit_cast<uint32_t>(r.result.uvHit.x),
                  std::bit_cast<uint32_t>(one.result.uvHit.x))
            << w.width;
        EXPECT_EQ(std::bit_cast<uint32_t>(r.result.depthHit),
                  std::bit_cast<uint32_t>(one.result.depthHit))
            << w.width;
        EXPECT_EQ(r.counts.nFetches, one.counts.nFetches) << w.width;
        EXPECT_EQ(r.result.nRefine, one.result.nRefine) << w.width;
    }
    return one;
}

}  // namespace reliefsim::test
