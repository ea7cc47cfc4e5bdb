// Microbenchmarks of the kernels with counting and uncounted samplers.
#include <benchmark/benchmark.h>

#include "kernels/linear_search.h"
#include "texture/procedural.h"
#include "texture/sampler.h"

using namespace reliefsim;

namespace {

const HeightField& Field() {
    static HeightField f = MakeBuiltinMap("shapes", 512, 512);
    return f;
}

template <bool kCount>
void BM_MarchRelief(benchmark::State& state) {
    LinearSearchKernel k;
    k.params.linearSteps = int(state.range(0));
    k.params.refineSteps = 6;
    FetchCounts counts;
    uint64_t fetches = 0, rays = 0;
    for (auto _ : state) {
        for (int i = 0; i < 256; ++i) {
            Sampler<kCount> s(Field(), {}, &counts);
            MarchInput in{{float(i) / 256.0f, 0.37f}, {0.3f, 0.1f}};
            benchmark::DoNotOptimize(k.March(in, s));
            ++rays;
        }
    }
    fetches = counts.nFetches;
    state.SetItemsProcessed(int64_t(rays));
    if (kCount) state.counters["fetches/ray"] = double(fetches) / double(rays);
}
BENCHMARK_TEMPLATE(BM_MarchRelief, true)->Arg(16)->Arg(32)->Arg(64);
BENCHMARK_TEMPLATE(BM_MarchRelief, false)->Arg(16)->Arg(32)->Arg(64);

void BM_SampleBilinear(benchmark::State& state) {
    Sampler<false> s(Field(), {});
    float u = 0.1f;
    for (auto _ : state) {
        u += 0.0013f;
        benchmark::DoNotOptimize(s.Sample({u, 0.3f}));
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SampleBilinear);

}  // namespace

BENCHMARK_MAIN();
