// Microbenchmarks of the fragment driver and its sampler, at every lane width this CPU
// runs (docs/benchmarks.md).
//   BM_Kernel/<method>/<lanes>    rays through one kernel (fetches counted), items =
//   rays;
//                                 counted fetches/s = items/s x fetches/ray
//   BM_SampleChain/<lanes>        dependent counted bilinear fetches, items = fetches
//   BM_SampleChainRawAvx2/<packs>  the same chain as a plain AVX2 intrinsics loop,
//   uncounted
//                                 (bench/raw_chain_avx2.cpp): the reference point
//   BM_SampleScalar<counted>      the scalar Sampler, counted and uncounted
//   BM_AnimateFrame/<threads>     `render --animate`'s frame: the 256² sinusoid map
//                                 regenerated, adaptive ACM4, acm4 rendered at 512²
//                                 (frames/s counter; the ACM paper's 50 frames/s)
#include <benchmark/benchmark.h>

#include "bench/raw_chain.h"
#include "core/memory.h"
#include "maps/cone_map.h"
#include "render/batch.h"
#include "render/frame.h"
#include "render/kernel_maps.h"
#include "texture/procedural.h"
#include "texture/sampler.h"

using namespace reliefsim;

namespace {

const DepthField& Field() {
    static DepthField f = MakeBuiltinMap("noise", 512, 512);
    return f;
}

constexpr int kRays = 4096;

struct Rays {
    std::vector<float> uE, vE, du, dv, u, v, depth;
    std::vector<uint16_t> nc, nr;
    std::vector<uint32_t> fetches, texels;
    std::vector<uint8_t> flags;
    Rays() {
        for (int i = 0; i < kRays; ++i) {
            uE.push_back(float(i % 64) / 64.0f);
            vE.push_back(float(i / 64) / 64.0f);
            du.push_back(0.3f + 0.1f * float(i % 7) / 7.0f);
            dv.push_back(-0.12f);
        }
        u.resize(kRays), v.resize(kRays), depth.resize(kRays), nc.resize(kRays);
        nr.resize(kRays), fetches.resize(kRays), texels.resize(kRays),
            flags.resize(kRays);
    }
    LaneBatch Batch() {
        LaneBatch b;
        b.n = kRays;
        b.uEntry = uE.data(), b.vEntry = vE.data(), b.du = du.data(), b.dv = dv.data();
        b.u = u.data(), b.v = v.data(), b.depth = depth.data(), b.nCoarse = nc.data();
        b.nRefine = nr.data(), b.fetches = fetches.data(), b.texelReads = texels.data();
        b.flags = flags.data();
        return b;
    }
};

void BM_Kernel(benchmark::State& state, const KernelInfo* info, LaneWidthInfo width) {
    if (!width.supported) {
        state.SkipWithError("this CPU lacks the ISA");
        return;
    }
    std::shared_ptr<const void> params;
    const Kernel kernel = MakeKernel(*info, ResolveParams(*info, {}));
    KernelMapSettings maps;  // cone kernels: their map, made once (not timed)
    maps.useCache = false;
    const BatchJob job =
        MakeBatchJob(kernel, BindKernelTextures(Field(), {}, kernel, maps), params);
    Rays rays;
    LaneBatch b = rays.Batch();
    uint64_t fetches = 0;
    for (auto _ : state) {
        width.fn(job, b);
        benchmark::ClobberMemory();
        for (uint32_t f : rays.fetches) fetches += f;
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * kRays);
    state.counters["fetches/ray"] =
        double(fetches) / (double(state.iterations()) * kRays);
}

void BM_SampleChain(benchmark::State& state, LaneWidthInfo width, bool count) {
    if (!width.supported) {
        state.SkipWithError("this CPU lacks the ISA");
        return;
    }
    constexpr int kLanes = 64, kChain = 256;
    std::vector<float> u(kLanes), v(kLanes);
    for (int i = 0; i < kLanes; ++i)
        u[size_t(i)] = float(i) / kLanes, v[size_t(i)] = 0.3f;
    const Textures tex = BindTextures(Field(), {});
    uint64_t texels = 0;
    for (auto _ : state)
        benchmark::DoNotOptimize(width.sampleChain(tex, u.data(), v.data(), kLanes,
                                                   kChain, count ? &texels : nullptr));
    state.SetItemsProcessed(int64_t(state.iterations()) * kLanes * kChain);
    if (count)
        state.counters["texel_reads/fetch"] =
            double(texels) / (double(state.iterations()) * kLanes * kChain);
}

void BM_SampleChainRawAvx2(benchmark::State& state, int packs) {
    if (!bench::RawChainAvx2Available() || !__builtin_cpu_supports("avx2") ||
        !__builtin_cpu_supports("fma")) {
        state.SkipWithError("no AVX2 loop in this build or CPU");
        return;
    }
    constexpr int kLanes = 64, kChain = 256;
    std::vector<float> u(kLanes), v(kLanes);
    for (int i = 0; i < kLanes; ++i)
        u[size_t(i)] = float(i) / kLanes, v[size_t(i)] = 0.3f;
    const Textures tex = BindTextures(Field(), {});
    for (auto _ : state)
        benchmark::DoNotOptimize(
            bench::RawChainAvx2(*tex.padded, u.data(), v.data(), kLanes, kChain, packs));
    state.SetItemsProcessed(int64_t(state.iterations()) * kLanes * kChain);
}
BENCHMARK_CAPTURE(BM_SampleChainRawAvx2, 1, 1);
BENCHMARK_CAPTURE(BM_SampleChainRawAvx2, 2, 2);
BENCHMARK_CAPTURE(BM_SampleChainRawAvx2, 4, 4);

template <bool kCount>
void BM_SampleScalar(benchmark::State& state) {
    FetchCounts counts;
    Sampler<kCount> s(Field(), {}, &counts);
    float u = 0.1f;
    for (auto _ : state) {
        u += 0.0013f + s.Sample({u, 0.3f}) * 1e-6f;  // dependent, as in a kernel
        benchmark::DoNotOptimize(u);
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK_TEMPLATE(BM_SampleScalar, true);
BENCHMARK_TEMPLATE(BM_SampleScalar, false);

void BM_AnimateFrame(benchmark::State& state) {
    KeepFreedMemoryInHeap();  // as `render --animate` does
    RenderSettings s;
    s.method = "acm4";
    s.width = s.height = 512;
    s.reference = false;
    s.threads = int(state.range(0));
    s.maps.generator = AdaptiveMapGenerator(0.25f, 3);
    DepthField field;
    int frame = 0;
    for (auto _ : state) {
        FillSinusoidMap(field, 256, 256, float(frame++) / 30.0f);
        const RenderOutput out = Render(field, s);
        benchmark::DoNotOptimize(out.record.nFetches.data());
    }
    state.counters["frames/s"] =
        benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_AnimateFrame)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

const int kRegistered = [] {
    benchmark::AddCustomContext("footprints (RS_FOOTPRINT)",
                                GatherFootprints() ? "gather" : "loads");
    for (const LaneWidthInfo& w : LaneWidths()) {
        benchmark::RegisterBenchmark(
            ("BM_SampleChain/" + std::to_string(w.width)).c_str(), BM_SampleChain, w,
            true);
        benchmark::RegisterBenchmark(
            ("BM_SampleChainUncounted/" + std::to_string(w.width)).c_str(),
            BM_SampleChain, w, false);
        for (const KernelInfo* m : Methods())
            benchmark::RegisterBenchmark(
                ("BM_Kernel/" + std::string(m->name) + "/" + std::to_string(w.width))
                    .c_str(),
                BM_Kernel, m, w);
    }
    return 0;
}();

}  // namespace

BENCHMARK_MAIN();
