// Whole-frame timing: the simulator's frame loop against the GLSL twin on llvmpipe, same
// scene, kernel, resolution and thread count (research/llvmpipe.md §4).
//
//   frame_vs_llvmpipe --method relief --size 512x512 --threads 1 [render's map/scene
//   options]
//
// Simulator: Render() with --threads worker threads; the time is the frame loop
// (RenderOutput::frameSeconds). llvmpipe: LP_NUM_THREADS = --threads (all cores for 0),
// shader disk cache off, one warm-up draw (JIT) plus two more, then per frame draw +
// glFinish on a steady clock, no lane probe. Both report the median of --frames (>= 5).
// The last line is `ratio=<simulator ms / llvmpipe ms>`.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "app/glcompare.h"
#include "core/error.h"
#include "core/param_name.h"
#include "metrics/record_compare.h"
#include "render/frame.h"

namespace {

using namespace reliefsim;

double Median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string CpuModel() {
    std::ifstream f("/proc/cpuinfo");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}

int Run(int argc, char** argv) {
    CLI::App app{
        "frame_vs_llvmpipe: ms/frame of the simulator and of llvmpipe for one scene"};
    RenderOptions o;
    int frames = 7;
    AddRenderOptions(&app, o);
    app.add_option("--frames", frames, "timed frames per path (median; >= 5)")
        ->capture_default_str();
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    if (frames < 5) throw Error("--frames " + std::to_string(frames) + ": must be >= 5");
    ResolveRenderSettings(o);
    RenderSettings& s = o.settings;
    const int threads = s.threads > 0
                            ? s.threads
                            : int(std::max(1u, std::thread::hardware_concurrency()));
    s.threads = threads;
    DepthField field = LoadRenderMap(o);

    // llvmpipe first: LP_NUM_THREADS and the cache switch must be set before its screen
    // exists.
    setenv("MESA_SHADER_CACHE_DISABLE", "true", 1);
    GlReference gl(threads);
    GlScene scene = MakeGlScene(s);
    scene.measureLanes = false;
    BindSceneMaps(scene, field, s);  // the cone kernels' maps, as Render() binds them
    gl.Prepare(field, scene);
    for (int k = 0; k < 3; ++k) gl.DrawAndFinish();  // JIT + warm caches
    std::vector<double> glMs;
    for (int k = 0; k < frames; ++k) {
        auto t0 = std::chrono::steady_clock::now();
        gl.DrawAndFinish();
        glMs.push_back(std::chrono::duration<double, std::milli>(
                           std::chrono::steady_clock::now() - t0)
                           .count());
    }
    const GlFrame glFrame = gl.ReadBack();

    s.reference = false;  // the frame loop is timed; the reference pass is not part of it
    // Both sides write the record and its counts; llvmpipe's twin shades nothing
    // (glref/record_main.glsl), so the simulator does not shade either.
    s.shade = false;
    RenderOutput warm = Render(field, s);  // warm-up
    std::vector<double> simMs;
    for (int k = 0; k < frames; ++k) simMs.push_back(Render(field, s).frameSeconds * 1e3);
    const RecordComparison cmp = CompareRecords(warm.record, glFrame.record, 0);

    const double sim = Median(simMs), ref = Median(glMs);
    std::printf("scene: %s on %s at %dx%d, %s %s %s, threads %d\n", s.method.c_str(),
                field.name.c_str(), s.width, s.height,
                std::string(kTextureFormatNames.Name(s.sampler.precision)).c_str(),
                std::string(ToString(s.sampler.filter)).c_str(),
                std::string(ToString(s.sampler.wrap)).c_str(), threads);
    std::printf("cpu: %s (footprints: %s, RS_FOOTPRINT); llvmpipe: %s\n",
                CpuModel().c_str(), GatherFootprints() ? "gather" : "loads",
                gl.Renderer().c_str());
    std::printf("fetches/px %.3f, lane-fetches (4x2) %llu; records bit-identical: %s\n",
                warm.summary.avgFetches, (unsigned long long)warm.summary.laneFetches4x2,
                cmp.AllIdentical() ? "yes" : "NO");
    std::printf("simulator: %.3f ms/frame (median of %d; min %.3f, max %.3f)\n", sim,
                frames, *std::min_element(simMs.begin(), simMs.end()),
                *std::max_element(simMs.begin(), simMs.end()));
    std::printf("llvmpipe:  %.3f ms/frame (median of %d; min %.3f, max %.3f)\n", ref,
                frames, *std::min_element(glMs.begin(), glMs.end()),
                *std::max_element(glMs.begin(), glMs.end()));
    std::printf("ratio=%.4f\n", sim / ref);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    reliefsim::SetParamNamer(&reliefsim::FlagName);  // errors name the flags
    try {
        return Run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "frame_vs_llvmpipe: error: %s\n", e.what());
        return 1;
    }
}
