// The reference pass of a frame: the exact first hit (metrics/exact.h) of every covered
// pixel's ray, its shading, and the missed-geometry test of the frame's hits.
#pragma once

#include "kernels/kernel.h"
#include "metrics/reference_metrics.h"
#include "render/scene.h"
#include "texture/depth_field.h"

namespace reliefsim {

class ExactSurface;

/// Depth below which a ray counts as outside the relief in the missed-geometry test
/// (ExactSurface::LeavesBetween; float rounding of the kernels' hits is about 1e-7).
inline constexpr double kReferenceLeaveTolerance = 1e-6;

/// The missed-geometry test of one pixel (MissedGeometry): tHit more than `step` beyond
/// tRef, and the ray `in` left the relief in between. The walk runs only when the first
/// condition holds. The frame's reference pass and trace both decide with this.
bool PixelMissesGeometry(const ExactSurface& surface, const MarchInput& in, float tHit,
                         float tRef, double step);

/// One coarse step's depth of the settings' kernel: 1 / linear_steps for the kernels
/// that step linearly (those with a `linear_steps` parameter), 0 for the others and for
/// the exact method.
double CoarseStepDepth(const RenderSettings& settings);

/// The reference of `record` (a frame rendered with `settings`): for each covered pixel,
/// the exact hit of the same ray (PixelToRay), shaded as the kernels shade (with the
/// settings' sampler made bilinear: the reference's surface), and the missed-geometry
/// test of record's hit against it (ReferenceRecord, MissedGeometry with
/// CoarseStepDepth). Rows run in parallel under the caller's thread limit; each pixel's
/// result is independent of the others, so the outputs do not depend on threads.
ReferenceRecord RenderReference(const DepthField& field, const RenderSettings& settings,
                                const FrameRecord& record);

}  // namespace reliefsim
