// The fragment driver: runs a lane-generic kernel (kernels/kernel.h) over a pack of
// lanes.
//
// It owns what every kernel shares: the trip loop (one fetch per active lane per trip, as
// the GLSL twins' do-while loops), the active mask, the fetch budget, and the per-lane
// counts (fetches, texel reads). Kernels own only their step. Included by each lane
// width's translation unit (batch_w*.cpp) with that unit's ISA tag.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/record.h"
#include "kernels/registry.h"
#include "render/batch.h"

#ifndef RS_PACKS_IN_FLIGHT
#define RS_PACKS_IN_FLIGHT 4
#endif

namespace reliefsim::detail {

/// The shading of a hit (not part of the kernel's counts): Lambert with a normal from
/// central differences of the height sampler (four uncounted fetches), albedo by depth,
/// magenta where the kernel has no answer (docs/architecture.md "Shading").
/// `visibility` (kernels/shadow.h LightVisibility, 1 without shadows) scales the
/// Lambert term.
template <class L>
RS_INLINE void ShadeHit(const LaneTextures& tex, float slopeScale, const glm::vec3& light,
                        const typename L::F& u, const typename L::F& v,
                        const typename L::F& depth, const typename L::M& hit,
                        const typename L::M& active, const typename L::F& visibility,
                        const typename L::F& ambient, typename L::F (&rgb)[3]) {
    using F = typename L::F;
    const float du = 1.0f / float(tex.width), dv = 1.0f / float(tex.height);
    F unused(0.0f);
    // (SampleHeightLanes called directly: through a lambda GCC kept the four fetches
    // out of line.)
    const F hu1 = SampleHeightLanes<L>(tex, u + F(du), v + F(0.0f), active, unused);
    const F hu0 = SampleHeightLanes<L>(tex, u - F(du), v - F(0.0f), active, unused);
    const F hv1 = SampleHeightLanes<L>(tex, u + F(0.0f), v + F(dv), active, unused);
    const F hv0 = SampleHeightLanes<L>(tex, u - F(0.0f), v - F(dv), active, unused);
    const F ddu = (hu1 - hu0) / F(2 * du);
    const F ddv = (hv1 - hv0) / F(2 * dv);
    F nx = ddu * F(slopeScale), ny = ddv * F(slopeScale), nz(1.0f);
    const F inv = F(1.0f) / stdx::sqrt(nx * nx + ny * ny + nz * nz);
    nx = nx * inv, ny = ny * inv, nz = nz * inv;
    const F dot = nx * F(light.x) + ny * F(light.y) + nz * F(light.z);
    const F lambert = Select(dot > F(0.0f), dot, F(0.0f));
    const F d = Select(depth < F(0.0f), F(0.0f), Select(depth > F(1.0f), F(1.0f), depth));
    const float top[3] = {0.93f, 0.80f, 0.55f}, deep[3] = {0.35f, 0.45f, 0.65f};
    const float miss[3] = {0.9f, 0.1f, 0.6f};  // no hit: magenta, as peers do
    // (ambient is 1 without AO: then F(0.15f) * 1 is 0.15f, bit for bit.)
    const F lit = F(0.15f) * ambient + F(0.85f) * (lambert * visibility);
    for (int c = 0; c < 3; ++c) {
        const F albedo = Select(hit, F(top[c]) + F(deep[c] - top[c]) * d, F(miss[c]));
        rgb[c] = albedo * lit;
    }
}

/// One pack of lanes in flight: its rays, kernel state, next fetch and counts.
template <class K, class L>
struct PackRun {
    using F = typename L::F;
    using M = typename L::M;
    LaneRay<L> ray{F(0.0f), F(0.0f), F(0.0f), F(0.0f), F(1.0f)};
    typename K::template State<L> state;
    Fetch<L> fetch;
    F fetches{0.0f}, texels{0.0f};
    M valid{true}, exhausted{false}, active{false};
    int base = 0;
};

/// Whether BeginPack loads the rays inline (LoadPackRaysBody) rather than through the
/// out-of-line LoadPackRays: at one lane only. There a pack is one ray, so the call comes
/// once per ray; inline, the shortest kernels (parallax, offset-limit: ~2 fetches a ray)
/// ran 0.85-0.87x the time at one lane, linear, secant, mcns and maxmip 0.87-1.03x
/// (bench/kernels_bench BM_Kernel/<kernel>/1, five alternating rounds). Inlining
/// StorePack too helped those two more (0.76-0.80x) but made secant and linear
/// 1.07-1.10x slower: it stays out of line.
template <class L>
inline constexpr bool kLoadRaysInline = L::kWidth == 1;

/// The rays of pack [base, base + width) of the batch (lanes past n repeat lane n-1 and
/// are not valid). LoadPackRays runs it out of line (kLoadRaysInline).
template <class L>
RS_INLINE void LoadPackRaysBody(const BatchJob& job, const LaneBatch& b, int base,
                                LaneRay<L>& ray, typename L::M& valid) {
    using F = typename L::F;
    constexpr int N = L::kWidth;
    valid = typename L::M(true);
    if (b.px) {
        F px(0.0f), py(0.0f);
        for (int k = 0; k < N; ++k) {
            const int i = base + k < b.n ? base + k : b.n - 1;
            px[k] = float(b.px[i]);
            py[k] = float(b.py[i]);
            valid[k] = base + k < b.n;
        }
        ray = PixelToRayLanes<L>(*job.view, px, py);
    } else if (base + N <= b.n) {
        ray.uEntry.copy_from(b.uEntry + base, stdx::element_aligned);
        ray.vEntry.copy_from(b.vEntry + base, stdx::element_aligned);
        ray.du.copy_from(b.du + base, stdx::element_aligned);
        ray.dv.copy_from(b.dv + base, stdx::element_aligned);
        if (b.viewZ)
            ray.viewZ.copy_from(b.viewZ + base, stdx::element_aligned);
        else
            ray.viewZ = F(1.0f);
    } else {
        for (int k = 0; k < N; ++k) {
            const int i = base + k < b.n ? base + k : b.n - 1;
            ray.uEntry[k] = b.uEntry[i];
            ray.vEntry[k] = b.vEntry[i];
            ray.du[k] = b.du[i];
            ray.dv[k] = b.dv[i];
            ray.viewZ[k] = b.viewZ ? b.viewZ[i] : 1.0f;
            valid[k] = base + k < b.n;
        }
    }
    ray.mapW = float(job.textures.depth ? job.textures.depth->width : 1);
    ray.mapH = float(job.textures.depth ? job.textures.depth->height : 1);
}

/// LoadPackRaysBody out of line: kernel-independent and run once per pack, so each lane
/// unit holds it once rather than once per kernel (StorePack says why that matters).
template <class L>
RS_NOINLINE void LoadPackRays(const BatchJob& job, const LaneBatch& b, int base,
                              LaneRay<L>& ray, typename L::M& valid) {
    LoadPackRaysBody<L>(job, b, base, ray, valid);
}

/// Loads pack [base, base + width) of the batch and begins the kernel on it.
template <class K, class L>
RS_INLINE void BeginPack(const typename K::Params& params, const BatchJob& job,
                         const LaneBatch& b, int base, PackRun<K, L>& p) {
    using F = typename L::F;
    // A slot is reused for the next pack: the driver's fields are reset here, the ray
    // below and the kernel's state and first fetch by Begin (not a whole-struct copy of
    // a fresh PackRun, which measured as 4% of a relief batch).
    p.fetches = F(0.0f);
    p.texels = F(0.0f);
    p.exhausted = typename L::M(false);
    p.base = base;
    if constexpr (kLoadRaysInline<L>)
        LoadPackRaysBody<L>(job, b, base, p.ray, p.valid);
    else
        LoadPackRays<L>(job, b, base, p.ray, p.valid);
    K::template Begin<L>(params, p.ray, p.state, p.fetch);
    p.active = p.valid;  // a budget, when set, is >= 1: the first fetch is allowed
}

/// One trip of a pack: a fetch for every active lane, then the kernel's step and the
/// budget. onFetch(active, fetch, sampled) sees every fetch.
template <class K, class L, class OnFetch>
RS_INLINE void TripPack(const typename K::Params& params, const BatchJob& job,
                        const LaneTextures& tex, PackRun<K, L>& p, OnFetch&& onFetch) {
    using F = typename L::F;
    using M = typename L::M;
    Sample<L> sampled;
    if constexpr (KernelReadsAllLayers<K>) {
        // One fetch of every stacked cone at the point: the layers' (depth, value)
        // pairs, each a footprint (the twin's texture calls on the layer array), with
        // the wrap, weights and depth computed once.
        constexpr int kLayers = KernelConeLayers<K>();
        static_assert(kLayers <= kMaxStackedCones);
        using I = typename L::I;
        sampled.h = SampleHeightConeStackLanes<L, kLayers>(
            tex, p.fetch.u, p.fetch.v, I(0), p.active, p.texels, sampled.stack.data());
        sampled.ratio = sampled.stack[0];
    } else if constexpr (KernelReadsPyramid<K>) {
        SamplePyramidLanes<L>(tex, p.fetch.level, p.fetch.cx, p.fetch.cy, p.active,
                              p.texels, sampled.h, sampled.corners);
        // Level -2: a height fetch at (u, v) with the height sampler (qdm's bracket and
        // refinement).
        const M height =
            p.active && (stdx::static_simd_cast<F>(p.fetch.level) == F(-2.0f));
        if (Any(height))
            Assign(height, sampled.h,
                   SampleHeightLanes<L>(tex, p.fetch.u, p.fetch.v, height, p.texels));
    } else if constexpr (KernelReadsRatio<K>)
        sampled.h = SampleHeightConeLanes<L>(tex, p.fetch.u, p.fetch.v, p.fetch.layer,
                                             p.active, p.texels, sampled.ratio);
    else
        sampled.h = SampleHeightLanes<L>(tex, p.fetch.u, p.fetch.v, p.active, p.texels);
    Assign(p.active, p.fetches, p.fetches + F(1.0f));
    onFetch(p.active, p.fetch, sampled.h);
    M want = K::template Step<L>(params, p.ray, p.state, sampled, p.active, p.fetch);
    if (job.budget != 0) {
        const M refused = want && (p.fetches >= F(float(job.budget)));
        p.exhausted = p.exhausted || refused;
        want = want && !refused;
    }
    p.active = want;
}

/// Lights and shades a finished pack (`answered`: the lanes with an answer to light)
/// and writes its results into the batch. Independent of the kernel and run once per
/// pack, so out of line: inlined into every kernel's pack loop, its dozen fetches (light
/// rays, shading) and per-lane stores made each lane unit's build several times longer
/// (GCC's points-to analysis and inliner grow faster than the function they work on).
template <class L>
RS_NOINLINE void StorePack(const BatchJob& job, const LaneTextures& tex, LaneBatch& b,
                           int base, const LaneOutcome<L>& out,
                           const typename L::M& answered, const typename L::M& valid,
                           const typename L::M& exhausted, const typename L::F& fetches,
                           const typename L::F& texels) {
    using F = typename L::F;
    F rgb[3] = {F(0.0f), F(0.0f), F(0.0f)};
    F shadowFetches(0.0f);
    const F vis = LightVisibility<L>(tex, job.shadow, out.u, out.v, answered && valid,
                                     shadowFetches);
    const F ao = AmbientOcclusion<L>(tex, job.shadow, out.u, out.v, answered && valid,
                                     shadowFetches);
    if (b.rgb)
        ShadeHit<L>(tex, job.slopeScale, job.light, out.u, out.v, out.depth, answered,
                    valid, vis, ao, rgb);
    for (int k = 0; k < L::kWidth; ++k) {
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
        if (b.rgb)
            for (int c = 0; c < 3; ++c) b.rgb[3 * i + c] = rgb[c][k];
        if (b.shadowFetches) b.shadowFetches[i] = uint32_t(shadowFetches[k]);
        if (b.visibility) b.visibility[i] = vis[k];
        if (b.ambient) b.ambient[i] = ao[k];
    }
}

/// Writes a finished pack's results (and its shading, when asked) into the batch.
template <class K, class L>
RS_INLINE void EndPack(const typename K::Params& params, const BatchJob& job,
                       const LaneTextures& tex, LaneBatch& b, const PackRun<K, L>& p) {
    LaneOutcome<L> out;
    K::template End<L>(params, p.ray, p.state, out);
    // The lanes with an answer to shade and light: those that hit, and for a kernel
    // that answers where it stopped (the cone family), every lane.
    const typename L::M answered = KernelAnswersAtStop<K> ? typename L::M(true) : out.hit;
    StorePack<L>(job, tex, b, p.base, out, answered, p.valid, p.exhausted, p.fetches,
                 p.texels);
}

/// Runs every pack of the batch, kPacks in flight: their trips alternate, so the fetch
/// latency of one pack overlaps the work of the others (each pack's lanes are independent
/// of the others', so results do not depend on kPacks). A finished slot takes the next
/// pack.
/// onFetch(active, fetch, sampled) sees every fetch of every pack.
template <class K, class L, int kPacks, class OnFetch>
void MarchPacks(const typename K::Params& params, const BatchJob& job, LaneBatch& b,
                OnFetch&& onFetch) {
    const LaneTextures tex = BindLanes(job.textures);
    PackRun<K, L> run[kPacks];
    bool busy[kPacks] = {};
    int next = 0, nBusy = 0;
    for (int j = 0; j < kPacks && next < b.n; ++j, next += L::kWidth) {
        BeginPack<K, L>(params, job, b, next, run[j]);
        busy[j] = true;
        ++nBusy;
    }
    while (nBusy > 0) {
        for (int j = 0; j < kPacks; ++j) {
            if (!busy[j]) continue;
            TripPack<K, L>(params, job, tex, run[j], onFetch);
            if (Any(run[j].active)) continue;
            EndPack<K, L>(params, job, tex, b, run[j]);
            if (next < b.n) {
                BeginPack<K, L>(params, job, b, next, run[j]);
                next += L::kWidth;
            } else {
                busy[j] = false;
                --nBusy;
            }
        }
    }
}

/// Packs a lane width keeps in flight (measured: bench/kernels_bench BM_Kernel).
inline constexpr int kPacksInFlight = RS_PACKS_IN_FLIGHT;

/// A lane width's kernels are compiled in kBatchParts units (the part of kernel index i
/// is i % kBatchParts), so that the per-ISA units build in parallel and a change to one
/// kernel rebuilds only its part.
inline constexpr int kBatchParts = 4;

template <class K, class... Ks>
constexpr int KernelIndexIn(KernelList<Ks...>) {
    int i = 0, found = -1;
    ((std::is_same_v<K, Ks> ? (found = i, ++i) : ++i), ...);
    return found;
}
/// K's index in KernelTypes.
template <class K>
inline constexpr int kKernelIndex = KernelIndexIn<K>(KernelTypes{});

/// The batch entry point of one part of a lane width: every pack of the batch, for the
/// job's kernel, which must belong to part kPart.
template <class L, int kPart>
void RunBatchPart(const BatchJob& job, LaneBatch& b) {
    VisitKernelType(job.kernelIndex, [&](auto type) {
        using K = typename decltype(type)::type;
        if constexpr (kKernelIndex<K> % kBatchParts == kPart) {
            const auto& params = *static_cast<const typename K::Params*>(job.params);
            MarchPacks<K, L, kPacksInFlight>(
                params, job, b, [](const auto&, const auto&, const auto&) {});
        } else {
            RS_CHECK(false);  // dispatched to the wrong part
        }
    });
}

/// kPacks packs' dependent chains from u0, v0 interleaved (kPacks a constant, so the
/// packs' registers need no array in memory); adds to sum and texels.
template <class L, bool kCount, int kPacks>
RS_INLINE void ChainPacks(const LaneTextures& tex, const float* u0, const float* v0,
                          int chain, typename L::F& sum, double& texels) {
    using F = typename L::F;
    constexpr int N = L::kWidth;
    const typename L::M all(true);
    F u[kPacks], v[kPacks], reads[kPacks];
    for (int j = 0; j < kPacks; ++j) {
        u[j].copy_from(u0 + j * N, stdx::element_aligned);
        v[j].copy_from(v0 + j * N, stdx::element_aligned);
        reads[j] = F(0.0f);
    }
    for (int k = 0; k < chain; ++k) {
        for (int j = 0; j < kPacks; ++j) {
            const F h = SampleHeightLanes<L, kCount>(tex, u[j], v[j], all, reads[j]);
            u[j] = u[j] + h * F(0.01f) + F(0.0031f);
            v[j] = v[j] + F(0.0017f);
            sum = sum + h;
        }
    }
    for (int j = 0; j < kPacks; ++j) texels += double(stdx::reduce(reads[j]));
}

/// SampleChainFn of one lane width: kPacksInFlight packs' chains interleaved, as the
/// driver runs packs; kCount = false is the uncounted baseline.
template <class L, bool kCount>
float SampleChainCounted(const Textures& textures, const float* u0, const float* v0,
                         int n, int chain, uint64_t* texelReads) {
    using F = typename L::F;
    const LaneTextures tex = BindLanes(textures);
    constexpr int N = L::kWidth, P = kPacksInFlight;
    F sum(0.0f);
    double texels = 0.0;
    for (int base = 0; base + N <= n; base += N * P) {
        const float *u = u0 + base, *v = v0 + base;
        if ((n - base) / N >= P)
            ChainPacks<L, kCount, P>(tex, u, v, chain, sum, texels);
        else
            for (int j = 0; j < (n - base) / N; ++j)
                ChainPacks<L, kCount, 1>(tex, u + j * N, v + j * N, chain, sum, texels);
    }
    if constexpr (kCount) *texelReads += uint64_t(texels);
    return stdx::reduce(sum);
}

template <class L>
float SampleChain(const Textures& tex, const float* u0, const float* v0, int n, int chain,
                  uint64_t* texelReads) {
    return texelReads ? SampleChainCounted<L, true>(tex, u0, v0, n, chain, texelReads)
                      : SampleChainCounted<L, false>(tex, u0, v0, n, chain, nullptr);
}

/// SampleLanesFn of one lane width.
template <class L>
void SampleLanes(const Textures& textures, const float* u0, const float* v0, int n,
                 float* out, uint32_t* texels) {
    using F = typename L::F;
    const LaneTextures tex = BindLanes(textures);
    constexpr int N = L::kWidth;
    for (int base = 0; base < n; base += N) {
        F u(0.0f), v(0.0f), reads(0.0f);
        typename L::M active(false);
        for (int k = 0; k < N; ++k) {
            const int i = std::min(base + k, n - 1);
            u[k] = u0[i], v[k] = v0[i];
            active[k] = base + k < n;
        }
        const F h = SampleHeightLanes<L>(tex, u, v, active, reads);
        for (int k = 0; k < N && base + k < n; ++k) {
            out[base + k] = h[k];
            texels[base + k] = uint32_t(reads[k]);
        }
    }
}

}  // namespace reliefsim::detail

