// Derived-map generation (docs/cone_maps.md, Performance): every kind at 1024² on the
// DirectX SDK rocks resized to 8 and 16 bits, the float built-ins and stones at 2048²
// (16-bit), and the bilinear-bound maps (maps/cone_map_bilinear.h) on the same; the
// growth with size (256² to 2048²) and its fitted exponent; the ACM paper's dynamic map
// (regenerate + adaptive ACM4 per frame); plain against adaptive ACM. Maps from
// ../shared/data are made at run time and skipped when it is absent.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "bench/bench_maps.h"
#include "maps/cone_map.h"
#include "maps/cone_map_bilinear.h"
#include "maps/cone_map_detail.h"
#include "maps/cone_search.h"
#include "texture/procedural.h"

namespace reliefsim {
namespace {

using bench::Quantize;
using bench::SharedMap;
using bench::Upsample;

struct NamedKind {
    const char* name;
    ConeKind kind;
};
constexpr NamedKind kKinds[] = {{"cone", ConeKind::Cone},
                                {"relaxed", ConeKind::Relaxed},
                                {"relaxed-exact", ConeKind::RelaxedExact},
                                {"quad", ConeKind::Quad},
                                {"acm4", ConeKind::Acm4},
                                {"acm8", ConeKind::Acm8},
                                {"cone-normal", ConeKind::ConeNormal},
                                {"stacked", ConeKind::Stacked}};

void GenerateOnce(benchmark::State& state, std::shared_ptr<const DepthField> field,
                  ConeKind kind) {
    for (auto _ : state) benchmark::DoNotOptimize(GenerateConeMap(*field, kind));
    state.SetItemsProcessed(state.iterations() * int64_t(field->width) *
                            int64_t(field->height));
}

void GenerateBilinearOnce(benchmark::State& state,
                          std::shared_ptr<const DepthField> field, ConeKind kind) {
    for (auto _ : state) benchmark::DoNotOptimize(GenerateBilinearConeMap(*field, kind));
    state.SetItemsProcessed(state.iterations() * int64_t(field->width) *
                            int64_t(field->height));
}

/// The relaxed map with the lane search's unit forced to `isa` for the run: "sse4.1",
/// the scalar search; "avx2", the scalar search with the AVX2 exit field, as a CPU
/// without AVX-512 runs it (the default picks the AVX-512 search where the CPU has it:
/// docs/cone_maps.md, "With AVX-512"). The same map.
void GenerateRelaxedIsa(benchmark::State& state, std::shared_ptr<const DepthField> field,
                        const char* isa) {
    const char* old = std::getenv("RS_CONE_SEARCH_ISA");
    const std::string saved = old ? old : "";
    setenv("RS_CONE_SEARCH_ISA", isa, 1);
    if (std::string_view(detail::ConeSearchIsa()) != isa)
        state.SkipWithError("the CPU lacks this unit");
    else
        GenerateOnce(state, field, ConeKind::Relaxed);
    if (old)
        setenv("RS_CONE_SEARCH_ISA", saved.c_str(), 1);
    else
        unsetenv("RS_CONE_SEARCH_ISA");
}

/// The relaxed map's exit field alone (docs/cone_maps.md, "Exit bound"), 128 steps, by
/// the search's own build (AVX-512 or AVX2 as ConeSearchIsa() says).
void BuildExitFieldOnce(benchmark::State& state,
                        std::shared_ptr<const DepthField> field) {
    for (auto _ : state)
        benchmark::DoNotOptimize(detail::RelaxedExitField(*field, 128, true));
    state.SetItemsProcessed(state.iterations() * int64_t(field->width) *
                            int64_t(field->height));
}

/// One benchmark per map and kind, named BM_ConeMap/<map>/<kind>, and per kind with a
/// bilinear-bound variant BM_ConeMapBilinear/<map>/<kind> (`--cone-bounds bilinear`);
/// BM_RelaxedScalar/<map>: the relaxed map by the scalar search (the reporter prints
/// its ratio to BM_ConeMap/<map>/relaxed when both ran); BM_RelaxedAvx2/<map>: as a CPU
/// without AVX-512 makes it (skipped without AVX2); BM_RelaxedExitField/<map>: its exit
/// field alone. Each generation is one iteration (they take seconds).
void RegisterMap(const std::string& name, std::shared_ptr<const DepthField> field,
                 bool conservativeOnly = false) {
    if (!conservativeOnly) {
        benchmark::RegisterBenchmark(("BM_RelaxedScalar/" + name).c_str(),
                                     GenerateRelaxedIsa, field, "sse4.1")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->Iterations(1);
        benchmark::RegisterBenchmark(("BM_RelaxedAvx2/" + name).c_str(),
                                     GenerateRelaxedIsa, field, "avx2")
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->Iterations(1);
        benchmark::RegisterBenchmark(("BM_RelaxedExitField/" + name).c_str(),
                                     BuildExitFieldOnce, field)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->Iterations(1);
    }
    for (const NamedKind& k : kKinds) {
        if (conservativeOnly && k.kind != ConeKind::Cone) continue;
        benchmark::RegisterBenchmark(("BM_ConeMap/" + name + "/" + k.name).c_str(),
                                     GenerateOnce, field, k.kind)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->Iterations(1);
    }
    for (const NamedKind& k : kKinds) {
        if (!HasBilinearBounds(k.kind) || (conservativeOnly && k.kind != ConeKind::Cone))
            continue;
        benchmark::RegisterBenchmark(
            ("BM_ConeMapBilinear/" + name + "/" + k.name).c_str(), GenerateBilinearOnce,
            field, k.kind)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime()
            ->Iterations(1);
    }
}

/// The growth with size: rocks (or, without ../shared, noise) at n² float, n = 256 ..
/// 2048; names BM_ConeMapScaling/<kind>/<n>. The reporter fits the exponent.
void RegisterScaling(const DepthField& base) {
    std::map<int, std::shared_ptr<const DepthField>> fields;
    for (int n : {256, 512, 1024, 2048})
        fields[n] = std::make_shared<const DepthField>(Upsample(base, n));
    for (ConeKind k : {ConeKind::Cone, ConeKind::Acm4, ConeKind::Relaxed})
        for (const auto& [n, field] : fields) {
            benchmark::RegisterBenchmark(
                ("BM_ConeMapScaling/" + std::string(ToString(k)) + "/" +
                 std::to_string(n))
                    .c_str(),
                GenerateOnce, field, k)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime()
                ->Iterations(1);
        }
}

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

const char* kBuiltins[] = {"shapes", "bumps", "steps", "noise"};

void BM_Acm4PlainSearch(benchmark::State& state) {
    const DepthField hf =
        QuantizeToUnorm8(MakeBuiltinMap(kBuiltins[state.range(0)], 256, 256));
    for (auto _ : state)
        benchmark::DoNotOptimize(GenerateSectorMapPlainSearch(hf, ConeKind::Acm4));
    state.SetLabel(kBuiltins[state.range(0)]);
}
BENCHMARK(BM_Acm4PlainSearch)
    ->DenseRange(0, 3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Acm4Adaptive(benchmark::State& state) {
    const DepthField hf =
        QuantizeToUnorm8(MakeBuiltinMap(kBuiltins[state.range(0)], 256, 256));
    for (auto _ : state)
        benchmark::DoNotOptimize(GenerateAdaptiveSectorMap(hf, ConeKind::Acm4, 0.25f, 3));
    state.SetLabel(kBuiltins[state.range(0)]);
}
BENCHMARK(BM_Acm4Adaptive)
    ->DenseRange(0, 3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// Prints, after the runs, the exponent of the time's growth with the side n of each
/// kind's scaling family (least squares of log time on log n; N² log N gives about 2.1
/// to 2.2 over 256..2048), and per map the relaxed search's time over the scalar
/// search's (BM_ConeMap/<map>/relaxed over BM_RelaxedScalar/<map>).
class ScalingReporter : public benchmark::ConsoleReporter {
  public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs) {
            const std::string name = r.benchmark_name();
            if (r.error_occurred) continue;
            const std::string scalar = "BM_RelaxedScalar/", cone = "BM_ConeMap/";
            const std::string relaxed = "/relaxed/";
            if (name.rfind(scalar, 0) == 0) {
                const std::string map = name.substr(
                    scalar.size(), name.find('/', scalar.size()) - scalar.size());
                relaxed_[map].second = r.GetAdjustedRealTime();
            } else if (name.rfind(cone, 0) == 0 &&
                       name.find(relaxed) != std::string::npos) {
                const std::string map =
                    name.substr(cone.size(), name.find('/', cone.size()) - cone.size());
                relaxed_[map].first = r.GetAdjustedRealTime();
            }
            const std::string prefix = "BM_ConeMapScaling/";
            if (name.rfind(prefix, 0) != 0 || r.error_occurred) continue;
            const size_t slash = name.find('/', prefix.size());
            const std::string kind = name.substr(prefix.size(), slash - prefix.size());
            const int n = std::stoi(name.substr(slash + 1));
            points_[kind].push_back(
                {std::log(double(n)), std::log(r.GetAdjustedRealTime())});
        }
    }
    void Finalize() override {
        ConsoleReporter::Finalize();
        for (const auto& [kind, p] : points_) {
            if (p.size() < 2) continue;
            double sx = 0, sy = 0, sxx = 0, sxy = 0;
            for (const auto& [x, y] : p) {
                sx += x;
                sy += y;
                sxx += x * x;
                sxy += x * y;
            }
            const double k = double(p.size());
            const double slope = (k * sxy - sx * sy) / (k * sxx - sx * sx);
            std::printf("fitted exponent of %s (time ~ n^e over %zu sizes): e = %.2f\n",
                        kind.c_str(), p.size(), slope);
        }
        for (const auto& [map, t] : relaxed_)
            if (t.first > 0 && t.second > 0)
                std::printf(
                    "relaxed on %s: %.2fx the scalar search's time (%.0f / %.0f ms)\n",
                    map.c_str(), t.first / t.second, t.first, t.second);
    }

  private:
    std::map<std::string, std::vector<std::pair<double, double>>> points_;
    std::map<std::string, std::pair<double, double>> relaxed_;  ///< default, scalar
};

}  // namespace
}  // namespace reliefsim

