// The reference pass (render/reference.h).
#include "render/reference.h"

#include <tbb/parallel_for.h>

#include <chrono>

#include "metrics/exact.h"
#include "raster/rasterizer.h"
#include "render/exact_batch.h"

namespace reliefsim {

bool PixelMissesGeometry(const ExactSurface& surface, const MarchInput& in, float tHit,
                         float tRef, double step) {
    if (!(double(tHit) - double(tRef) > step)) return false;
    return MissedGeometry(
        tHit, tRef, step,
        surface.LeavesBetween(in.uvEntry.x, in.uvEntry.y, in.dirUv.x, in.dirUv.y, tRef,
                              tHit, kReferenceLeaveTolerance));
}

double CoarseStepDepth(const RenderSettings& s) {
    if (s.method == kExactMethod) return 0.0;
    const Kernel kernel = SettingsKernel(s);
    const auto it = kernel.values.find("linear_steps");
    return it == kernel.values.end() ? 0.0 : 1.0 / it->second;
}

ReferenceRecord RenderReference(const DepthField& field, const RenderSettings& s,
                                const FrameRecord& record) {
    const auto start = std::chrono::steady_clock::now();
    const ExactSurface surface(field, s.sampler.wrap);
    const ViewUniforms view = MakeViewUniforms(s);
    SamplerState shading = s.sampler;
    shading.filter = Filter::Bilinear;
    BatchJob job;
    // The cone-normal soft shadow and the cone AO read the kernel's cone map: bind it as
    // the frame did (through the cache), with the shading's filter for the depth.
    job.textures = s.shadow == ShadowKind::Cone || s.ao != AoKind::None
                       ? BindKernelTextures(field, shading, SettingsKernel(s), s.maps)
                       : BindTextures(field, shading);
    job.params = &surface;
    job.view = &view;
    job.slopeScale = SceneSlopeScale(s);
    job.light = SceneLight(s);
    job.shadow = SceneShadow(s);
    const double step = CoarseStepDepth(s);
    const int w = record.width, h = record.height;
    const size_t n = size_t(w) * size_t(h);
    ReferenceRecord ref;
    ref.u.assign(n, 0.0f);
    ref.v.assign(n, 0.0f);
    ref.depth.assign(n, 0.0f);
    ref.rgb.assign(3 * n, 0.0f);
    ref.missed.assign(n, 0);
    tbb::parallel_for(0, h, [&](int y) {
        detail::DenormalsAreZeroScope gpuFloatMode;  // as the frame's tiles run
        std::vector<int32_t> px, py;
        for (int x = 0; x < w; ++x)
            if (record.Covered(record.Index(x, y))) px.push_back(x), py.push_back(y);
        const size_t m = px.size();
        if (m == 0) return;
        std::vector<float> u(m), v(m), depth(m), rgb(3 * m);
        std::vector<uint16_t> coarse(m), refine(m);
        std::vector<uint32_t> fetches(m), texels(m);
        std::vector<uint8_t> flags(m);
        LaneBatch b;
        b.n = int(m);
        b.px = px.data(), b.py = py.data(), b.rgb = rgb.data();
        b.u = u.data(), b.v = v.data(), b.depth = depth.data();
        b.nCoarse = coarse.data(), b.nRefine = refine.data();
        b.fetches = fetches.data(), b.texelReads = texels.data(), b.flags = flags.data();
        RunExactBatch(job, b);
        for (size_t k = 0; k < m; ++k) {
            const size_t i = record.Index(px[k], py[k]);
            ref.u[i] = u[k], ref.v[i] = v[k], ref.depth[i] = depth[k];
            for (size_t c = 0; c < 3; ++c) ref.rgb[3 * i + c] = rgb[3 * k + c];
            ref.missed[i] = PixelMissesGeometry(surface, PixelToRay(view, px[k], py[k]),
                                                record.hitDepth[i], depth[k], step)
                                ? 1
                                : 0;
        }
    });
    ref.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return ref;
}

}  // namespace reliefsim
