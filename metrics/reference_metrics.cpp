// Metrics against the exact reference (metrics/reference_metrics.h).
#include "metrics/reference_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace reliefsim {

ReferenceSummary SummarizeAgainstReference(const FrameRecord& r,
                                           const std::vector<float>& color,
                                           const ReferenceRecord& ref, int mapWidth,
                                           int mapHeight) {
    const size_t n = size_t(r.width) * size_t(r.height);
    RS_CHECK(ref.depth.size() == n && ref.u.size() == n && ref.v.size() == n &&
             ref.missed.size() == n && ref.rgb.size() == 3 * n && color.size() == 3 * n);
    ReferenceSummary s;
    uint64_t covered = 0;
    double sumSq = 0, sum = 0, sumUv = 0, sumColorSq = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!r.Covered(i)) continue;
        ++covered;
        const double e = double(r.hitDepth[i]) - double(ref.depth[i]);
        sum += e;
        sumSq += e * e;
        s.depthErrorMaxAbs = std::max(s.depthErrorMaxAbs, std::abs(e));
        const double uv =
            UvErrorTexels(double(r.hitU[i]) - double(ref.u[i]),
                          double(r.hitV[i]) - double(ref.v[i]), mapWidth, mapHeight);
        sumUv += uv;
        s.uvErrorTexelsMax = std::max(s.uvErrorTexelsMax, uv);
        s.missedGeometryPixels += ref.missed[i];
        s.pastFirstHitPixels += PastFirstHit(double(r.hitDepth[i]), double(ref.depth[i]));
        for (size_t c = 0; c < 3; ++c) {
            const double d = double(color[3 * i + c]) - double(ref.rgb[3 * i + c]);
            sumColorSq += d * d;
        }
    }
    if (covered == 0) return s;
    const double k = double(covered);
    s.mseExactDepth = sumSq / k;
    s.depthErrorMean = sum / k;
    s.uvErrorTexelsMean = sumUv / k;
    s.pastFirstHitShare = double(s.pastFirstHitPixels) / k;
    const double mseColor = sumColorSq / (3 * k);
    s.psnrColor = mseColor > 0 ? 10.0 * std::log10(1.0 / mseColor)
                               : std::numeric_limits<double>::infinity();
    return s;
}

}  // namespace reliefsim
