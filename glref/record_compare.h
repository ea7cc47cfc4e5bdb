// Bit-level comparison of two per-pixel records (the C++ frame loop vs the GL twin) and the
// check of the llvmpipe lane-cost model against the lanes measured inside the shader.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

#include <glm/mat4x4.hpp>

#include "core/record.h"
#include "glref/gl_reference.h"
#include "raster/camera.h"
#include "raster/mesh.h"

namespace reliefsim {

/// Agreement of one field over the pixels covered in both records.
struct FieldAgreement {
    uint64_t identical = 0;  ///< pixels whose values are bit-identical
    double fraction = 1.0;   ///< identical / compared pixels (1 when none are compared)
    uint64_t maxDiff = 0;    ///< floats: max distance in ulps; counts: max absolute difference
};

struct RecordComparison {
    uint64_t pixels = 0;   ///< pixels covered in both records (the compared set)
    uint64_t cpuOnly = 0;  ///< covered only by the C++ frame loop
    uint64_t glOnly = 0;   ///< covered only by llvmpipe
    uint64_t flagsDiffer = 0;  ///< compared pixels whose hit / budget flags differ
    FieldAgreement hitUv;      ///< hit u and hit v (ulps: the larger of the two)
    FieldAgreement hitDepth;
    FieldAgreement iterations;  ///< coarse and refine iterations (diff: of their sum)
    FieldAgreement fetches;
    std::vector<glm::ivec2> firstDiffs;  ///< the first differing pixels in row order
    /// Per pixel (row 0 at the top): number of differing fields (0..4) where both cover it,
    /// 5 where only one covers it; mask = covered by either.
    std::vector<float> diffMap;
    std::vector<uint8_t> mask;

    bool AllIdentical() const {
        return cpuOnly == 0 && glOnly == 0 && flagsDiffer == 0 && hitUv.identical == pixels &&
               hitDepth.identical == pixels && iterations.identical == pixels &&
               fetches.identical == pixels;
    }
};

/// Distance in units in the last place between two finite floats (0 when bit-identical;
/// +0 and -0 are 1 apart, so only identical bits count as equal).
uint64_t UlpDistance(float a, float b);

/// Compares the records field by field; lists up to maxListed differing pixels.
RecordComparison CompareRecords(const FrameRecord& cpu, const FrameRecord& gl,
                                int maxListed = 10);

/// The mesh clipped in world space to the camera's side planes, each pulled in by 2^-12 of w
/// (far less than half a pixel), and fan-triangulated from each polygon's first vertex.
/// llvmpipe's draw module clips triangles that leave the viewport and rasterizes the pieces
/// separately, so a 4x2 block on a piece boundary runs once per piece. The lane-cost run
/// draws this pre-clipped mesh, so the pieces are explicit and identical in both paths: GL
/// never clips again, and gl_PrimitiveID and the C++ triangle index name the same piece.
/// (The record comparison draws the unclipped mesh: the new vertices can move a clipped edge
/// by up to 1/256 pixel and flip the coverage of a pixel centre lying that close to it.)
/// Only positions are kept.
Mesh ClipMeshToViewport(const Mesh& mesh, const glm::mat4& clipFromWorld);

/// gl_PrimitiveID of each covered pixel as the C++ rasterizer assigns it (triangle index),
/// -1 where no triangle covers it.
std::vector<int16_t> TrianglePerPixel(const Mesh& mesh, const Camera& camera, int width,
                                      int height);

/// The lane-cost model against the measurement.
struct LaneCostCheck {
    uint32_t lanesPerGroup = 8;   ///< 4x2 lanes
    uint64_t modelGroups = 0;     ///< (4x2 block, triangle) pairs with a covered pixel
    uint64_t measuredGroups = 0;  ///< group runs counted by the shader
    uint64_t modelLaneFetches = 0;     ///< 8 x sum over groups of max fetches (C++ record)
    uint64_t measuredLaneFetches = 0;  ///< 8 x sum of executed trips (1 fetch per trip)
    uint64_t summaryLaneFetches = 0;   ///< metrics/summary.h laneFetches4x2 (blocks not
                                       ///< split by triangle)
    uint64_t groupsMismatched = 0;     ///< groups whose measured trips != model trips
    /// The first mismatched groups: block (x, y) in 4x2 units, triangle, model and measured
    /// trips.
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

/// Model from C++ data: the fetches of each pixel (row 0 at the top) and the C++ triangle
/// (piece) covering it (-1: none); the measurement from the GL frame. Requires
/// lanes.available.
LaneCostCheck CheckLaneCost(const std::vector<uint32_t>& fetches,
                            const std::vector<int16_t>& cpuTriangle, int width, int height,
                            const LaneMeasurement& lanes, uint64_t summaryLaneFetches);

}  // namespace reliefsim
