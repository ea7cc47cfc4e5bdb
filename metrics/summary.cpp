// Frame summaries and the dissertation's error metric.
#include "metrics/summary.h"

#include <algorithm>
#include <cmath>

namespace reliefsim {

float PaperError(const FrameRecord& record, size_t i, const DepthField& field,
                 const SamplerState& state) {
    if (!record.Covered(i)) return 0.0f;
    Sampler<false> sampler(field, state);
    float d = sampler.Sample(glm::vec2(record.hitU[i], record.hitV[i]));
    return record.hitDepth[i] - d;
}

namespace {
uint64_t BlockCost(const FrameRecord& r, int bw, int bh) {
    uint64_t total = 0;
    for (int by = 0; by < r.height; by += bh)
        for (int bx = 0; bx < r.width; bx += bw) {
            uint32_t m = 0;
            bool any = false;
            for (int y = by; y < std::min(by + bh, r.height); ++y)
                for (int x = bx; x < std::min(bx + bw, r.width); ++x) {
                    size_t i = r.Index(x, y);
                    if (!r.Covered(i)) continue;
                    any = true;
                    m = std::max(m, r.nFetches[i]);
                }
            if (any) total += uint64_t(m) * uint64_t(bw * bh);
        }
    return total;
}
}  // namespace

FrameSummary Summarize(const FrameRecord& r, const DepthField& field,
                       const SamplerState& state) {
    std::vector<float> errors(r.flags.size());
    for (size_t i = 0; i < errors.size(); ++i) errors[i] = PaperError(r, i, field, state);
    return Summarize(r, errors);
}

FrameSummary Summarize(const FrameRecord& r, const std::vector<float>& paperErrors) {
    FrameSummary s;
    uint64_t sumCoarse = 0, sumRefine = 0;
    for (size_t i = 0; i < r.flags.size(); ++i) {
        if (!r.Covered(i)) continue;
        ++s.coveredPixels;
        sumCoarse += r.nCoarse[i];
        sumRefine += r.nRefine[i];
        s.totalFetches += r.nFetches[i];
        s.totalTexelReads += r.nTexelReads[i];
        s.maxFetches = std::max(s.maxFetches, r.nFetches[i]);
        if (r.flags[i] & kFlagBudgetExhausted) ++s.budgetExhaustedPixels;
        if (r.flags[i] & kFlagNoHit) ++s.noHitPixels;
        double e = double(paperErrors[i]);
        s.sumSqPaper += e * e;
        s.maxAbsErrorPaper = std::max(s.maxAbsErrorPaper, std::fabs(e));
    }
    if (s.coveredPixels) {
        double n = double(s.coveredPixels);
        s.avgCoarse = double(sumCoarse) / n;
        s.avgRefine = double(sumRefine) / n;
        s.avgIterations = double(sumCoarse + sumRefine) / n;
        s.avgFetches = double(s.totalFetches) / n;
        s.msePaper = s.sumSqPaper / n;
    }
    s.laneFetches4x2 = BlockCost(r, 4, 2);
    s.laneFetches8x4 = BlockCost(r, 8, 4);
    return s;
}

}  // namespace reliefsim
