// Step-by-step trace of one pixel's kernel.
#include "app/trace.h"

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "raster/rasterizer.h"

namespace reliefsim {

namespace {

/// Wraps the counting sampler and records every call (HeightSampler concept).
class TracingSampler {
  public:
    TracingSampler(CountingSampler& inner, const MarchInput& in,
                   std::vector<TraceFetch>& log)
        : inner_(inner), in_(in), log_(log) {}
    float Sample(glm::vec2 uv) {
        float d = inner_.Sample(uv);
        glm::vec2 off = uv - in_.uvEntry;
        float t = std::fabs(in_.dirUv.x) >= std::fabs(in_.dirUv.y)
                      ? (in_.dirUv.x != 0.0f ? off.x / in_.dirUv.x : NAN)
                      : off.y / in_.dirUv.y;
        log_.push_back({uv, t, d});
        return d;
    }

  private:
    CountingSampler& inner_;
    const MarchInput& in_;
    std::vector<TraceFetch>& log_;
};

}  // namespace

PixelTrace TracePixel(const HeightField& field, const RenderSettings& s, int x, int y) {
    ValidateSettings(s);
    if (x < 0 || y < 0 || x >= s.width || y >= s.height)
        throw Error("--pixel " + std::to_string(x) + "," + std::to_string(y) +
                    ": outside the " + std::to_string(s.width) + "x" +
                    std::to_string(s.height) + " image");
    const MethodInfo& method = FindMethod(s.method);
    Kernel kernel = MakeKernel(method, ResolveParams(method, s.set));
    PixelTrace trace;
    trace.x = x;
    trace.y = y;
    trace.input = PixelToRay(MakeViewUniforms(s), x, y);
    detail::DenormalsAreZeroScope gpuFloatMode;  // as in the frame loop's tiles
    CountingSampler counting(field, s.sampler, &trace.counts);
    TracingSampler tracing(counting, trace.input, trace.fetches);
    trace.result =
        std::visit([&](const auto& k) { return k.March(trace.input, tracing); }, kernel);
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
    s += "  fetch          u            v   ray depth t~  sampled depth\n";
    for (size_t k = 0; k < t.fetches.size(); ++k) {
        const TraceFetch& f = t.fetches[k];
        // t is recovered from the uv, so it carries rounding noise: print 6 decimals.
        const double t = std::fabs(f.t) < 1e-6f ? 0.0 : double(f.t);
        std::snprintf(line, sizeof line, "  %5zu %12.9f %12.9f %13.6f %15.9f\n", k + 1,
                      double(f.uv.x), double(f.uv.y), t, double(f.depth));
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
