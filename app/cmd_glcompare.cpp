// `reliefsim glcompare`: renders with the C++ frame loop and with the GLSL twins on
// llvmpipe and compares the per-pixel records bit for bit.
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <sstream>

#include "app/commands.h"
#include "app/glcompare.h"
#include "core/error.h"
#include "core/parse.h"
#include "metrics/heatmap.h"
#include "raster/camera.h"
#include "raster/rasterizer.h"
#include "raster/viewport_pieces.h"
#include "render/batch.h"
#include "render/trace.h"

namespace reliefsim {

namespace {

std::string Hex(float f) {
    uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g (0x%08" PRIx32 ")", double(f), b);
    return buf;
}

struct GlCompareArgs {
    RenderOptions options;
    bool json = false;
    std::string heatmap = "glcompare_diff.png";
    std::string tracePixel;
    int maxListed = 10;
    const CLI::Option* heatmapOption = nullptr;
};

void PrintTrace(const GlCompareArgs& a, const DepthField& field, int x, int y) {
    const RenderSettings& s = a.options.settings;
    if (x < 0 || y < 0 || x >= s.width || y >= s.height)
        throw Error("--trace-pixel " + a.tracePixel + ": outside the " +
                    std::to_string(s.width) + "x" + std::to_string(s.height) + " frame");
    // C++ path: the shared per-pixel trace (same kernel, inputs and FTZ/DAZ as the
    // frame).
    const PixelTrace cpu = TracePixel(field, s, x, y);
    const MarchInput& in = cpu.input;
    const MarchResult& m = cpu.result;
    const FetchCounts& counts = cpu.counts;
    std::vector<glm::vec4> cpuLog;  // u, v, depth, t
    for (const TraceFetch& f : cpu.fetches)
        cpuLog.emplace_back(f.uv.x, f.uv.y, f.depth, f.t);
    GlReference gl(s.threads > 0 ? s.threads : -1);
    GlScene scene = MakeGlScene(s);
    scene.measureLanes = false;
    BindSceneMaps(scene, field, s);  // the cone channel exactly as the C++ frame's
    scene.traceX = x;
    scene.traceY = y;
    GlFrame g = gl.Render(field, scene);
    const size_t i = g.record.Index(x, y);
    std::cout << "trace of pixel " << x << "," << y << " (row 0 at the top), " << s.method
              << "; " << gl.Renderer() << "\n"
              << "ray: uvEntry " << Hex(in.uvEntry.x) << ", " << Hex(in.uvEntry.y)
              << "; dirUv " << Hex(in.dirUv.x) << ", " << Hex(in.dirUv.y) << "\n";
    const size_t n = std::max(cpuLog.size(), g.trace.size());
    bool diverged = false;
    for (size_t k = 0; k < n; ++k) {
        std::cout << "fetch " << k << ":\n";
        if (k < cpuLog.size())
            std::cout << "  C++  uv " << Hex(cpuLog[k].x) << ", " << Hex(cpuLog[k].y)
                      << "  depth " << Hex(cpuLog[k].z) << "\n";
        if (k < g.trace.size())
            std::cout << "  GL   uv " << Hex(g.trace[k].x) << ", " << Hex(g.trace[k].y)
                      << "  depth " << Hex(g.trace[k].z) << "  t " << Hex(g.trace[k].w)
                      << "\n";
        if (!diverged && k < cpuLog.size() && k < g.trace.size() &&
            (UlpDistance(cpuLog[k].x, g.trace[k].x) ||
             UlpDistance(cpuLog[k].y, g.trace[k].y) ||
             UlpDistance(cpuLog[k].z, g.trace[k].z))) {
            std::cout << "  ^ first divergence\n";
            diverged = true;
        }
    }
    std::cout << "result C++: uv " << Hex(m.uvHit.x) << ", " << Hex(m.uvHit.y)
              << " depth " << Hex(m.depthHit) << " coarse " << m.nCoarse << " refine "
              << m.nRefine << " fetches " << counts.nFetches << "\n";
    if (g.record.Covered(i))
        std::cout << "result GL:  uv " << Hex(g.record.hitU[i]) << ", "
                  << Hex(g.record.hitV[i]) << " depth " << Hex(g.record.hitDepth[i])
                  << " coarse " << g.record.nCoarse[i] << " refine "
                  << g.record.nRefine[i] << " fetches " << g.record.nFetches[i] << "\n";
    else
        std::cout << "result GL:  pixel not covered\n";
}

void PrintText(const GlCompareResult& r, const GlCompareArgs& a,
               const DepthField& field) {
    const RenderSettings& s = a.options.settings;
    const RecordComparison& c = r.comparison;
    std::printf("reliefsim glcompare: %s on %s at %dx%d, %s %s %s; %s\n",
                s.method.c_str(), field.name.c_str(), s.width, s.height,
                std::string(kTextureFormatNames.Name(s.sampler.precision)).c_str(),
                std::string(ToString(s.sampler.filter)).c_str(),
                std::string(ToString(s.sampler.wrap)).c_str(), r.renderer.c_str());
    std::printf("pixels %" PRIu64 " covered by both; coverage differs at %" PRIu64
                " (C++ only %" PRIu64 ", llvmpipe only %" PRIu64
                "); flags differ at %" PRIu64 "\n",
                c.pixels, c.cpuOnly + c.glOnly, c.cpuOnly, c.glOnly, c.flagsDiffer);
    auto row = [&](const char* name, const FieldAgreement& f, const char* unit) {
        std::printf("  %-16s %8.3f%% identical (%" PRIu64 " / %" PRIu64
                    "), max diff %" PRIu64 " %s\n",
                    name, 100.0 * f.fraction, f.identical, c.pixels, f.maxDiff, unit);
    };
    row("hit_uv", c.hitUv, "ulp");
    row("hit_depth", c.hitDepth, "ulp");
    row("iterations", c.iterations, "");
    row("fetches", c.fetches, "");
    if (r.shadow.on) {
        const ShadowComparison& sh = r.shadow;
        auto share = [&](uint64_t n) {
            return sh.pixels ? 100.0 * double(n) / double(sh.pixels) : 100.0;
        };
        std::printf("  %-16s %8.3f%% identical (%" PRIu64 " / %" PRIu64 ")\n",
                    "shadow_fetches", share(sh.fetchesIdentical), sh.fetchesIdentical,
                    sh.pixels);
        std::printf("  %-16s %8.3f%% identical (%" PRIu64 " / %" PRIu64 ")\n",
                    "light_visibility", share(sh.visibilityIdentical),
                    sh.visibilityIdentical, sh.pixels);
        if (sh.ambient)
            std::printf("  %-16s %8.3f%% identical (%" PRIu64 " / %" PRIu64 ")\n",
                        "ambient_occlusion", share(sh.ambientIdentical),
                        sh.ambientIdentical, sh.pixels);
    }
    if (r.gl.lanes.available) {
        const LaneCostCheck& l = r.laneCost;
        std::printf(
            "lane cost (4x2 groups x 8 lanes): model %" PRIu64 " %s measured %" PRIu64
            " lane-fetches; groups model %" PRIu64 " / run %" PRIu64 ", %" PRIu64
            " mismatched; subgroup size %u, shape violations %" PRIu64
            "; summary lane_fetches_4x2 (blocks not split by triangle) %" PRIu64 "\n",
            l.modelLaneFetches, l.Equal() ? "==" : "!=", l.measuredLaneFetches,
            l.modelGroups, l.measuredGroups, l.groupsMismatched, r.gl.lanes.subgroupSize,
            r.gl.lanes.shapeViolations, l.summaryLaneFetches);
        for (const LaneCostCheck::Mismatch& mm : l.firstMismatches)
            std::printf(
                "  group at pixels %d..%d, rows %d..%d, triangle %d: model %u trips, "
                "measured %u\n",
                4 * mm.blockX, 4 * mm.blockX + 3, 2 * mm.blockY, 2 * mm.blockY + 1,
                mm.triangle, mm.modelTrips, mm.measuredTrips);
    } else {
        std::printf("lane cost: not measured (GL_ARB_shader_ballot unavailable)\n");
    }
    if (c.firstDiffs.empty()) {
        std::printf("first differing pixels: none\n");
    } else {
        std::printf("first differing pixels (trace with the command shown):\n");
        for (const glm::ivec2& p : c.firstDiffs)
            std::printf("  %d,%d: %s\n", p.x, p.y,
                        TraceCommand(a.options, p.x, p.y).c_str());
    }
}

void RunGlCompareCommand(GlCompareArgs& a) {
    ResolveRenderSettings(a.options);
    const RenderSettings& s = a.options.settings;
    if (s.sampler.precision == Precision::Gpu8)
        throw Error("--texture-format: the gpu8 precision has no llvmpipe twin");
    std::pair<int, int> pixel{-1, -1};
    if (!a.tracePixel.empty()) {
        pixel = ParsePixel("--trace-pixel", a.tracePixel, s.width, s.height);
        if (a.json)
            throw Error("--json: not used with --trace-pixel (the trace is text)");
        if (a.heatmapOption && a.heatmapOption->count() > 0)
            throw Error(
                "--heatmap: not used with --trace-pixel (a trace writes no heatmap)");
    } else if (!a.heatmap.empty()) {
        CheckOutputFile("--heatmap", a.heatmap, /*folderIsCreated=*/false);
    }
    if (a.tracePixel.empty())
        RequireFrameMemory(s.width, s.height, kGlCompareBytesPerPixel);
    DepthField field = LoadRenderMap(a.options);
    if (!a.tracePixel.empty()) {
        const auto [x, y] = pixel;
        PrintTrace(a, field, x, y);
        return;
    }
    GlReference gl(s.threads > 0 ? s.threads : -1);
    GlCompareResult r = RunGlCompare(field, s, gl);
    const RecordComparison& c = r.comparison;
    if (!a.heatmap.empty())
        WriteHeatmapPng(
            a.heatmap, c.diffMap.data(), c.mask.data(), s.width, s.height,
            {0.0f, 5.0f, "inferno",
             "differing fields (0-4; 5 = coverage), " + s.method + " C++ vs llvmpipe"});
    if (a.json) {
        std::cout << GlCompareJson(r, a.options, field).dump(2) << "\n";
    } else {
        PrintText(r, a, field);
        if (!a.heatmap.empty()) std::printf("wrote %s\n", a.heatmap.c_str());
    }
}

}  // namespace

std::string TraceCommand(const RenderOptions& o, int x, int y) {
    const RenderSettings& s = o.settings;
    std::ostringstream cmd;
    cmd << "reliefsim glcompare --map " << o.map.map;
    if (o.map.channel != Channel::Auto)
        cmd << " --map-channel " << ToString(o.map.channel);
    if (o.map.stores != Stores::Height) cmd << " --map-stores " << ToString(o.map.stores);
    cmd << " --method " << s.method;
    for (const auto& kv : s.set) cmd << " --set " << kv;
    cmd << " --size " << s.width << "x" << s.height;
    // Only what the frame reads (glcompare refuses the others: RefuseIgnoredSettings).
    const auto read = [&](std::string_view key) { return SettingRead(s, key); };
    if (read("view_angle")) cmd << " --view-angle " << FloatText(s.viewAngle);
    if (read("azimuth")) cmd << " --azimuth " << FloatText(s.azimuth);
    if (read("distance")) cmd << " --distance " << FloatText(s.distance);
    if (read("fov")) cmd << " --fov " << FloatText(s.fovY);
    cmd << " --depth-scale " << FloatText(s.depthScale) << " --tiling "
        << FloatText(s.tiling) << " --filter " << ToString(s.sampler.filter) << " --wrap "
        << ToString(s.sampler.wrap) << " --texture-format "
        << kTextureFormatNames.Name(s.sampler.precision);
    auto vec3 = [](const glm::vec3& v) {
        return FloatText(v.x) + "," + FloatText(v.y) + "," + FloatText(v.z);
    };
    cmd << " --camera " << kCameraNames.Name(s.camera);
    if (read("view_dir")) cmd << " --view-dir " << vec3(s.viewDir);
    cmd << " --light-dir " << vec3(s.lightDir);
    if (s.shadow != ShadowKind::None) {
        cmd << " --shadow " << kShadowNames.Name(s.shadow);
        if (read("shadow_steps")) cmd << " --shadow-steps " << s.shadowSteps;
        if (read("shadow_softening"))
            cmd << " --shadow-softening " << FloatText(s.shadowSoftening);
        if (read("shadow_penumbra"))
            cmd << " --shadow-penumbra " << FloatText(s.shadowPenumbra);
    }
    if (s.ao != AoKind::None) cmd << " --ao " << kAoNames.Name(s.ao);
    // The cone map as it was made or given.
    if (!s.maps.coneMap.empty()) {
        cmd << " --cone-map " << s.maps.coneMap;
        if (s.maps.coneMapChannel >= 0)
            cmd << " --cone-map-channel "
                << "RGBA"[s.maps.coneMapChannel];
        if (s.maps.encoding) cmd << " --cone-map-encoding " << ToString(*s.maps.encoding);
    } else if (s.maps.encoding) {
        cmd << " --cone-encoding " << ToString(*s.maps.encoding);
    }
    if (s.maps.bounds != ConeBounds::Texel)
        cmd << " --cone-bounds " << kConeBoundsNames.Name(s.maps.bounds);
    cmd << " --trace-pixel " << x << "," << y;
    return cmd.str();
}

nlohmann::json GlCompareJson(const GlCompareResult& r, const RenderOptions& o,
                             const DepthField& field) {
    const RecordComparison& c = r.comparison;
    const RenderSettings& s = o.settings;
    nlohmann::json j;
    j["method"] = s.method;
    j["map"] = field.name;
    j["width"] = s.width;
    j["height"] = s.height;
    j["texture_format"] = std::string(kTextureFormatNames.Name(s.sampler.precision));
    j["filter"] = std::string(ToString(s.sampler.filter));
    j["wrap"] = std::string(ToString(s.sampler.wrap));
    j["renderer"] = r.renderer;
    j["pixels"] = c.pixels;
    j["identical"] = {{"hit_uv", c.hitUv.fraction},
                      {"hit_depth", c.hitDepth.fraction},
                      {"iterations", c.iterations.fraction},
                      {"fetches", c.fetches.fraction}};
    j["max_diff"] = {{"hit_uv_ulps", c.hitUv.maxDiff},
                     {"hit_depth_ulps", c.hitDepth.maxDiff},
                     {"iterations", c.iterations.maxDiff},
                     {"fetches", c.fetches.maxDiff}};
    j["coverage"] = {{"cpu_only", c.cpuOnly}, {"gl_only", c.glOnly}};
    j["flags_differ"] = c.flagsDiffer;
    if (r.shadow.on) {
        const ShadowComparison& sh = r.shadow;
        auto share = [&](uint64_t n) {
            return sh.pixels ? double(n) / double(sh.pixels) : 1.0;
        };
        j["identical"]["shadow_fetches"] = share(sh.fetchesIdentical);
        j["identical"]["light_visibility"] = share(sh.visibilityIdentical);
        if (sh.ambient) j["identical"]["ambient_occlusion"] = share(sh.ambientIdentical);
        j["shadow"] = std::string(kShadowNames.Name(s.shadow));
        j["ao"] = std::string(kAoNames.Name(s.ao));
    }
    j["all_identical"] = c.AllIdentical() && (!r.shadow.on || r.shadow.Identical());
    nlohmann::json diffs = nlohmann::json::array();
    for (const glm::ivec2& p : c.firstDiffs)
        diffs.push_back({{"x", p.x}, {"y", p.y}, {"trace", TraceCommand(o, p.x, p.y)}});
    j["first_differences"] = diffs;
    if (r.gl.lanes.available) {
        const LaneCostCheck& l = r.laneCost;
        j["lane_cost"] = {{"model_lane_fetches", l.modelLaneFetches},
                          {"measured_lane_fetches", l.measuredLaneFetches},
                          {"model_groups", l.modelGroups},
                          {"measured_groups", l.measuredGroups},
                          {"groups_mismatched", l.groupsMismatched},
                          {"equal", l.Equal()},
                          {"subgroup_size", r.gl.lanes.subgroupSize},
                          {"shape_violations", r.gl.lanes.shapeViolations},
                          {"summary_lane_fetches_4x2", l.summaryLaneFetches}};
    }
    return j;
}

void RegisterGlCompareCommand(CLI::App& root) {
    auto a = std::make_shared<GlCompareArgs>();
    auto* cmd = root.add_subcommand(
        "glcompare",
        "render with the C++ simulator and with the GLSL twins on Mesa llvmpipe (EGL "
        "surfaceless); report per field the share of bit-identical pixels, max ulps, the "
        "first differing pixels, the lane-cost check, and write a difference heatmap");
    AddRenderOptions(cmd, a->options, /*withHeatmapScales=*/false);
    cmd->add_flag("--json", a->json, "print the report as JSON");
    a->heatmapOption =
        cmd->add_option(
               "--heatmap", a->heatmap,
               "difference heatmap PNG (differing fields per pixel); empty: none")
            ->capture_default_str();
    cmd->add_option("--trace-pixel", a->tracePixel,
                    "print both paths' fetches for pixel X,Y (row 0 at the top) instead")
        ->type_name("X,Y");
    cmd->callback([a] { RunGlCompareCommand(*a); });
}

}  // namespace reliefsim
