// The exact reference (metrics/exact.h) as the frame's fragment stage: `render --method
// exact` runs it where a kernel would run.
#pragma once

#include "render/batch.h"

namespace reliefsim {

/// A BatchFn for the exact reference: job.params points to the frame's ExactSurface.
/// Each lane gets its first hit (u, v, depth rounded to float), nCoarse = the bilinear
/// cells whose quadratic was solved (saturated at 65535), nRefine = fetches = texel
/// reads = 0 (it reads the depths directly, not through the sampler), and the shading
/// every kernel's hit gets (detail::ShadeHit, at one lane: bit-identical at every
/// width).
void RunExactBatch(const BatchJob& job, LaneBatch& batch);

}  // namespace reliefsim
