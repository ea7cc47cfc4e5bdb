// Step-by-step trace of one pixel's kernel.
#include "render/trace.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "metrics/exact.h"
#include "metrics/reference_metrics.h"
#include "raster/rasterizer.h"
#include "render/batch.h"
#include "render/reference.h"

namespace reliefsim {

namespace {

void TraceReferenceErrors(PixelTrace& trace, const ExactSurface& surface,
                          const DepthField& field, double step, float tRef, float tHit,
                          float uRef, float vRef) {
    PixelTrace::Reference& r = trace.reference;
    r.depthError = double(tHit) - double(tRef);
    r.uvErrorTexels = UvErrorTexels(double(trace.result.uvHit.x) - double(uRef),
                                    double(trace.result.uvHit.y) - double(vRef),
                                    field.width, field.height);
    r.missedGeometry = PixelMissesGeometry(surface, trace.input, tHit, tRef, step);
}

}  // namespace

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
    const ExactSurface surface(field, s.sampler.wrap);
    const MarchInput& in = trace.input;
    detail::DenormalsAreZeroScope gpuFloatMode;  // as in the frame loop's tiles
    const ExactHit hit =
        surface.FirstHit(in.uvEntry.x, in.uvEntry.y, in.dirUv.x, in.dirUv.y);
    trace.reference.t = hit.t, trace.reference.u = hit.u, trace.reference.v = hit.v;
    trace.reference.cells = hit.cellsTested;
    if (s.method == kExactMethod) {
        trace.exact = true;
        trace.result.uvHit = glm::vec2(float(hit.u), float(hit.v));
        trace.result.depthHit = float(hit.t);
        trace.result.nCoarse = uint16_t(std::min<uint32_t>(hit.cellsTested, 65535));
        trace.result.hit = true;
        return trace;
    }
    const Kernel kernel = SettingsKernel(s);
    std::shared_ptr<const void> params;
    const BatchJob job = MakeBatchJob(
        kernel, BindKernelTextures(field, s.sampler, kernel, s.maps), params);
    const RayRun run = MarchRay(job, trace.input, [&](const TracedFetch& f) {
        trace.fetches.push_back({glm::vec2(f.u, f.v), f.t, f.sampled});
    });
    trace.result = run.result;
    trace.counts = run.counts;
    // The errors as the reference pass computes them: from the float hits.
    const float tRef = float(hit.t), tHit = trace.result.depthHit;
    TraceReferenceErrors(trace, surface, field, CoarseStepDepth(s), tRef, tHit,
                         float(hit.u), float(hit.v));
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
    const PixelTrace::Reference& r = t.reference;
    if (t.exact) {
        std::snprintf(line, sizeof line,
                      "exact first hit: t %.17g at uv (%.17g, %.17g); %u bilinear cells "
                      "solved, no fetches\n",
                      r.t, r.u, r.v, unsigned(r.cells));
        s += line;
        return s;
    }
    s += "  fetch          u            v    ray depth t  sampled depth  ray is\n";
    for (size_t k = 0; k < t.fetches.size(); ++k) {
        const TraceFetch& f = t.fetches[k];
        std::snprintf(line, sizeof line, "  %5zu %12.9f %12.9f %13.9f %15.9f  %s\n",
                      k + 1, double(f.uv.x), double(f.uv.y), double(f.t), double(f.depth),
                      f.t >= f.depth ? "inside" : "above");
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
    std::snprintf(
        line, sizeof line,
        "exact:  first hit at uv (%.9g, %.9g), depth %.9g; depth error %+.3g, uv "
        "error %.3g texels%s\n",
        r.u, r.v, r.t, r.depthError, r.uvErrorTexels,
        r.missedGeometry ? "; MISSED GEOMETRY (it skipped a structure)" : "");
    s += line;
    return s;
}

std::string TraceJson(const PixelTrace& t) {
    nlohmann::ordered_json j;
    j["pixel"] = {t.x, t.y};
    j["ray"] = {{"uv_entry", {t.input.uvEntry.x, t.input.uvEntry.y}},
                {"dir_uv", {t.input.dirUv.x, t.input.dirUv.y}}};
    nlohmann::ordered_json fetches = nlohmann::ordered_json::array();
    for (const TraceFetch& f : t.fetches)
        fetches.push_back({{"u", f.uv.x},
                           {"v", f.uv.y},
                           {"t", f.t},
                           {"sampled", f.depth},
                           {"inside", f.t >= f.depth}});
    j["fetches"] = fetches;
    j["result"] = {{"hit", t.result.hit},
                   {"uv", {t.result.uvHit.x, t.result.uvHit.y}},
                   {"depth", t.result.depthHit},
                   {"coarse_iterations", t.result.nCoarse},
                   {"refine_iterations", t.result.nRefine},
                   {"fetches", t.counts.nFetches},
                   {"texel_reads", t.counts.nTexelReads},
                   {"budget_exhausted", t.result.budgetExhausted}};
    const PixelTrace::Reference& r = t.reference;
    j["reference"] = {{"t", r.t},
                      {"uv", {r.u, r.v}},
                      {"cells", r.cells},
                      {"depth_error", r.depthError},
                      {"uv_error_texels", r.uvErrorTexels},
                      {"missed_geometry", r.missedGeometry}};
    return j.dump(2) + "\n";
}

}  // namespace reliefsim