/// The entry points of one lane-width unit (render/batch_w*.cpp), declared by batch.cpp
/// and defined by the unit, with its own ISA tag type so its instantiations are its own.
#define RS_DECLARE_LANE_WIDTH(suffix)                                                   \
    namespace reliefsim {                                                               \
    void RunBatch##suffix(const BatchJob& job, LaneBatch& batch);                       \
    float SampleChain##suffix(const Textures& textures, const float* u, const float* v, \
                              int n, int chain, uint64_t* texelReads);                  \
    void SampleLanes##suffix(const Textures& textures, const float* u, const float* v,  \
                             int n, float* out, uint32_t* texels);                      \
    }
#define RS_DEFINE_LANE_WIDTH(suffix, width)                                             \
    RS_DECLARE_LANE_WIDTH(suffix)                                                       \
    namespace reliefsim {                                                               \
    namespace {                                                                         \
    struct Isa##suffix {};                                                              \
    }                                                                                   \
    void RunBatch##suffix##Part0(const BatchJob& job, LaneBatch& batch);                \
    void RunBatch##suffix##Part1(const BatchJob& job, LaneBatch& batch);                \
    void RunBatch##suffix##Part2(const BatchJob& job, LaneBatch& batch);                \
    void RunBatch##suffix##Part3(const BatchJob& job, LaneBatch& batch);                \
    void RunBatch##suffix(const BatchJob& job, LaneBatch& batch) {                      \
        static_assert(detail::kBatchParts == 4);                                        \
        static constexpr BatchFn kParts[] = {                                           \
            &RunBatch##suffix##Part0, &RunBatch##suffix##Part1,                         \
            &RunBatch##suffix##Part2, &RunBatch##suffix##Part3};                        \
        kParts[job.kernelIndex % detail::kBatchParts](job, batch);                      \
    }                                                                                   \
    float SampleChain##suffix(const Textures& textures, const float* u, const float* v, \
                              int n, int chain, uint64_t* texelReads) {                 \
        return detail::SampleChain<Lanes<width, Isa##suffix>>(textures, u, v, n, chain, \
                                                              texelReads);              \
    }                                                                                   \
    void SampleLanes##suffix(const Textures& textures, const float* u, const float* v,  \
                             int n, float* out, uint32_t* texels) {                     \
        detail::SampleLanes<Lanes<width, Isa##suffix>>(textures, u, v, n, out, texels); \
    }                                                                                   \
    }

/// One part of a lane width's kernels (render/CMakeLists.txt generates a unit per part,
/// compiled with the width's flags).
#define RS_DEFINE_LANE_WIDTH_PART(suffix, width, part)                           \
    namespace reliefsim {                                                        \
    namespace {                                                                  \
    struct Isa##suffix##part {};                                                 \
    }                                                                            \
    void RunBatch##suffix##Part##part(const BatchJob& job, LaneBatch& batch) {   \
        detail::RunBatchPart<Lanes<width, Isa##suffix##part>, part>(job, batch); \
    }                                                                            \
    }
