// Step-by-step trace of one pixel's kernel.
#include "render/trace.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "metrics/exact.h"
#include "raster/rasterizer.h"
#include "render/batch.h"

namespace reliefsim {

PixelTrace TracePixel(const DepthField& field, const RenderSettings& s, int x, int y) {
    ValidateSettings(s);
    if (x < 0 || y < 0 || x >= s.width || y >= s.height)
        throw Error("pixel " + std::to_string(x) + "," + std::to_string(y) +
                    ": outside the " + std::to_string(s.width) + "x" +
                    std::to_string(s.height) + " image");
    PixelTrace trace;
    trace.x = x;
    trace.y = y;
    trace.input = PixelToRay(MakeViewUniforms(s), x, y);
    if (s.method == kExactMethod) {
        const ExactSurface surface(field, s.sampler.wrap);
        detail::DenormalsAreZeroScope gpuFloatMode;  // as in the frame loop's tiles
        const MarchInput& in = trace.input;
        const ExactHit hit =
            surface.FirstHit(in.uvEntry.x, in.uvEntry.y, in.dirUv.x, in.dirUv.y);
        trace.exact = true;
        trace.exactT = hit.t, trace.exactU = hit.u, trace.exactV = hit.v;
        trace.result.uvHit = glm::vec2(float(hit.u), float(hit.v));
        trace.result.depthHit = float(hit.t);
        trace.result.nCoarse = uint16_t(std::min<uint32_t>(hit.cellsTested, 65535));
        trace.result.hit = true;
        return trace;
    }
    const Kernel kernel = SettingsKernel(s);
    std::shared_ptr<const void> params;
    const BatchJob job = MakeBatchJob(kernel, BindTextures(field, s.sampler), params);
    detail::DenormalsAreZeroScope gpuFloatMode;  // as in the frame loop's tiles
    const RayRun run = MarchRay(job, trace.input, [&](const TracedFetch& f) {
        trace.fetches.push_back({glm::vec2(f.u, f.v), f.t, f.sampled});
    });
    trace.result = run.result;
    trace.counts = run.counts;
    return trace;
}

std::string FormatTrace(const PixelTrace& t) {
    std::string s;
    char line[256];
    std::snprintf(
        line, sizeof line,
        "pixel (%d, %d): ray enters at uv (%.9g, %.9g), moves (%.9g, %.9g) uv per unit "
        "depth\n",
        t.x, t.y, double(t.input.uvEntry.x), double(t.input.uvEntry.y),
        double(t.input.dirUv.x), double(t.input.dirUv.y));
    s += line;
    if (t.exact) {
        std::snprintf(line, sizeof line,
                      "exact first hit: t %.17g at uv (%.17g, %.17g); %u bilinear cells "
                      "solved, no fetches\n",
                      t.exactT, t.exactU, t.exactV, unsigned(t.result.nCoarse));
        s += line;
        return s;
    }
    s += "  fetch          u            v    ray depth t  sampled depth\n";
    for (size_t k = 0; k < t.fetches.size(); ++k) {
        const TraceFetch& f = t.fetches[k];
        std::snprintf(line, sizeof line, "  %5zu %12.9f %12.9f %13.9f %15.9f\n", k + 1,
                      double(f.uv.x), double(f.uv.y), double(f.t), double(f.depth));
        s += line;
    }
    std::snprintf(
        line, sizeof line,
        "result: %s at uv (%.9g, %.9g), depth %.9g; %u coarse + %u refine iterations, "
        "%u fetches, %u texel reads%s\n",
        t.result.hit ? "hit" : "no hit", double(t.result.uvHit.x),
        double(t.result.uvHit.y), double(t.result.depthHit), unsigned(t.result.nCoarse),
        unsigned(t.result.nRefine), t.counts.nFetches, t.counts.nTexelReads,
        t.result.budgetExhausted ? ", budget exhausted" : "");
    s += line;
    return s;
}

}  // namespace reliefsim