int main(int argc, char** argv) {
    using namespace reliefsim;
    benchmark::Initialize(&argc, argv);
    if (const auto rocks = bench::SharedMap("rocks")) {
        const DepthField big = Upsample(*rocks, 1024);
        RegisterMap("rocks1024_8bit",
                    std::make_shared<const DepthField>(Quantize(big, 8)));
        RegisterMap("rocks1024_16bit",
                    std::make_shared<const DepthField>(Quantize(big, 16)));
        RegisterScaling(*rocks);
    } else {
        std::fprintf(stderr,
                     "maps_bench: %s absent; the rocks and stones maps are skipped\n",
                     RS_SHARED_DATA);
        RegisterScaling(MakeBuiltinMap("noise", 256, 256));
    }
    RegisterMap("shapes1024_float",
                std::make_shared<const DepthField>(MakeBuiltinMap("shapes", 1024, 1024)));
    RegisterMap("noise1024_float",
                std::make_shared<const DepthField>(MakeBuiltinMap("noise", 1024, 1024)));
    if (const auto stones = bench::SharedMap("stones"))
        RegisterMap(
            "stones2048_16bit",
            std::make_shared<const DepthField>(Quantize(Upsample(*stones, 2048), 16)),
            true);
    reliefsim::ScalingReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    return 0;
}
