// The output files of a frame: metrics.json and the images and record of
// WriteRenderOutputs.
#include "render/outputs.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/error.h"
#include "core/output_set.h"
#include "core/param_name.h"
#include "metrics/heatmap.h"
#include "metrics/lane_groups.h"
#include "raster/viewport_pieces.h"

namespace reliefsim {

namespace fs = std::filesystem;

namespace {

// A float setting as the shortest decimal that round-trips (0.1f prints as 0.1, not
// 0.10000000149011612), so metrics.json reads like the command line that made it.
double ShortestDouble(float f) {
    char buf[32];
    auto res = std::to_chars(buf, buf + sizeof buf, f);
    return std::strtod(std::string(buf, res.ptr).c_str(), nullptr);
}

}  // namespace

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
    j["camera"] = std::string(kCameraNames.Name(s.camera));
    if (s.camera == CameraKind::Ortho)
        j["view_dir"] = {ShortestDouble(s.viewDir.x), ShortestDouble(s.viewDir.y),
                         ShortestDouble(s.viewDir.z)};
    j["light_dir"] = {ShortestDouble(s.lightDir.x), ShortestDouble(s.lightDir.y),
                      ShortestDouble(s.lightDir.z)};
    j["shadow"] = std::string(kShadowNames.Name(s.shadow));
    if (s.shadow == ShadowKind::Hard) j["shadow_steps"] = s.shadowSteps;
    if (s.shadow == ShadowKind::Soft)
        j["shadow_softening"] = ShortestDouble(s.shadowSoftening);
    if (s.shadow == ShadowKind::Cone) {
        j["shadow_steps"] = s.shadowSteps;
        j["shadow_penumbra"] = ShortestDouble(s.shadowPenumbra);
    }
    j["view_angle"] = ShortestDouble(s.viewAngle);
    j["azimuth"] = ShortestDouble(s.azimuth);
    j["distance"] = ShortestDouble(s.distance);
    j["fov"] = ShortestDouble(s.fovY);
    j["depth_scale"] = ShortestDouble(s.depthScale);
    j["tiling"] = ShortestDouble(s.tiling);
    j["filter"] = std::string(ToString(s.sampler.filter));
    j["wrap"] = std::string(ToString(s.sampler.wrap));
    if (s.method != kExactMethod && !FindMethod(s.method).maps.empty())
        j["cone_bounds"] = std::string(kConeBoundsNames.Name(s.maps.bounds));
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
    {
        // The light rays' fetches, counted apart from the view rays' (0 without shadows),
        // and the mean light visibility of the covered pixels that hit.
        // The pixels with an answer (lit and shaded): those that hit, and every covered
        // pixel of a kernel that answers where it stopped (KernelInfo::answersAtStop).
        const bool answersAtStop =
            s.method != kExactMethod && FindMethod(s.method).answersAtStop;
        const auto answered = [&](size_t i) {
            return out.record.Covered(i) &&
                   (answersAtStop || !(out.record.flags[i] & kFlagNoHit));
        };
        uint64_t total = 0, maxFetches = 0, lit = 0;
        double visibility = 0.0;
        for (size_t i = 0; i < out.shadowFetches.size(); ++i) {
            if (!out.record.Covered(i)) continue;
            total += out.shadowFetches[i];
            maxFetches = std::max<uint64_t>(maxFetches, out.shadowFetches[i]);
            if (!answered(i)) continue;
            visibility += double(out.visibility[i]);
            ++lit;
        }
        j["avg_shadow_fetches"] =
            m.coveredPixels ? double(total) / double(m.coveredPixels) : 0.0;
        if (!out.shadowFetches.empty()) {
            j["total_shadow_fetches"] = total;
            j["max_shadow_fetches"] = maxFetches;
            j["avg_light_visibility"] = lit ? visibility / double(lit) : 1.0;
        }
        j["ao"] = std::string(kAoNames.Name(s.ao));
        if (!out.ambient.empty()) {
            // The mean ambient occlusion factor of the pixels with an answer.
            double ambient = 0.0;
            uint64_t hits = 0;
            for (size_t i = 0; i < out.ambient.size(); ++i) {
                if (!answered(i)) continue;
                ambient += double(out.ambient[i]);
                ++hits;
            }
            j["avg_ambient_occlusion"] = hits ? ambient / double(hits) : 1.0;
        }
    }
    j["lane_fetches_4x2"] = m.laneFetches4x2;
    j["lane_fetches_8x4"] = m.laneFetches8x4;
    j["heatmap_scale"] = {
        {"iterations", {ShortestDouble(s.iterScaleMin), ShortestDouble(s.iterScaleMax)}},
        {"fetches", {ShortestDouble(s.fetchScaleMin), ShortestDouble(s.fetchScaleMax)}}};
    j["lane_cost_quad"] = out.laneCost.quad;
    j["lane_cost_4x2"] = out.laneCost.group4x2;
    j["lane_cost_warp32"] = out.laneCost.warp32;
    j["lane_cost_wave64"] = out.laneCost.wave64;
    // The share of the lane-trips a group pays that do a covered pixel's work.
    auto utilisation = [&](uint64_t cost) {
        return cost == 0 ? nlohmann::json(nullptr)
                         : nlohmann::json(double(m.totalFetches) / double(cost));
    };
    j["lane_utilisation_quad"] = utilisation(out.laneCost.quad);
    j["lane_utilisation_4x2"] = utilisation(out.laneCost.group4x2);
    j["lane_utilisation_warp32"] = utilisation(out.laneCost.warp32);
    j["lane_utilisation_wave64"] = utilisation(out.laneCost.wave64);
    j["reference"] = out.hasReference;
    if (out.hasReference) {
        const ReferenceSummary& r = out.referenceSummary;
        j["mse_exact_depth"] = r.mseExactDepth;
        j["depth_error_mean"] = r.depthErrorMean;
        j["depth_error_max_abs"] = r.depthErrorMaxAbs;
        j["uv_error_texels_mean"] = r.uvErrorTexelsMean;
        j["uv_error_texels_max"] = r.uvErrorTexelsMax;
        j["missed_geometry_pixels"] = r.missedGeometryPixels;
        j["past_first_hit_pixels"] = r.pastFirstHitPixels;
        j["past_first_hit_share"] = r.pastFirstHitShare;
        // Equal colours give an infinite PSNR, which JSON cannot hold: null.
        j["psnr_color"] = std::isfinite(r.psnrColor) ? nlohmann::json(r.psnrColor)
                                                     : nlohmann::json(nullptr);
    }
    j["timing"] = {{"frame_seconds", out.frameSeconds},
                   {"threads", out.threads},
                   {"lanes", out.lanes},
                   {"isa", out.isa}};
    if (out.hasReference) j["timing"]["reference_seconds"] = out.reference.seconds;
    return j;
}

