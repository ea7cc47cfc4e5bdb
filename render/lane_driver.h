// The fragment driver: runs a lane-generic kernel (kernels/kernel.h) over a pack of
// lanes.
//
// It owns what every kernel shares: the trip loop (one fetch per active lane per trip, as
// the GLSL twins' do-while loops), the active mask, the fetch budget, and the per-lane
// counts (fetches, texel reads). Kernels own only their step. Included by each lane
// width's translation unit (batch_w*.cpp) with that unit's ISA tag.
#pragma once

#include <algorithm>

#include "core/record.h"
#include "kernels/registry.h"
#include "render/batch.h"

namespace reliefsim::detail {

/// Runs pack [base, base + width) of the batch (lanes past n repeat lane n-1, inactive).
/// onFetch(active, fetch, sampled) is called once per trip after the fetch.
template <class K, class L, class OnFetch>
RS_INLINE void MarchPack(const typename K::Params& params, const BatchJob& job,
                         LaneBatch& b, int base, OnFetch&& onFetch) {
    using F = typename L::F;
    using M = typename L::M;
    constexpr int N = L::kWidth;
    LaneRay<L> ray;
    M valid(true);
    if (base + N <= b.n) {
        ray.uEntry.copy_from(b.uEntry + base, stdx::element_aligned);
        ray.vEntry.copy_from(b.vEntry + base, stdx::element_aligned);
        ray.du.copy_from(b.du + base, stdx::element_aligned);
        ray.dv.copy_from(b.dv + base, stdx::element_aligned);
    } else {
        for (int k = 0; k < N; ++k) {
            const int i = base + k < b.n ? base + k : b.n - 1;
            ray.uEntry[k] = b.uEntry[i];
            ray.vEntry[k] = b.vEntry[i];
            ray.du[k] = b.du[i];
            ray.dv[k] = b.dv[i];
            valid[k] = base + k < b.n;
        }
    }
    typename K::template State<L> state;
    Fetch<L> fetch;
    K::template Begin<L>(params, ray, state, fetch);
    F fetches(0.0f), texels(0.0f);
    M exhausted(false);
    M active = valid;
    const F budget(float(job.budget));
    // A budget, when set, is at least 1: the first fetch is always allowed.
    while (Any(active)) {
        const F sampled =
            SampleHeightLanes<L>(job.textures, fetch.u, fetch.v, active, texels);
        Assign(active, fetches, fetches + F(1.0f));
        onFetch(active, fetch, sampled);
        M want = K::template Step<L>(params, ray, state, sampled, active, fetch);
        if (job.budget != 0) {
            const M refused = want && (fetches >= budget);
            exhausted = exhausted || refused;
            want = want && !refused;
        }
        active = want;
    }
    LaneOutcome<L> out;
    K::template End<L>(params, ray, state, out);
    for (int k = 0; k < N; ++k) {
        if (!valid[k]) continue;
        const int i = base + k;
        b.u[i] = out.u[k];
        b.v[i] = out.v[k];
        b.depth[i] = out.depth[k];
        b.nCoarse[i] = uint16_t(out.nCoarse[k]);
        b.nRefine[i] = uint16_t(out.nRefine[k]);
        b.fetches[i] = uint32_t(fetches[k]);
        b.texelReads[i] = uint32_t(texels[k]);
        uint8_t f = 0;
        if (!out.hit[k]) f |= kFlagNoHit;
        if (exhausted[k]) f |= kFlagBudgetExhausted;
        b.flags[i] = f;
    }
}

/// The batch entry point of one lane width: every pack of the batch, for the job's
/// kernel.
template <class L>
void RunBatch(const BatchJob& job, LaneBatch& b) {
    VisitKernelType(job.kernelIndex, [&](auto type) {
        using K = typename decltype(type)::type;
        const auto& params = *static_cast<const typename K::Params*>(job.params);
        for (int base = 0; base < b.n; base += L::kWidth)
            MarchPack<K, L>(params, job, b, base,
                            [](const auto&, const auto&, const auto&) {});
    });
}

/// SampleChainFn of one lane width.
template <class L>
float SampleChain(const Textures& tex, const float* u0, const float* v0, int n, int chain,
                  uint64_t* texelReads) {
    using F = typename L::F;
    F sum(0.0f);
    double texels = 0.0;
    for (int base = 0; base + L::kWidth <= n; base += L::kWidth) {
        F u, v, reads(0.0f);
        u.copy_from(u0 + base, stdx::element_aligned);
        v.copy_from(v0 + base, stdx::element_aligned);
        const typename L::M all(true);
        for (int k = 0; k < chain; ++k) {
            const F h = SampleHeightLanes<L>(tex, u, v, all, reads);
            u = u + h * F(0.01f) + F(0.0031f);
            v = v + F(0.0017f);
            sum = sum + h;
        }
        texels += double(stdx::reduce(reads));
    }
    *texelReads += uint64_t(texels);
    return stdx::reduce(sum);
}

}  // namespace reliefsim::detail
