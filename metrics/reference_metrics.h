// Metrics against the exact reference (metrics/exact.h, docs/exact.md "Metrics"): per
// pixel and as frame summaries, over covered pixels, reduced serially in pixel order.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/record.h"

namespace reliefsim {

/// The exact reference of a frame, per pixel (row-major, as FrameRecord; zero where the
/// pixel is not covered): its hit, its shading, and whether the kernel's hit lies beyond
/// a structure the ray met first (MissedGeometry).
struct ReferenceRecord {
    std::vector<float> u, v, depth;
    std::vector<float> rgb;       ///< 3 per pixel: the kernels' shading of the exact hit
    std::vector<uint8_t> missed;  ///< 1: missed geometry at this pixel
    double seconds = 0.0;         ///< wall time of the reference pass (timing only)
};

/// A pixel's missed geometry: the kernel's hit depth tHit lies beyond the exact first hit
/// tRef by more than `coarseStep` (one coarse step's depth: the ordinary overshoot of a
/// stepping search stays within it) and the ray left the relief somewhere between the two
/// (`leftBetween`: ExactSurface::LeavesBetween), so tHit is behind a skipped structure,
/// not inside the one the ray met first.
inline bool MissedGeometry(double tHit, double tRef, double coarseStep,
                           bool leftBetween) {
    return tHit - tRef > coarseStep && leftBetween;
}

/// How far (in depth) a returned point may lie beyond the exact first hit and still count
/// as not past it: a few float roundings of t in [0, 1] (the reference is stored as
/// float).
inline constexpr double kPastFirstHitTolerance = 1.0 / (1 << 20);

/// Whether the kernel's returned depth tHit lies past the exact first hit tRef: the ray
/// point it answers is beyond where the ray first met the surface (inside it, or behind a
/// structure). A conservative search stops before the hit and never counts.
inline bool PastFirstHit(double tHit, double tRef) {
    return tHit - tRef > kPastFirstHitTolerance;
}

/// The distance between the kernel's hit uv and the reference's, in texels of a
/// mapWidth x mapHeight map (both unwrapped along the same ray).
inline double UvErrorTexels(double du, double dv, int mapWidth, int mapHeight) {
    const double x = du * mapWidth, y = dv * mapHeight;
    return std::sqrt(x * x + y * y);
}

struct ReferenceSummary {
    double mseExactDepth = 0.0;     ///< mean of (hit depth - reference depth)^2
    double depthErrorMean = 0.0;    ///< mean of hit depth - reference depth (signed)
    double depthErrorMaxAbs = 0.0;  ///< largest |hit depth - reference depth|
    double uvErrorTexelsMean = 0.0, uvErrorTexelsMax = 0.0;
    uint64_t missedGeometryPixels = 0;
    uint64_t pastFirstHitPixels = 0;  ///< covered pixels with PastFirstHit
    double pastFirstHitShare = 0.0;   ///< of the covered pixels
    /// 10 log10(1 / MSE) of the shaded colour (RGB in [0, 1]) against the reference's
    /// shading, over covered pixels' channels; infinite when the colours are equal.
    double psnrColor = 0.0;
};

/// Summarises `record` and its colour (3 floats per pixel) against `ref`, over the
/// record's covered pixels.
ReferenceSummary SummarizeAgainstReference(const FrameRecord& record,
                                           const std::vector<float>& color,
                                           const ReferenceRecord& ref, int mapWidth,
                                           int mapHeight);

}  // namespace reliefsim
