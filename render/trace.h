// Step-by-step trace of one pixel's kernel: every fetch with its uv, ray depth and value.
#pragma once

#include <string>
#include <vector>

#include "render/scene.h"
#include "texture/depth_field.h"

namespace reliefsim {

struct TraceFetch {
    glm::vec2 uv;  ///< where the sampler was called
    float t;       ///< the ray depth of the fetch, as the kernel computed it
    float depth;   ///< what the sampler returned
};

struct PixelTrace {
    int x = 0, y = 0;
    MarchInput input;
    MarchResult result;
    FetchCounts counts;
    std::vector<TraceFetch> fetches;
    /// Method exact (metrics/exact.h): no fetches; result holds the hit as the record
    /// stores it, reference the same hit in double.
    bool exact = false;
    /// The exact first hit of the same ray (every method), and the pixel's errors against
    /// it as the frame's reference pass computes them (render/reference.h).
    struct Reference {
        double t = 0, u = 0, v = 0;  ///< in double
        uint32_t cells = 0;          ///< bilinear cells solved
        double depthError = 0;       ///< hit depth - exact depth (both as floats)
        double uvErrorTexels = 0;
        bool missedGeometry = false;
    } reference;
};

/// The trace as JSON (`trace --json`): pixel, ray, fetches (u, v, t, sampled, inside),
/// result, reference.
std::string TraceJson(const PixelTrace& trace);

/// Runs the settings' kernel for pixel (x, y) alone, recording every fetch. The kernel,
/// sampler and inputs are those of Render(), so the result equals the frame's record at
/// that pixel. Throws Error for a pixel outside the image.
PixelTrace TracePixel(const DepthField& field, const RenderSettings& settings, int x,
                      int y);

/// Human-readable trace: the ray, one line per fetch, and the result.
std::string FormatTrace(const PixelTrace& trace);

}  // namespace reliefsim
