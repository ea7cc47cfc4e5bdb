// The exact reference as the frame's fragment stage (render/exact_batch.h).
#include "render/exact_batch.h"

#include <algorithm>

#include "metrics/exact.h"
#include "render/lane_driver.h"

namespace reliefsim {

namespace {
struct IsaExact {};
}  // namespace

void RunExactBatch(const BatchJob& job, LaneBatch& b) {
    using L = Lanes<1, IsaExact>;
    using F = L::F;
    using M = L::M;
    const ExactSurface& surface = *static_cast<const ExactSurface*>(job.params);
    const LaneTextures tex = BindLanes(job.textures);
    for (int i = 0; i < b.n; ++i) {
        const MarchInput in = b.px ? PixelToRay(*job.view, b.px[i], b.py[i])
                                   : MarchInput{{b.uEntry[i], b.vEntry[i]},
                                                {b.du[i], b.dv[i]},
                                                b.viewZ ? b.viewZ[i] : 1.0f};
        const ExactHit hit =
            surface.FirstHit(in.uvEntry.x, in.uvEntry.y, in.dirUv.x, in.dirUv.y);
        b.u[i] = float(hit.u);
        b.v[i] = float(hit.v);
        b.depth[i] = float(hit.t);
        b.nCoarse[i] = uint16_t(std::min<uint32_t>(hit.cellsTested, 65535));
        b.nRefine[i] = 0;
        b.fetches[i] = 0;
        b.texelReads[i] = 0;
        b.flags[i] = 0;  // the surface is always met, by t = 1 at the latest
        // The light ray of the exact hit is the frame's light-ray kernel, counted apart.
        F shadowFetches(0.0f);
        const F vis = LightVisibility<L>(tex, job.shadow, F(b.u[i]), F(b.v[i]), M(true),
                                         shadowFetches);
        const F ao = AmbientOcclusion<L>(tex, job.shadow, F(b.u[i]), F(b.v[i]), M(true),
                                         shadowFetches);
        if (b.shadowFetches) b.shadowFetches[i] = uint32_t(shadowFetches[0]);
        if (b.visibility) b.visibility[i] = vis[0];
        if (b.ambient) b.ambient[i] = ao[0];
        if (!b.rgb) continue;
        F rgb[3] = {F(0.0f), F(0.0f), F(0.0f)};
        detail::ShadeHit<L>(tex, job.slopeScale, job.light, F(b.u[i]), F(b.v[i]),
                            F(b.depth[i]), M(true), M(true), vis, ao, rgb);
        for (int c = 0; c < 3; ++c) b.rgb[3 * i + c] = rgb[c][0];
    }
}

}  // namespace reliefsim
