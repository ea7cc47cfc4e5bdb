// Lane widths, runtime ISA dispatch, kernel parameters and the traced single-lane run.
#include "render/batch.h"

#include <memory>

#include "core/error.h"
#include "core/param_name.h"
#include "render/lane_driver.h"

RS_DECLARE_LANE_WIDTH(W1)
RS_DECLARE_LANE_WIDTH(W4)
#if RS_HAVE_AVX2_UNIT
RS_DECLARE_LANE_WIDTH(W8Avx2)
#endif
#if RS_HAVE_AVX512_UNIT
RS_DECLARE_LANE_WIDTH(W16Avx512)
#endif

namespace reliefsim {

namespace {

[[maybe_unused]] bool CpuHas([[maybe_unused]] const char* what) {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_cpu_init();
    if (std::string_view(what) == "avx2")
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    if (std::string_view(what) == "avx512")
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
               __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
               __builtin_cpu_supports("fma");
#endif
    return false;
}

std::vector<LaneWidthInfo> MakeWidths() {
    std::vector<LaneWidthInfo> w = {
        {1, "baseline", true, &RunBatchW1, &SampleChainW1, &SampleLanesW1},
        {4, "baseline", true, &RunBatchW4, &SampleChainW4, &SampleLanesW4}};
#if RS_HAVE_AVX2_UNIT
    w.push_back({8, "avx2", CpuHas("avx2"), &RunBatchW8Avx2, &SampleChainW8Avx2,
                 &SampleLanesW8Avx2});
#endif
#if RS_HAVE_AVX512_UNIT
    w.push_back({16, "avx512", CpuHas("avx512"), &RunBatchW16Avx512,
                 &SampleChainW16Avx512, &SampleLanesW16Avx512});
#endif
    return w;
}

struct TraceIsa {};

}  // namespace

std::span<const LaneWidthInfo> LaneWidths() {
    static const std::vector<LaneWidthInfo> kWidths = MakeWidths();
    return kWidths;
}

const LaneWidthInfo& PickLaneWidth(int width) {
    const auto all = LaneWidths();
    std::string valid;
    for (const LaneWidthInfo& w : all) {
        if (w.supported) valid += (valid.empty() ? "" : ", ") + std::to_string(w.width);
    }
    if (width == 0) {
        const LaneWidthInfo* best = &all[0];
        for (const LaneWidthInfo& w : all)
            if (w.supported) best = &w;
        return *best;
    }
    for (const LaneWidthInfo& w : all) {
        if (w.width != width) continue;
        if (!w.supported)
            throw Error(ParamName("lanes") + " " + std::to_string(width) +
                        ": this CPU lacks " + w.isa + "; valid here: 0 (the widest), " +
                        valid);
        return w;
    }
    throw Error(ParamName("lanes") + " " + std::to_string(width) +
                ": not a lane width of this build; valid: 0 (the widest), " + valid);
}

std::shared_ptr<const void> MakeKernelParams(int kernelIndex, const ParamValues& values) {
    return VisitKernelType(kernelIndex, [&](auto type) -> std::shared_ptr<const void> {
        using K = typename decltype(type)::type;
        return std::make_shared<typename K::Params>(K::FromValues(values));
    });
}

namespace {

// One ray as a batch of one lane, run by `run(batch)`.
template <class Run>
RayRun RunOneRay(const MarchInput& in, Run&& run) {
    RayRun out;
    float u = 0, v = 0, depth = 0;
    uint8_t flags = 0;
    LaneBatch b;
    b.n = 1;
    b.uEntry = &in.uvEntry.x, b.vEntry = &in.uvEntry.y;
    b.du = &in.dirUv.x, b.dv = &in.dirUv.y;
    b.viewZ = &in.viewZ;
    b.u = &u, b.v = &v, b.depth = &depth;
    b.nCoarse = &out.result.nCoarse, b.nRefine = &out.result.nRefine;
    b.fetches = &out.counts.nFetches, b.texelReads = &out.counts.nTexelReads;
    b.flags = &flags;
    run(b);
    out.result.uvHit = glm::vec2(u, v);
    out.result.depthHit = depth;
    out.result.hit = !(flags & kFlagNoHit);
    out.result.budgetExhausted = (flags & kFlagBudgetExhausted) != 0;
    return out;
}

}  // namespace

RayRun MarchRay(const BatchJob& job, const MarchInput& in, const TraceSink& trace) {
    using L = Lanes<1, TraceIsa>;
    return RunOneRay(in, [&](LaneBatch& b) {
        VisitKernelType(job.kernelIndex, [&](auto type) {
            using K = typename decltype(type)::type;
            const auto& params = *static_cast<const typename K::Params*>(job.params);
            detail::MarchPacks<K, L, 1>(
                params, job, b,
                [&](const L::M& active, const Fetch<L>& f, const L::F& sampled) {
                    if (trace && active[0]) trace({f.u[0], f.v[0], f.t[0], sampled[0]});
                });
        });
    });
}

RayRun MarchRayAt(const LaneWidthInfo& width, const BatchJob& job, const MarchInput& in) {
    return RunOneRay(in, [&](LaneBatch& b) { width.fn(job, b); });
}

BatchJob MakeBatchJob(const Kernel& kernel, const Textures& textures,
                      std::shared_ptr<const void>& params) {
    params = MakeKernelParams(kernel.index, kernel.values);
    BatchJob job;
    job.kernelIndex = kernel.index;
    job.params = params.get();
    job.budget = kernel.Budget();
    job.textures = textures;
    if (!job.textures.padded)
        job.textures.padded = BindTextures(*textures.depth, textures.sampler).padded;
    const KernelInfo& info = kernel.Info();
    if (!info.maps.empty() && job.textures.cone.size() != size_t(info.mapLayers))
        throw Error(ParamName("method") + " " + std::string(info.name) +
                    ": reads a cone map of " + std::to_string(info.mapLayers) +
                    " layer(s) and " + std::to_string(job.textures.cone.size()) +
                    " are bound (render/kernel_maps.h BindKernelTextures makes it)");
    RS_CHECK(job.textures.cone.empty() || job.textures.conePadded);
    return job;
}

}  // namespace reliefsim
