// The exact reference's frame (method `exact`, metrics/exact.h): a 512x512 render per
// iteration, timed over the frame loop (RenderOutput::frameSeconds), on the built-in
// maps, the DirectX SDK's rocks and stones (8-bit, from ../shared/data; skipped when
// absent), and stones upsampled to a 1024^2 float map; at 45 degrees, at a grazing 80
// degrees and tiled 3x with clamp (no pyramid). The goal is <= 1 s per frame
// (docs/exact.md).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "bench/bench_maps.h"
#include "render/frame.h"
#include "texture/image_io.h"
#include "texture/procedural.h"

using namespace reliefsim;
using reliefsim::bench::Upsample;

namespace {

struct View {
    const char* name;
    float angle, depthScale, tiling;
    WrapMode wrap;
};
constexpr View kViews[] = {{"45deg", 45.0f, 0.1f, 1.0f, WrapMode::Repeat},
                           {"grazing80", 80.0f, 0.1f, 1.0f, WrapMode::Repeat},
                           {"clamp_tiled3", 60.0f, 0.1f, 3.0f, WrapMode::Clamp}};

void ExactFrame(benchmark::State& state, DepthField field, View view) {
    RenderSettings s;
    s.method = "exact";
    s.width = s.height = 512;
    s.viewAngle = view.angle;
    s.depthScale = view.depthScale;
    s.tiling = view.tiling;
    s.sampler.wrap = view.wrap;
    s.threads = int(state.range(0));
    double cells = 0, pixels = 0;
    for (auto _ : state) {
        const RenderOutput out = Render(field, s);
        state.SetIterationTime(out.frameSeconds);
        cells += out.summary.avgIterations * double(out.summary.coveredPixels);
        pixels += double(out.summary.coveredPixels);
    }
    state.counters["cells/px"] = cells / std::max(pixels, 1.0);
    state.counters["frames/s"] =
        benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}

void Register(const std::string& mapName, const DepthField& field) {
    for (const View& v : kViews)
        benchmark::RegisterBenchmark(
            ("BM_ExactFrame512/" + mapName + "/" + v.name).c_str(),
            [field, v](benchmark::State& st) { ExactFrame(st, field, v); })
            ->Arg(1)
            ->Arg(2)
            ->ArgName("threads")
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    Register("shapes256", MakeBuiltinMap("builtin:shapes"));
    Register("noise1024", MakeBuiltinMap("builtin:noise:1024"));
    const std::string data = RS_SHARED_DATA;
    if (std::filesystem::exists(data + "/dxsdk-pom/rocks_NM_height.tga")) {
        MapLoadOptions o;
        Register("rocks256_8bit",
                 LoadHeightMap(data + "/dxsdk-pom/rocks_NM_height.tga", o));
        const DepthField stones =
            LoadHeightMap(data + "/dxsdk-pom/stones_NM_height.tga", o);
        Register("stones256_8bit", stones);
        Register("stones1024_float", Upsample(stones, 1024));
    }
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