void WriteRenderOutputs(const std::string& outDir, const RenderOutput& out,
                        const RenderSettings& s, const DepthField& field,
                        bool allLaneGroups) {
    if (outDir.empty()) throw Error(ParamName("out") + ": empty; give a directory");
    if (out.color.empty())
        throw Error(ParamName("shade") + ": off; color.png needs the shaded frame");
    const fs::path dir(outDir);
    std::error_code ec;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
        throw Error(ParamName("out") + " \"" + outDir +
                    "\": exists and is not a directory");
    // All five files are staged as temporaries beside their destinations (or in the
    // nearest existing ancestor while the folder does not exist) and replace what was
    // there only once every one is complete, all or nothing (core/output_set.h). Every
    // destination is checked before anything is written.
    OutputSet outputs(ParamName("out") + " \"" + outDir + "\"");
    auto dest = [&](const char* name) { return (dir / name).string(); };
    for (const char* name : {"color.png", "iterations.png", "fetches.png", "record.exr",
                             "metrics.json", "warp_trips.png", "warp_utilisation.png"})
        outputs.Add(dest(name));
    if (out.hasReference) outputs.Add(dest("missed_geometry.png"));
    const bool shadows = !out.shadowFetches.empty();
    if (shadows) outputs.Add(dest("shadow_fetches.png"));
    if (allLaneGroups)
        for (const LaneGroupHeatmap& g : kLaneGroupHeatmaps) {
            outputs.Add(dest((std::string(g.prefix) + "_trips.png").c_str()));
            outputs.Add(dest((std::string(g.prefix) + "_utilisation.png").c_str()));
        }
    const FrameRecord& r = out.record;
    const int w = r.width, h = r.height;
    const size_t n = size_t(w) * size_t(h);
    std::vector<uint8_t> mask(n);
    std::vector<float> iters(n), fetches(n), err(n);
    std::vector<uint32_t> coarse(n), refine(n), iterCounts(n), flags(n);
    for (size_t i = 0; i < n; ++i) {
        mask[i] = r.Covered(i) ? 1 : 0;
        coarse[i] = r.nCoarse[i];
        refine[i] = r.nRefine[i];
        iterCounts[i] = uint32_t(r.nCoarse[i]) + r.nRefine[i];
        iters[i] = float(iterCounts[i]);
        fetches[i] = float(r.nFetches[i]);
        flags[i] = r.flags[i];
        err[i] = PaperError(r, i, field, s.sampler);
    }
    // The 32-lane warps (8x4) of the frame, split by triangle as the driver executes
    // them.
    const Camera camera = SceneCamera(s);
    const std::vector<int32_t> piece = PiecePerPixel(MakePlane(s.tiling), camera, w, h);
    const LaneGroupMap warps = LaneGroups(r, piece, 8, 4);
    WriteHeatmapPng(dest("warp_trips.png"), warps.trips.data(), mask.data(), w, h,
                    {s.fetchScaleMin, s.fetchScaleMax, "inferno",
                     "trips of the pixel's 8x4 warp, " + s.method},
                    &outputs);
    WriteHeatmapPng(dest("warp_utilisation.png"), warps.utilisation.data(), mask.data(),
                    w, h, {0.0f, 1.0f, "viridis", "lane utilisation of the 8x4 warp"},
                    &outputs);
    if (allLaneGroups)
        for (const LaneGroupHeatmap& g : kLaneGroupHeatmaps) {
            const LaneGroupMap m = LaneGroups(r, piece, g.width, g.height);
            const std::string prefix = g.prefix;
            WriteHeatmapPng(
                dest((prefix + "_trips.png").c_str()), m.trips.data(), mask.data(), w, h,
                {s.fetchScaleMin, s.fetchScaleMax, "inferno",
                 std::string("trips of the pixel's ") + g.what + ", " + s.method},
                &outputs);
            WriteHeatmapPng(
                dest((prefix + "_utilisation.png").c_str()), m.utilisation.data(),
                mask.data(), w, h,
                {0.0f, 1.0f, "viridis", std::string("lane utilisation of the ") + g.what},
                &outputs);
        }
    WriteColorPng(dest("color.png"), out.color.data(), w, h, &outputs);
    WriteHeatmapPng(dest("iterations.png"), iters.data(), mask.data(), w, h,
                    {s.iterScaleMin, s.iterScaleMax, "inferno",
                     "iterations (coarse + refine), " + s.method},
                    &outputs);
    WriteHeatmapPng(dest("fetches.png"), fetches.data(), mask.data(), w, h,
                    {s.fetchScaleMin, s.fetchScaleMax, "inferno", "fetches, " + s.method},
                    &outputs);
    // Counts as 32-bit UINT channels, values as FLOAT (issue: exact counts at any size).
    std::vector<ExrChannel> channels = {{"hit_u", r.hitU.data(), nullptr},
                                        {"hit_v", r.hitV.data(), nullptr},
                                        {"hit_depth", r.hitDepth.data(), nullptr},
                                        {"coarse_iterations", nullptr, coarse.data()},
                                        {"refine_iterations", nullptr, refine.data()},
                                        {"iterations", nullptr, iterCounts.data()},
                                        {"fetches", nullptr, r.nFetches.data()},
                                        {"texel_reads", nullptr, r.nTexelReads.data()},
                                        {"flags", nullptr, flags.data()},
                                        {"error_paper", err.data(), nullptr}};
    std::vector<float> shadowHeat;
    if (shadows) {
        channels.push_back({"shadow_fetches", nullptr, out.shadowFetches.data()});
        channels.push_back({"light_visibility", out.visibility.data(), nullptr});
        if (!out.ambient.empty())
            channels.push_back({"ambient_occlusion", out.ambient.data(), nullptr});
        shadowHeat.assign(out.shadowFetches.begin(), out.shadowFetches.end());
        WriteHeatmapPng(
            dest("shadow_fetches.png"), shadowHeat.data(), mask.data(), w, h,
            {s.fetchScaleMin, s.fetchScaleMax, "inferno",
             "light-ray fetches, " +
                 (s.shadow != ShadowKind::None
                      ? std::string(kShadowNames.Name(s.shadow)) +
                            (s.ao != AoKind::None ? " shadows and AO" : " shadows")
                      : std::string("AO"))},
            &outputs);
    }
    std::vector<float> depthError, uvError, missedRgb;
    std::vector<uint32_t> missed;
    if (out.hasReference) {
        const ReferenceRecord& ref = out.reference;
        depthError.assign(n, 0.0f), uvError.assign(n, 0.0f), missed.assign(n, 0);
        missedRgb.assign(3 * n, 0.0f);
        for (size_t i = 0; i < n; ++i) {
            if (!mask[i]) continue;
            depthError[i] = r.hitDepth[i] - ref.depth[i];
            uvError[i] = float(UvErrorTexels(double(r.hitU[i]) - double(ref.u[i]),
                                             double(r.hitV[i]) - double(ref.v[i]),
                                             field.width, field.height));
            missed[i] = ref.missed[i];
            // The mask: white where geometry was missed, grey elsewhere on the plane.
            const float shade = ref.missed[i] ? 1.0f : 0.25f;
            for (size_t c = 0; c < 3; ++c) missedRgb[3 * i + c] = shade;
        }
        channels.insert(channels.end(), {{"ref_u", ref.u.data(), nullptr},
                                         {"ref_v", ref.v.data(), nullptr},
                                         {"ref_depth", ref.depth.data(), nullptr},
                                         {"depth_error", depthError.data(), nullptr},
                                         {"uv_error_texels", uvError.data(), nullptr},
                                         {"missed_geometry", nullptr, missed.data()}});
        WriteColorPng(dest("missed_geometry.png"), missedRgb.data(), w, h, &outputs);
    }
    WriteMultiChannelExr(dest("record.exr"), w, h, channels, &outputs);
    outputs.Write(dest("metrics.json"), MetricsJson(out, s, field).dump(2) + "\n");
    outputs.Commit();
}

}  // namespace reliefsim
