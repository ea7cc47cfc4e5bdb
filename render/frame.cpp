// The frame driver: the rasterizer's fragment program, which runs the scene's kernel on
// the lane driver, and the frame loop.
#include "render/frame.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <utility>

#include "core/error.h"
#include "core/memory.h"
#include "core/param_name.h"
#include "metrics/exact.h"
#include "raster/rasterizer.h"
#include "render/batch.h"
#include "render/exact_batch.h"
#include "render/reference.h"

namespace reliefsim {

uint64_t EstimateFrameBytes(int width, int height, uint64_t bytesPerPixel) {
    constexpr uint64_t kBaseBytes = 64ull << 20;
    return kBaseBytes +
           bytesPerPixel * uint64_t(std::max(width, 0)) * uint64_t(std::max(height, 0));
}

void RequireFrameMemory(int width, int height, uint64_t bytesPerPixel) {
    RequireMemory(
        EstimateFrameBytes(width, height, bytesPerPixel),
        ParamName("size") + " " + std::to_string(width) + "x" + std::to_string(height),
        "use a smaller " + ParamName("size"));
}

namespace {

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
                 std::vector<float>& color, std::vector<TileTotals>& tiles,
                 std::vector<uint32_t>& shadowFetches, std::vector<float>& visibility,
                 std::vector<float>& ambient)
        : job_(job),
          run_(run),
          record_(record),
          color_(color),
          tiles_(tiles),
          shadowFetches_(shadowFetches),
          visibility_(visibility),
          ambient_(ambient) {}

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
        std::vector<uint32_t> fetches, texels, shadowFetches;
        std::vector<uint8_t> flags;
        std::vector<float> visibility, ambient;
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
        b.px = s.px.data(), b.py = s.py.data();
        b.rgb = color_.empty() ? nullptr : s.rgb.data();
        b.u = s.u.data(), b.v = s.v.data(), b.depth = s.depth.data();
        b.nCoarse = s.nCoarse.data(), b.nRefine = s.nRefine.data();
        b.fetches = s.fetches.data(), b.texelReads = s.texels.data();
        b.flags = s.flags.data();
        const bool shadows = job_.shadow.Any();
        const bool ambient = job_.shadow.ao != AoKind::None;
        if (shadows) {
            s.shadowFetches.resize(n), s.visibility.resize(n);
            b.shadowFetches = s.shadowFetches.data(), b.visibility = s.visibility.data();
        }
        if (ambient) {
            s.ambient.resize(n);
            b.ambient = s.ambient.data();
        }
        run_(job_, b);

        TileTotals& tile = tiles_[size_t(tileIndex)];
        const int tilesX = TileCountX(record_.width);
        const int tileX0 = (tileIndex % tilesX) * kTileSize;
        const int tileY0 = (tileIndex / tilesX) * kTileSize;
        // The record's and the batch's arrays as plain pointers: through the vectors,
        // every store reloaded every data pointer (measured: a fifth of Flush in perf).
        float *hitU = record_.hitU.data(), *hitV = record_.hitV.data(),
              *hitDepth = record_.hitDepth.data(), *color = color_.data();
        uint16_t *nCoarse = record_.nCoarse.data(), *nRefine = record_.nRefine.data();
        uint32_t *nFetches = record_.nFetches.data(),
                 *nTexelReads = record_.nTexelReads.data();
        uint8_t* flags = record_.flags.data();
        const size_t width = size_t(record_.width);
        // (The uint8_t stores may alias anything, so the batch's pointers are locals
        // too.)
        const float *bu = b.u, *bv = b.v, *bDepth = b.depth, *bRgb = b.rgb;
        const uint16_t *bCoarse = b.nCoarse, *bRefine = b.nRefine;
        const uint32_t *bFetches = b.fetches, *bTexels = b.texelReads;
        const uint8_t* bFlags = b.flags;
        uint64_t helperLanes = 0, helperFetches = 0, helperTexelReads = 0, quadCost = 0;
        for (size_t q = 0; q < nQuads; ++q) {
            const PendingQuad& quad = s.quads[q];
            uint32_t quadTrips = 0;
            for (int k = 0; k < 4; ++k) {
                const size_t i = 4 * q + size_t(k);
                const uint32_t fetches = bFetches[i];
                if (!((quad.coveredMask >> k) & 1u)) {
                    ++helperLanes;
                    helperFetches += fetches;
                    helperTexelReads += bTexels[i];
                    continue;
                }
                quadTrips = std::max(quadTrips, fetches);  // one fetch per trip
                const size_t px = size_t(quad.pixel0.x + (k & 1)),
                             py = size_t(quad.pixel0.y + (k >> 1));
                const size_t at = py * width + px;  // FrameRecord::Index
                hitU[at] = bu[i];
                hitV[at] = bv[i];
                hitDepth[at] = bDepth[i];
                nCoarse[at] = bCoarse[i];
                nRefine[at] = bRefine[i];
                nFetches[at] = fetches;
                nTexelReads[at] = bTexels[i];
                flags[at] = uint8_t(kFlagCovered | bFlags[i]);
                if (bRgb)
                    for (int c = 0; c < 3; ++c)
                        color[3 * at + size_t(c)] = bRgb[3 * i + size_t(c)];
                if (shadows) {
                    shadowFetches_[at] = s.shadowFetches[i];
                    visibility_[at] = s.visibility[i];
                }
                if (ambient) ambient_[at] = s.ambient[i];
            }
            // A lane leaves the loop for good, so a group runs as many trips as its
            // longest-running covered lane.
            quadCost += 4 * uint64_t(quadTrips);
            const int lx = quad.pixel0.x - tileX0, ly = quad.pixel0.y - tileY0;
            uint32_t& g = s.group4x2[size_t((ly / 2) * (kTileSize / 4) + lx / 4)];
            uint32_t& w = s.warp32[size_t((ly / 4) * (kTileSize / 8) + lx / 8)];
            uint32_t& v = s.wave64[size_t((ly / 8) * (kTileSize / 8) + lx / 8)];
            g = std::max(g, quadTrips);
            w = std::max(w, quadTrips);
            v = std::max(v, quadTrips);
        }
        tile.helperLanes += helperLanes;
        tile.helperFetches += helperFetches;
        tile.helperTexelReads += helperTexelReads;
        tile.laneCost.quad += quadCost;
        s.quads.clear();
    }

    const BatchJob& job_;
    BatchFn run_;
    FrameRecord& record_;
    std::vector<float>& color_;
    std::vector<TileTotals>& tiles_;
    std::vector<uint32_t>& shadowFetches_;
    std::vector<float>& visibility_;
    std::vector<float>& ambient_;
    tbb::enumerable_thread_specific<Scratch> scratch_;
};

}  // namespace

