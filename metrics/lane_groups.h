// Divergence per lane group as images: for each pixel, the cost and the lane utilisation
// of its group (docs/exact.md "Lane groups").
#pragma once

#include <cstdint>
#include <vector>

#include "core/record.h"

namespace reliefsim {

/// Per pixel (row-major; 0 where not covered): the trips its (group, triangle) runs
/// (the largest trip count of the group's covered pixels of that triangle, a trip being
/// one fetch), and the group's lane utilisation (the trips its covered lanes need over
/// the lanes x trips it runs). totalCost sums lanes x trips over the (group, triangle)
/// pairs: the executed lane cost of the frame (metrics.json lane_cost_*).
struct LaneGroupMap {
    std::vector<float> trips, utilisation;
    uint64_t totalCost = 0;
};

/// Groups of groupWidth x groupHeight pixels aligned to the image (8x4: the 32-lane
/// warp), split by `piece` (the rasterizer's piece of each pixel, PiecePerPixel). Throws
/// Error for a bad group size or a triangle map of the wrong size.
LaneGroupMap LaneGroups(const FrameRecord& record, const std::vector<int32_t>& piece,
                        int groupWidth, int groupHeight);

}  // namespace reliefsim
