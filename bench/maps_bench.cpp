// Derived-map generation benchmarks (issue #3 targets): conservative 8-bit 1024², relaxed
// 512², plain vs adaptive ACM on the built-in maps, dynamic sinusoid map + adaptive ACM
// per frame.
#include <benchmark/benchmark.h>

#include <string>

#include "maps/cone_map.h"
#include "texture/procedural.h"

namespace reliefsim {
namespace {

const char* kMaps[] = {"shapes", "bumps", "steps", "noise"};

void BM_ConeMapConservative8Bit(benchmark::State& state) {
    const int n = int(state.range(0));
    const DepthField hf = QuantizeToUnorm8(MakeBuiltinMap("shapes", n, n));
    for (auto _ : state) benchmark::DoNotOptimize(GenerateConeMap(hf, ConeKind::Cone));
    state.SetItemsProcessed(state.iterations() * int64_t(n) * n);
}
BENCHMARK(BM_ConeMapConservative8Bit)
    ->Arg(256)
    ->Arg(1024)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_ConeMapRelaxed(benchmark::State& state) {
    const int n = int(state.range(0));
    const DepthField hf = QuantizeToUnorm8(MakeBuiltinMap("shapes", n, n));
    for (auto _ : state) benchmark::DoNotOptimize(GenerateConeMap(hf, ConeKind::Relaxed));
    state.SetItemsProcessed(state.iterations() * int64_t(n) * n);
}
BENCHMARK(BM_ConeMapRelaxed)
    ->Arg(128)
    ->Arg(256)
    ->Arg(512)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

void BM_ConeMapOtherKinds512(benchmark::State& state) {
    // The kinds without an issue target, 8-bit `shapes` 512² (docs/cone_maps.md,
    // Performance).
    static constexpr ConeKind kKinds[] = {ConeKind::Acm8, ConeKind::RelaxedExact,
                                          ConeKind::Stacked, ConeKind::Quad};
    const ConeKind kind = kKinds[state.range(0)];
    const DepthField hf = QuantizeToUnorm8(MakeBuiltinMap("shapes", 512, 512));
    for (auto _ : state) benchmark::DoNotOptimize(GenerateConeMap(hf, kind));
    state.SetLabel(std::string(ToString(kind)));
}
BENCHMARK(BM_ConeMapOtherKinds512)
    ->DenseRange(0, 3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

void BM_Acm4PlainSearch(benchmark::State& state) {
    const DepthField hf =
        QuantizeToUnorm8(MakeBuiltinMap(kMaps[state.range(0)], 256, 256));
    for (auto _ : state)
        benchmark::DoNotOptimize(GenerateSectorMapPlainSearch(hf, ConeKind::Acm4));
    state.SetLabel(kMaps[state.range(0)]);
}
BENCHMARK(BM_Acm4PlainSearch)
    ->DenseRange(0, 3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Acm4Adaptive(benchmark::State& state) {
    const DepthField hf =
        QuantizeToUnorm8(MakeBuiltinMap(kMaps[state.range(0)], 256, 256));
    for (auto _ : state)
        benchmark::DoNotOptimize(GenerateAdaptiveSectorMap(hf, ConeKind::Acm4, 0.25f, 3));
    state.SetLabel(kMaps[state.range(0)]);
}
BENCHMARK(BM_Acm4Adaptive)
    ->DenseRange(0, 3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_DynamicSinusoidAdaptiveAcm4(benchmark::State& state) {
    // As `reliefsim maps --animate`: buffers kept across frames, map refilled in place.
    int frame = 0;
    AdaptiveWorkspace ws;
    DepthField hf;
    ConeMap m;
    for (auto _ : state) {
        FillSinusoidMap(hf, 256, 256, float(frame++) / 30.0f);
        GenerateAdaptiveSectorMap(hf, ConeKind::Acm4, 0.25f, int(state.range(0)), ws, m);
        benchmark::DoNotOptimize(m.values.data());
    }
}
BENCHMARK(BM_DynamicSinusoidAdaptiveAcm4)
    ->Arg(3)
    ->Arg(4)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace reliefsim

BENCHMARK_MAIN();