RenderOutput Render(const DepthField& field, const RenderSettings& s) {
    ValidateSettings(s);
    ValidateDepthField(field);
    RenderOutput out;
    const LaneWidthInfo& lanes = PickLaneWidth(s.lanes);
    std::shared_ptr<const void> params;
    BatchJob job;
    BatchFn run = lanes.fn;
    std::unique_ptr<const ExactSurface> exact;
    if (s.method == kExactMethod) {
        exact = std::make_unique<const ExactSurface>(field, s.sampler.wrap);
        job.textures = BindTextures(field, s.sampler);  // for the shading
        job.params = exact.get();
        run = &RunExactBatch;
    } else {
        const Kernel kernel = SettingsKernel(s);
        out.params = kernel.values;
        job = MakeBatchJob(kernel, BindKernelTextures(field, s.sampler, kernel, s.maps),
                           params);
    }

    std::unique_ptr<tbb::global_control> limit;
    if (s.threads > 0)
        limit = std::make_unique<tbb::global_control>(
            tbb::global_control::max_allowed_parallelism, size_t(s.threads));
    out.lanes = exact ? 1 : lanes.width;
    out.isa = exact ? "exact (double, one lane)" : lanes.isa;
    out.threads = int(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

    out.record.Resize(s.width, s.height);
    if (s.shade)
        out.color.assign(size_t(s.width) * size_t(s.height) * 3, 0.0f);
    else
        out.color.clear();
    std::vector<TileTotals> tiles(size_t(TileCount(s.width, s.height)));
    const ViewUniforms uniforms = MakeViewUniforms(s);
    const Camera camera = SceneCamera(s);
    const Mesh mesh = MakePlane(s.tiling);
    job.view = &uniforms;
    job.slopeScale = SceneSlopeScale(s);
    job.light = SceneLight(s);
    job.shadow = SceneShadow(s);

    auto start = std::chrono::steady_clock::now();
    if (job.shadow.Any()) {
        out.shadowFetches.assign(size_t(s.width) * size_t(s.height), 0u);
        out.visibility.assign(size_t(s.width) * size_t(s.height), 0.0f);
    }
    if (s.ao != AoKind::None)
        out.ambient.assign(size_t(s.width) * size_t(s.height), 0.0f);
    FrameProgram program(job, run, out.record, out.color, tiles, out.shadowFetches,
                         out.visibility, out.ambient);
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
    // The dissertation's error of every pixel, in parallel (a sampler call each); the
    // summary sums them in pixel order.
    std::vector<float> paperErrors(out.record.flags.size());
    tbb::parallel_for(tbb::blocked_range<int>(0, s.height, 16),
                      [&](const tbb::blocked_range<int>& rows) {
                          for (int y = rows.begin(); y < rows.end(); ++y)
                              for (int x = 0; x < s.width; ++x) {
                                  const size_t i = out.record.Index(x, y);
                                  paperErrors[i] =
                                      PaperError(out.record, i, field, s.sampler);
                              }
                      });
    out.summary = Summarize(out.record, paperErrors);
    if (s.reference) {
        out.hasReference = true;
        out.reference = RenderReference(field, s, out.record);
        out.referenceSummary = SummarizeAgainstReference(
            out.record, out.color, out.reference, field.width, field.height);
    }
    return out;
}

}  // namespace reliefsim
