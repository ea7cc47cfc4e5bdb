// The frame driver: scene set-up, the fragment program running a kernel per lane,
// outputs.
#include "render/frame.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "core/error.h"
#include "core/memory.h"
#include "core/output_set.h"
#include "metrics/heatmap.h"
#include "raster/camera.h"
#include "raster/mesh.h"
#include "raster/rasterizer.h"
#include "render/batch.h"

namespace reliefsim {

namespace fs = std::filesystem;

void ValidateSettings(const RenderSettings& s) {
    auto bad = [](const std::string& what) { throw Error(what); };
    auto num = [](float v) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.9g", double(v));
        return std::string(buf);
    };
    if (s.width < 1 || s.height < 1 || s.width > 16384 || s.height > 16384)
        bad("--size " + std::to_string(s.width) + "x" + std::to_string(s.height) +
            ": each side must be in [1, 16384]");
    if (!(s.viewAngle >= 0.0f && s.viewAngle < 90.0f))
        bad("--view-angle " + num(s.viewAngle) + ": must be in [0, 90) degrees");
    if (!(std::fabs(s.azimuth) <= 1e6f))
        bad("--azimuth " + num(s.azimuth) +
            ": must be a finite angle in [-1e6, 1e6] degrees");
    if (!(s.depthScale > 0.0f && s.depthScale <= kMaxDepthScale))
        bad("--depth-scale " + num(s.depthScale) + ": must be in (0, " +
            num(kMaxDepthScale) + "] plane widths");
    if (!(s.tiling > 0.0f && s.tiling <= kMaxTiling))
        bad("--tiling " + num(s.tiling) + ": must be in (0, " + num(kMaxTiling) + "]");
    if (!(s.distance >= kMinDistance && s.distance <= kMaxDistance))
        bad("--distance " + num(s.distance) + ": must be in [" + num(kMinDistance) +
            ", " + num(kMaxDistance) + "] plane widths");
    if (!(s.fovY > 0.0f && s.fovY < 180.0f))
        bad("--fov " + num(s.fovY) + ": must be in (0, 180) degrees");
    if (s.threads < 0 || s.threads > kMaxThreads)
        bad("--threads " + std::to_string(s.threads) + ": must be in [0, " +
            std::to_string(kMaxThreads) + "]");
    if (!std::isfinite(s.iterScaleMin) || !std::isfinite(s.iterScaleMax) ||
        !(s.iterScaleMax > s.iterScaleMin))
        bad("--iterations-scale: MIN and MAX must be finite with MAX > MIN");
    if (!std::isfinite(s.fetchScaleMin) || !std::isfinite(s.fetchScaleMax) ||
        !(s.fetchScaleMax > s.fetchScaleMin))
        bad("--fetches-scale: MIN and MAX must be finite with MAX > MIN");
    ResolveParams(FindMethod(s.method), s.set);
    PickLaneWidth(s.lanes);
}

uint64_t EstimateFrameBytes(int width, int height, uint64_t bytesPerPixel) {
    constexpr uint64_t kBaseBytes = 64ull << 20;
    return kBaseBytes +
           bytesPerPixel * uint64_t(std::max(width, 0)) * uint64_t(std::max(height, 0));
}

void RequireFrameMemory(int width, int height, uint64_t bytesPerPixel) {
    RequireMemory(EstimateFrameBytes(width, height, bytesPerPixel),
                  "--size " + std::to_string(width) + "x" + std::to_string(height),
                  "use a smaller --size");
}

namespace {

// A float setting as the shortest decimal that round-trips (0.1f prints as 0.1, not
// 0.10000000149011612), so metrics.json reads like the command line that made it.
double ShortestDouble(float f) {
    char buf[32];
    auto res = std::to_chars(buf, buf + sizeof buf, f);
    return std::strtod(std::string(buf, res.ptr).c_str(), nullptr);
}

struct TileTotals {
    uint64_t helperLanes = 0, helperFetches = 0, helperTexelReads = 0;
    LaneCosts laneCost;
};

// The fragment stage: quads are collected per triangle and tile, their rays computed, and
// run through the fragment driver (render/batch.h) in packs of the lane width; results go
// to the record, helper lanes to the tile's totals, and each (group, triangle) costs its
// group's largest trip count times its lanes.
class FrameProgram {
  public:
    static constexpr bool kReadsAttributes = false;  // rays come from PixelToRay

