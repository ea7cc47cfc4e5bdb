// Bit-level comparison of two per-pixel records (the C++ frame loop vs the GL twin) and
// the check of the llvmpipe lane-cost model (4x2 lane groups per triangle) against
// measured trips.
#pragma once

#include <cstdint>
#include <glm/vec2.hpp>
#include <vector>

#include "core/record.h"

namespace reliefsim {

/// Agreement of one field over the pixels covered in both records.
struct FieldAgreement {
    uint64_t identical = 0;  ///< pixels whose values are bit-identical
    double fraction = 1.0;   ///< identical / compared pixels (1 when none are compared)
    uint64_t maxDiff =
        0;  ///< floats: max distance in ulps; counts: max absolute difference
};

struct RecordComparison {
    uint64_t pixels = 0;       ///< pixels covered in both records (the compared set)
    uint64_t cpuOnly = 0;      ///< covered only by the C++ frame loop
    uint64_t glOnly = 0;       ///< covered only by llvmpipe
    uint64_t flagsDiffer = 0;  ///< compared pixels whose hit / budget flags differ
    FieldAgreement hitUv;      ///< hit u and hit v (ulps: the larger of the two)
    FieldAgreement hitDepth;
    FieldAgreement iterations;  ///< coarse and refine iterations (diff: of their sum)
    FieldAgreement fetches;
    std::vector<glm::ivec2> firstDiffs;  ///< the first differing pixels in row order
    /// Per pixel (row 0 at the top): number of differing fields (0..4) where both cover
    /// it, 5 where only one covers it; mask = covered by either.
    std::vector<float> diffMap;
    std::vector<uint8_t> mask;

    bool AllIdentical() const {
        return cpuOnly == 0 && glOnly == 0 && flagsDiffer == 0 &&
               hitUv.identical == pixels && hitDepth.identical == pixels &&
               iterations.identical == pixels && fetches.identical == pixels;
    }
};

/// Distance in units in the last place between two finite floats (0 when bit-identical;
/// +0 and -0 are 1 apart, so only identical bits count as equal).
uint64_t UlpDistance(float a, float b);

/// Compares the records field by field; lists up to maxListed differing pixels.
RecordComparison CompareRecords(const FrameRecord& cpu, const FrameRecord& gl,
                                int maxListed = 10);

/// Loop trips measured per 4x2 lane group (in glcompare: by the GL twin's in-shader
/// counters, glref/gl_reference.h LaneMeasurement), as plain data.
struct LaneTrips {
    int blocksX = 0, blocksY = 0;  ///< 4x2 blocks across and down the image
    int nTriangles = 0;            ///< triangles (pieces) of the drawn mesh
    /// trips per (block, triangle): index ((by * blocksX) + bx) * nTriangles + triangle,
    /// with block (bx, by) = pixels [4bx, 4bx+4) x rows [2by, 2by+2) (row 0 at the top).
    std::vector<uint32_t> groupTrips;
    uint64_t groupRuns = 0;  ///< group runs counted (per triangle, per block)
};

/// The lane-cost model against the measurement.
struct LaneCostCheck {
    uint32_t lanesPerGroup = 8;     ///< 4x2 lanes
    uint64_t modelGroups = 0;       ///< (4x2 block, triangle) pairs with a covered pixel
    uint64_t measuredGroups = 0;    ///< group runs counted by the shader
    uint64_t modelLaneFetches = 0;  ///< 8 x sum over groups of max fetches (C++ record)
    uint64_t measuredLaneFetches = 0;  ///< 8 x sum of executed trips (1 fetch per trip)
    uint64_t summaryLaneFetches = 0;   ///< metrics/summary.h laneFetches4x2 (blocks not
                                       ///< split by triangle)
    uint64_t groupsMismatched = 0;     ///< groups whose measured trips != model trips
    /// The first mismatched groups: block (x, y) in 4x2 units, triangle, model and
    /// measured trips.
    struct Mismatch {
        int blockX, blockY, triangle;
        uint32_t modelTrips, measuredTrips;
    };
    std::vector<Mismatch> firstMismatches;
    bool Equal() const {
        return groupsMismatched == 0 && modelGroups == measuredGroups &&
               modelLaneFetches == measuredLaneFetches;
    }
};

/// Model from C++ data: the fetches of each pixel (row 0 at the top, width x height) and
/// the triangle (piece) covering it (-1: none); the measurement: measured.groupTrips (its
/// size is blocksX * blocksY * nTriangles) and measured.groupRuns. A group's model trips
/// are the largest fetches of its covered pixels (one fetch per trip); lane fetches are 8
/// x trips, summed over groups. Throws Error when a pixel's group lies outside
/// measured.groupTrips.
LaneCostCheck CheckLaneCost(const std::vector<uint32_t>& fetches,
                            const std::vector<int16_t>& cpuTriangle, int width,
                            int height, const LaneTrips& measured,
                            uint64_t summaryLaneFetches);

}  // namespace reliefsim