    FrameProgram(const BatchJob& job, BatchFn run, FrameRecord& record,
                 std::vector<float>& color, std::vector<TileTotals>& tiles)
        : job_(job), run_(run), record_(record), color_(color), tiles_(tiles) {}

    void ShadeQuad(const QuadFragment& q, int tileIndex) {
        Scratch& s = scratch_.local();
        s.quads.push_back({q.pixel0, q.coveredMask});
        if (s.quads.size() == kMaxPending) Flush(s, tileIndex);
    }

    void EndTriangleInTile(int tileIndex) {
        Scratch& s = scratch_.local();
        Flush(s, tileIndex);
        LaneCosts& c = tiles_[size_t(tileIndex)].laneCost;
        for (uint32_t& m : s.group4x2) c.group4x2 += 8 * std::exchange(m, 0u);
        for (uint32_t& m : s.warp32) c.warp32 += 32 * std::exchange(m, 0u);
        for (uint32_t& m : s.wave64) c.wave64 += 64 * std::exchange(m, 0u);
    }

  private:
    static constexpr size_t kMaxPending = 256;  // quads per batch
    struct PendingQuad {
        glm::ivec2 pixel0;
        uint8_t coveredMask;
    };
    // Per thread: the pending quads of the tile it runs, the batch arrays, and the
    // largest trip count of each group of the current (tile, triangle), indexed within
    // the tile.
    struct Scratch {
        std::vector<PendingQuad> quads;
        std::vector<int32_t> px, py;
        std::vector<float> u, v, depth, rgb;
        std::vector<uint16_t> nCoarse, nRefine;
        std::vector<uint32_t> fetches, texels;
        std::vector<uint8_t> flags;
        std::vector<uint32_t> group4x2 = std::vector<uint32_t>((kTileSize / 4) *
                                                               (kTileSize / 2)),
                              warp32 = std::vector<uint32_t>((kTileSize / 8) *
                                                             (kTileSize / 4)),
                              wave64 = std::vector<uint32_t>((kTileSize / 8) *
                                                             (kTileSize / 8));
    };

    void Flush(Scratch& s, int tileIndex) {
        const size_t nQuads = s.quads.size();
        if (nQuads == 0) return;
        const size_t n = 4 * nQuads;
        s.px.resize(n), s.py.resize(n), s.rgb.resize(3 * n);
        s.u.resize(n), s.v.resize(n), s.depth.resize(n), s.nCoarse.resize(n);
        s.nRefine.resize(n), s.fetches.resize(n), s.texels.resize(n), s.flags.resize(n);
        for (size_t q = 0; q < nQuads; ++q) {
            for (int k = 0; k < 4; ++k) {
                s.px[4 * q + size_t(k)] = s.quads[q].pixel0.x + (k & 1);
                s.py[4 * q + size_t(k)] = s.quads[q].pixel0.y + (k >> 1);
            }
        }
        LaneBatch b;
        b.n = int(n);
        b.px = s.px.data(), b.py = s.py.data(), b.rgb = s.rgb.data();
        b.u = s.u.data(), b.v = s.v.data(), b.depth = s.depth.data();
        b.nCoarse = s.nCoarse.data(), b.nRefine = s.nRefine.data();
        b.fetches = s.fetches.data(), b.texelReads = s.texels.data();
        b.flags = s.flags.data();
        run_(job_, b);

        TileTotals& tile = tiles_[size_t(tileIndex)];
        const int tilesX = TileCountX(record_.width);
        const int tileX0 = (tileIndex % tilesX) * kTileSize;
        const int tileY0 = (tileIndex / tilesX) * kTileSize;
        for (size_t q = 0; q < nQuads; ++q) {
            const PendingQuad& quad = s.quads[q];
            uint32_t quadTrips = 0;
            for (int k = 0; k < 4; ++k) {
                const size_t i = 4 * q + size_t(k);
                const int px = quad.pixel0.x + (k & 1), py = quad.pixel0.y + (k >> 1);
                if (!((quad.coveredMask >> k) & 1u)) {
                    ++tile.helperLanes;
                    tile.helperFetches += s.fetches[i];
                    tile.helperTexelReads += s.texels[i];
                    continue;
                }
                quadTrips = std::max(quadTrips, s.fetches[i]);  // one fetch per trip
                const size_t r = record_.Index(px, py);
                record_.hitU[r] = s.u[i];
                record_.hitV[r] = s.v[i];
                record_.hitDepth[r] = s.depth[i];
                record_.nCoarse[r] = s.nCoarse[i];
                record_.nRefine[r] = s.nRefine[i];
                record_.nFetches[r] = s.fetches[i];
                record_.nTexelReads[r] = s.texels[i];
                record_.flags[r] = uint8_t(kFlagCovered | s.flags[i]);
                for (int c = 0; c < 3; ++c)
                    color_[3 * r + size_t(c)] = s.rgb[3 * i + size_t(c)];
            }
            // A lane leaves the loop for good, so a group runs as many trips as its
            // longest-running covered lane.
            tile.laneCost.quad += 4 * uint64_t(quadTrips);
            const int lx = quad.pixel0.x - tileX0, ly = quad.pixel0.y - tileY0;
            uint32_t& g = s.group4x2[size_t((ly / 2) * (kTileSize / 4) + lx / 4)];
            uint32_t& w = s.warp32[size_t((ly / 4) * (kTileSize / 8) + lx / 8)];
            uint32_t& v = s.wave64[size_t((ly / 8) * (kTileSize / 8) + lx / 8)];
            g = std::max(g, quadTrips);
            w = std::max(w, quadTrips);
            v = std::max(v, quadTrips);
        }
        s.quads.clear();
    }

    const BatchJob& job_;
    BatchFn run_;
    FrameRecord& record_;
    std::vector<float>& color_;
    std::vector<TileTotals>& tiles_;
    tbb::enumerable_thread_specific<Scratch> scratch_;
};

}  // namespace

Kernel SettingsKernel(const RenderSettings& s) {
    const KernelInfo& method = FindMethod(s.method);
    return MakeKernel(method, ResolveParams(method, s.set));
}

Camera SceneCamera(const RenderSettings& s) {
    return MakeOrbitCamera(s.viewAngle, s.azimuth, s.distance, s.fovY,
                           float(s.width) / float(s.height));
}

ViewUniforms MakeViewUniforms(const RenderSettings& s) {
    Camera cam = SceneCamera(s);
    const glm::mat4& v = cam.viewFromWorld;
    const double tanY = std::tan(double(s.fovY) * 0.5 * 3.14159265358979323846 / 180.0);
    const double tanX = tanY * double(s.width) / double(s.height);
    ViewUniforms u;
    u.eye = cam.eye;
    u.right = glm::vec3(float(double(v[0][0]) * tanX), float(double(v[1][0]) * tanX),
                        float(double(v[2][0]) * tanX));
    u.up = glm::vec3(float(double(v[0][1]) * tanY), float(double(v[1][1]) * tanY),
                     float(double(v[2][1]) * tanY));
    u.forward = glm::vec3(-v[0][2], -v[1][2], -v[2][2]);
    u.width = float(s.width);
    u.height = float(s.height);
    u.tiling = s.tiling;
    u.depthScale = s.depthScale;
    return u;
}

RenderOutput Render(const DepthField& field, const RenderSettings& s) {
    ValidateSettings(s);
    ValidateDepthField(field);
    RenderOutput out;
    const Kernel kernel = SettingsKernel(s);
    out.params = kernel.values;
    const LaneWidthInfo& lanes = PickLaneWidth(s.lanes);
    std::shared_ptr<const void> params;
    BatchJob job = MakeBatchJob(kernel, BindTextures(field, s.sampler), params);

    std::unique_ptr<tbb::global_control> limit;
    if (s.threads > 0)
        limit = std::make_unique<tbb::global_control>(
            tbb::global_control::max_allowed_parallelism, size_t(s.threads));
    out.lanes = lanes.width;
    out.isa = lanes.isa;
    out.threads = int(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

    out.record.Resize(s.width, s.height);
    out.color.assign(size_t(s.width) * size_t(s.height) * 3, 0.0f);
    std::vector<TileTotals> tiles(size_t(TileCount(s.width, s.height)));
    const ViewUniforms uniforms = MakeViewUniforms(s);
    const Camera camera = SceneCamera(s);
    const Mesh mesh = MakePlane(s.tiling);
    job.view = &uniforms;
    job.slopeScale = s.depthScale * s.tiling;

    auto start = std::chrono::steady_clock::now();
    FrameProgram program(job, lanes.fn, out.record, out.color, tiles);
    const RasterStats stats = RasterizeFrame(mesh, camera, s.width, s.height, program);
    out.frameSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    out.nQuads = stats.nQuads;
    for (const TileTotals& t : tiles) {  // tile-index order
        out.record.nHelperLanes += t.helperLanes;
        out.record.nHelperFetches += t.helperFetches;
        out.record.nHelperTexelReads += t.helperTexelReads;
        out.laneCost.quad += t.laneCost.quad;
        out.laneCost.group4x2 += t.laneCost.group4x2;
        out.laneCost.warp32 += t.laneCost.warp32;
        out.laneCost.wave64 += t.laneCost.wave64;
    }
    out.summary = Summarize(out.record, field, s.sampler);
    return out;
}

nlohmann::json MetricsJson(const RenderOutput& out, const RenderSettings& s,
                           const DepthField& field) {
    const FrameSummary& m = out.summary;
    nlohmann::json params = nlohmann::json::object();
    for (const auto& [k, v] : out.params) {
        if (v == std::floor(v))
            params[k] = int64_t(v);
        else
            params[k] = v;
    }
    nlohmann::json j;
    j["method"] = s.method;
    j["params"] = params;
    j["map"] = field.name;
    j["map_width"] = field.width;
    j["map_height"] = field.height;
    j["width"] = s.width;
    j["height"] = s.height;
    j["view_angle"] = ShortestDouble(s.viewAngle);
    j["azimuth"] = ShortestDouble(s.azimuth);
    j["distance"] = ShortestDouble(s.distance);
    j["fov"] = ShortestDouble(s.fovY);
    j["depth_scale"] = ShortestDouble(s.depthScale);
    j["tiling"] = ShortestDouble(s.tiling);
    j["filter"] = std::string(ToString(s.sampler.filter));
    j["wrap"] = std::string(ToString(s.sampler.wrap));
    j["covered_pixels"] = m.coveredPixels;
    j["avg_iterations"] = m.avgIterations;
    j["avg_coarse_iterations"] = m.avgCoarse;
    j["avg_refine_iterations"] = m.avgRefine;
    j["avg_fetches"] = m.avgFetches;
    j["max_fetches"] = m.maxFetches;
    j["total_fetches"] = m.totalFetches;
    j["total_texel_reads"] = m.totalTexelReads;
    j["budget_exhausted_pixels"] = m.budgetExhaustedPixels;
    j["no_hit_pixels"] = m.noHitPixels;
    j["mse_paper"] = m.msePaper;
    j["sum_sq_error_paper"] = m.sumSqPaper;
    j["max_abs_error_paper"] = m.maxAbsErrorPaper;
    j["quads"] = out.nQuads;
    j["helper_lanes"] = out.record.nHelperLanes;
    j["helper_fetches"] = out.record.nHelperFetches;
    j["helper_texel_reads"] = out.record.nHelperTexelReads;
    j["lane_fetches_4x2"] = m.laneFetches4x2;
    j["lane_fetches_8x4"] = m.laneFetches8x4;
    j["heatmap_scale"] = {
        {"iterations", {ShortestDouble(s.iterScaleMin), ShortestDouble(s.iterScaleMax)}},
        {"fetches", {ShortestDouble(s.fetchScaleMin), ShortestDouble(s.fetchScaleMax)}}};
    j["lane_cost_quad"] = out.laneCost.quad;
    j["lane_cost_4x2"] = out.laneCost.group4x2;
    j["lane_cost_warp32"] = out.laneCost.warp32;
    j["lane_cost_wave64"] = out.laneCost.wave64;
    j["timing"] = {{"frame_seconds", out.frameSeconds},
                   {"threads", out.threads},
                   {"lanes", out.lanes},
                   {"isa", out.isa}};
    return j;
}

void WriteRenderOutputs(const std::string& outDir, const RenderOutput& out,
                        const RenderSettings& s, const DepthField& field) {
    if (outDir.empty()) throw Error("--out: empty; give a directory");
    const fs::path dir(outDir);
    std::error_code ec;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
        throw Error("--out \"" + outDir + "\": exists and is not a directory");
    // All five files are staged as temporaries beside their destinations (or in the
    // nearest existing ancestor while the folder does not exist) and replace what was
    // there only once every one is complete, all or nothing (core/output_set.h). Every
    // destination is checked before anything is written.
    OutputSet outputs("--out \"" + outDir + "\"");
    auto dest = [&](const char* name) { return (dir / name).string(); };
    for (const char* name :
         {"color.png", "iterations.png", "fetches.png", "record.exr", "metrics.json"})
        outputs.Add(dest(name));
    const FrameRecord& r = out.record;
    const int w = r.width, h = r.height;
    const size_t n = size_t(w) * size_t(h);
    std::vector<uint8_t> mask(n);
    std::vector<float> iters(n), fetches(n), coarse(n), refine(n), texels(n), flags(n),
        err(n);
    for (size_t i = 0; i < n; ++i) {
        mask[i] = r.Covered(i) ? 1 : 0;
        coarse[i] = float(r.nCoarse[i]);
        refine[i] = float(r.nRefine[i]);
        iters[i] = float(r.nCoarse[i] + r.nRefine[i]);
        fetches[i] = float(r.nFetches[i]);
        texels[i] = float(r.nTexelReads[i]);
        flags[i] = float(r.flags[i]);
        err[i] = PaperError(r, i, field, s.sampler);
    }
    WriteColorPng(dest("color.png"), out.color.data(), w, h, &outputs);
    WriteHeatmapPng(dest("iterations.png"), iters.data(), mask.data(), w, h,
                    {s.iterScaleMin, s.iterScaleMax, "inferno",
                     "iterations (coarse + refine), " + s.method},
                    &outputs);
    WriteHeatmapPng(dest("fetches.png"), fetches.data(), mask.data(), w, h,
                    {s.fetchScaleMin, s.fetchScaleMax, "inferno", "fetches, " + s.method},
                    &outputs);
    WriteMultiChannelExr(
        dest("record.exr"), w, h,
        {"hit_u", "hit_v", "hit_depth", "coarse_iterations", "refine_iterations",
         "iterations", "fetches", "texel_reads", "flags", "error_paper"},
        {r.hitU.data(), r.hitV.data(), r.hitDepth.data(), coarse.data(), refine.data(),
         iters.data(), fetches.data(), texels.data(), flags.data(), err.data()},
        &outputs);
    outputs.Write(dest("metrics.json"), MetricsJson(out, s, field).dump(2) + "\n");
    outputs.Commit();
}

}  // namespace reliefsim
