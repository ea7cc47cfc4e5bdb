// `reliefsim maps`: generate (or load) a derived map, print and write its statistics
// (#3).
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/enum_option.h"
#include "app/render_options.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/output_set.h"
#include "maps/cone_map.h"
#include "maps/cone_map_bilinear.h"
#include "maps/map_cache.h"
#include "maps/mip_pyramid.h"

namespace reliefsim {

namespace {

/// --external-channel: a channel index of the external map, or -1 for all four.
constexpr int kAllChannels = -1;
constexpr auto kExternalChannelNames = MakeEnumNames<int>({
    {"R", 0},
    {"G", 1},
    {"B", 2},
    {"A", 3},
    {"all", kAllChannels},
});

struct MapsOptions {
    MapOptions map;
    ConeKind kind = ConeKind::Cone;
    ConeEncoding encoding = ConeEncoding::Float;
    std::string out;
    std::string cacheDir;
    std::string external;
    int externalChannel = 2;  ///< B, where GPU Gems 3 keeps its cone ratios
    bool adaptive = false;
    bool safety = false;
    ConeBounds bounds = ConeBounds::Texel;
    bool relaxed = false;
    bool normal = false;
    float threshold = 0.25f;
    int levels = 3;
    int searchSteps = 128;
    int stackedCount = 4;
    int animate = 0;
    int bins = 32;
    const CLI::App* command = nullptr;  ///< to ask which options were given
    bool Given(const char* option) const { return command && command->count(option) > 0; }
};

/// Refuses options that have no effect in this combination, naming both (a silently
/// ignored option misleads: the user believes it was applied).
void CheckCombinations(const MapsOptions& o, ConeKind kind) {
    const std::string k = "--kind " + std::string(ToString(kind));
    auto refuse = [](const std::string& option, const std::string& why) {
        throw Error(option + ": " + why);
    };
    const bool mip = kind == ConeKind::MinMip || kind == ConeKind::MaxMip;
    const bool sectorKind = kind == ConeKind::Cone || kind == ConeKind::Quad ||
                            kind == ConeKind::Acm4 || kind == ConeKind::Acm8;
    if (mip) {
        for (const char* opt :
             {"--encoding", "--adaptive", "--threshold", "--levels", "--search-steps",
              "--stacked-count", "--relaxed", "--normal", "--safety", "--external",
              "--external-channel", "--cache-dir", "--animate", "--bins",
              "--cone-bounds"})
            if (o.Given(opt))
                refuse(opt, "does not apply to " + k +
                                " (a pyramid of depths, written as one MIP-mapped file)");
    }
    if (o.Given("--animate")) {
        if (!sectorKind)
            refuse("--animate",
                   "needs --kind cone, quad, acm4 or acm8 (adaptive "
                   "preprocessing, 000 Algorithm 1), not " +
                       k);
        for (const char* opt :
             {"--out", "--cache-dir", "--external", "--external-channel", "--safety",
              "--encoding", "--search-steps", "--stacked-count", "--relaxed", "--normal",
              "--bins", "--cone-bounds"})
            if (o.Given(opt))
                refuse(opt,
                       "does not apply with --animate (frames are regenerated and timed, "
                       "not written)");
    }
    if (o.bounds == ConeBounds::Bilinear) {
        if (!HasBilinearBounds(kind))
            refuse("--cone-bounds bilinear",
                   "applies to --kind cone, cone-normal, quad, acm4 and acm8 only, not " +
                       k);
        for (const char* opt : {"--adaptive", "--relaxed", "--external", "--safety"})
            if (o.Given(opt))
                refuse(opt,
                       "does not apply with --cone-bounds bilinear (the exact "
                       "conservative maps of the bilinear surface)");
    }
    if (o.adaptive && !sectorKind)
        refuse("--adaptive",
               "applies to --kind cone, quad, acm4 and acm8 only, not " + k);
    for (const char* opt : {"--threshold", "--levels"})
        if (o.Given(opt) && !o.adaptive && !o.Given("--animate"))
            refuse(opt, "applies only with --adaptive (or --animate)");
    const bool relaxedSearch =
        kind == ConeKind::Relaxed ||
        ((kind == ConeKind::ConeNormal || kind == ConeKind::Stacked) && o.relaxed);
    if (o.Given("--search-steps") && !relaxedSearch)
        refuse("--search-steps",
               "applies to --kind relaxed (and cone-normal or stacked with "
               "--relaxed) only, not " +
                   k);
    if (o.Given("--stacked-count") && kind != ConeKind::Stacked)
        refuse("--stacked-count", "applies to --kind stacked only, not " + k);
    if (o.Given("--normal") && kind != ConeKind::Stacked)
        refuse("--normal", "applies to --kind stacked only, not " + k +
                               " (--kind cone-normal stores n_z of one cone)");
    if (o.Given("--external-channel") && o.external.empty())
        refuse("--external-channel", "applies only with --external");
    if (!o.external.empty()) {
        for (const char* opt :
             {"--cache-dir", "--adaptive", "--threshold", "--levels", "--search-steps",
              "--stacked-count", "--relaxed", "--normal"})
            if (o.Given(opt))
                refuse(opt,
                       "does not apply with --external (the map is read, not generated)");
        const bool all = o.externalChannel == kAllChannels;
        const bool oneChannel = kind == ConeKind::Cone || kind == ConeKind::Relaxed ||
                                kind == ConeKind::RelaxedExact ||
                                kind == ConeKind::ConeNormal;
        const bool manyChannels =
            kind == ConeKind::Quad || kind == ConeKind::Acm4 || kind == ConeKind::Acm8;
        if (!oneChannel && !manyChannels)
            refuse("--external", k + " cannot be read from an image (only cone, relaxed, "
                                     "relaxed-exact, cone-normal, quad, acm4 and acm8)");
        if (oneChannel && all)
            refuse("--external-channel all", k + " has one channel; pick R, G, B or A");
        if (manyChannels && !all)
            refuse(
                "--external-channel " +
                    std::string(kExternalChannelNames.Name(o.externalChannel)),
                k + (kind == ConeKind::Acm8
                         ? " has eight channels; use --external-channel all (8 channels, "
                           "or two RGBA halves side by side)"
                         : " has four channels; use --external-channel all (R, G, B, "
                           "A)"));
    }
}

void Status(const char* msg) {
    if (::isatty(2)) std::fprintf(stderr, "\r[maps] %-60s", msg);
}
/// The progress bar on stderr, "[maps] generating  42% [########    ]" (installed only
/// when stderr is a terminal).
void ProgressBar(double fraction) {
    const int width = 30, filled = int(fraction * width + 0.5);
    std::fprintf(stderr, "\r[maps] generating %3d%% [%s%s]", int(fraction * 100 + 0.5),
                 std::string(size_t(filled), '#').c_str(),
                 std::string(size_t(width - filled), ' ').c_str());
    std::fflush(stderr);
}
void StatusDone() {
    if (::isatty(2)) std::fprintf(stderr, "\r[maps] %-60s\n", "done");
}

std::string StatsPath(const std::string& out) {
    std::filesystem::path p(out);
    return (p.parent_path() / (p.stem().string() + ".stats.json")).string();
}

void PrintStats(const ConeMap& m, const ConeMapStats& s) {
    std::printf(
        "%s %dx%d x%d: min %.6g  mean %.6g  max %.6g  (%lld values, %lld unbounded)\n",
        std::string(ToString(m.kind)).c_str(), m.width, m.height, m.channels, s.minRatio,
        s.meanRatio, s.maxRatio, static_cast<long long>(s.nValues),
        static_cast<long long>(s.nUnbounded));
    const double nb = double(s.histogram.size());
    int64_t peak = 1;
    for (int64_t c : s.histogram) peak = std::max(peak, c);
    for (size_t b = 0; b < s.histogram.size(); ++b) {
        const int bar = int(40.0 * double(s.histogram[b]) / double(peak));
        std::printf("  [%.3f,%.3f%c %9lld %s\n", double(b) / nb, double(b + 1) / nb,
                    b + 1 == s.histogram.size() ? ']' : ')',
                    static_cast<long long>(s.histogram[b]),
                    std::string(size_t(bar), '#').c_str());
    }
}

void Run(const MapsOptions& o) {
    // Validate everything before any work or output.
    const ConeKind kind = o.kind;
    // A PNG holds 8-bit codes: u8 (or u8sqrt when asked), so that the statistics (and
    // the cache) describe what is written; float and u16 need an EXR.
    const bool mipKind = kind == ConeKind::MinMip || kind == ConeKind::MaxMip;
    if (!o.out.empty() && mipKind) {
        try {
            CheckMipPyramidPath(o.out);  // one MIP-mapped file: .exr only
        } catch (const Error& e) {
            throw Error("--out " + std::string(e.what()));
        }
    }
    const bool png = !o.out.empty() && !mipKind &&
                     ConeMapFormatOf(o.out) == ConeMapFormat::Png;  // throws: others
    if (png && o.Given("--encoding") && o.encoding != ConeEncoding::U8 &&
        o.encoding != ConeEncoding::U8Sqrt)
        throw Error("--encoding " + std::string(ToString(o.encoding)) + ": --out \"" +
                    o.out +
                    "\" is a PNG, which holds 8-bit codes (u8 or u8sqrt); use .exr");
    const ConeEncoding enc =
        png && !o.Given("--encoding") ? ConeEncoding::U8 : o.encoding;
    if (o.animate < 0 || o.animate > 100000)
        throw Error("--animate " + std::to_string(o.animate) +
                    ": expected 0..100000 frames");
    if (o.bins < 1 || o.bins > 4096) throw Error("--bins: expected 1..4096");
    CheckCombinations(o, kind);
    ConeMapParams p;
    p.searchSteps = o.searchSteps;
    p.stackedCount = o.stackedCount;
    p.relaxed = o.relaxed;
    p.normal = o.normal;
    p.adaptive = o.adaptive;
    p.threshold = o.threshold;
    p.adaptiveLevels = o.levels;
    if (::isatty(2)) p.progress = ProgressBar;
    ValidateConeMapParams(p);
    if (o.relaxed && kind != ConeKind::ConeNormal && kind != ConeKind::Stacked)
        throw Error(
            "--relaxed: applies to --kind cone-normal and stacked only (for plain "
            "relaxed "
            "cones use --kind relaxed)");
    if (!o.cacheDir.empty()) {
        std::error_code ec;
        const auto st = std::filesystem::status(o.cacheDir, ec);
        if (std::filesystem::exists(st) && !std::filesystem::is_directory(st))
            throw Error("--cache-dir \"" + o.cacheDir +
                        "\": exists and is not a directory");
    }
    if (!o.out.empty()) {
        CheckOutputFile("--out", o.out);
        CheckOutputDestination(StatsPath(o.out),
                               "--out \"" + o.out + "\" (its statistics)");
    }
    if (png && kind != ConeKind::Acm8 && ChannelCount(kind, p) > 4)
        throw Error("--out \"" + o.out + "\": " + std::string(ToString(kind)) + " has " +
                    std::to_string(ChannelCount(kind, p)) +
                    " channels, more than a PNG holds; use .exr");

    if (o.animate > 0) {
        const ConeKind k =
            (kind == ConeKind::Cone || kind == ConeKind::Quad || kind == ConeKind::Acm8)
                ? kind
                : ConeKind::Acm4;
        const DepthField first = LoadMapFromOptions(o.map);
        const int W = first.width, H = first.height;
        // Buffers live across frames, as a renderer would keep them: after frame 0 (which
        // allocates, page-faults the buffers in and starts the TBB workers) a frame
        // allocates nothing, so the steady-state times are the preprocessing cost itself.
        AdaptiveWorkspace ws;
        DepthField hf;
        ConeMap m;
        double sum = 0, worst = 0, first0 = 0;
        for (int f = 0; f < o.animate; ++f) {
            const auto t0 = std::chrono::steady_clock::now();
            FillSinusoidMap(hf, W, H, float(f) / 30.0f);
            GenerateAdaptiveSectorMap(hf, k, o.threshold, o.levels, ws, m);
            const double ms = std::chrono::duration<double, std::milli>(
                                  std::chrono::steady_clock::now() - t0)
                                  .count();
            if (f == 0)
                first0 = ms;
            else {
                sum += ms;
                worst = std::max(worst, ms);
            }
            std::printf("frame %d: %.3f ms (%s %dx%d, regenerate + adaptive%s)\n", f, ms,
                        std::string(ToString(k)).c_str(), m.width, m.height,
                        f == 0 ? ", warm-up" : "");
        }
        if (o.animate > 1)
            std::printf(
                "animate: %d frames, mean %.3f ms, max %.3f ms per frame after the first "
                "(first %.3f ms, warm-up)\n",
                o.animate, sum / (o.animate - 1), worst, first0);
        else
            std::printf("animate: 1 frame, %.3f ms (warm-up included)\n", first0);
        return;
    }

    const DepthField hf = LoadMapFromOptions(o.map);
    // The generators keep a few float planes and search windows per texel (measured peak
    // RSS: relaxed ~370 bytes per texel above the base, other kinds less).
    RequireMemory((64ull << 20) + uint64_t(hf.width) * uint64_t(hf.height) *
                                      (400 + 8 * uint64_t(ChannelCount(kind, p))),
                  "--map " + hf.name + " (" + std::to_string(hf.width) + "x" +
                      std::to_string(hf.height) + ", --kind " +
                      std::string(ToString(o.kind)) + ")",
                  "use a smaller map");
    if (kind == ConeKind::MinMip || kind == ConeKind::MaxMip) {
        // maxmip: max height = min depth; minmip: min height = max depth.
        const auto levels =
            BuildMipPyramid(hf.depth, hf.width, hf.height, 1,
                            kind == ConeKind::MaxMip ? MipReduce::Min : MipReduce::Max);
        for (size_t l = 0; l < levels.size(); ++l)
            std::printf("level %zu: %dx%d\n", l, levels[l].width, levels[l].height);
        if (!o.out.empty()) {
            // One MIP-mapped file with every level, created (with any missing folder)
            // only once it is complete.
            try {
                CheckMipPyramidPath(o.out);
            } catch (const Error& e) {
                throw Error("--out " + std::string(e.what()));
            }
            OutputSet outputs("--out \"" + o.out + "\"");
            WriteMipPyramidFile(o.out, levels, ToString(kind), &outputs);
            outputs.Commit();
            std::printf("wrote %s (%zu MIP levels)\n", o.out.c_str(), levels.size());
        }
        return;
    }

    const auto generate = [&] {
        return o.bounds == ConeBounds::Bilinear ? GenerateBilinearConeMap(hf, kind, p)
                                                : GenerateConeMap(hf, kind, p);
    };
    ConeMap m;
    Status("generating");
    if (!o.external.empty()) {
        m = LoadExternalConeMap(o.external, kind, o.externalChannel, hf.width, hf.height);
    } else if (!o.cacheDir.empty()) {
        bool hit = false;
        m = MapCache(o.cacheDir)
                .GetOrCreate(
                    hf, kind, p, [&] { return generate(); }, &hit, o.bounds);
        std::printf("cache: %s\n", hit ? "hit" : "miss (generated and stored)");
    } else {
        m = generate();
    }
    if (o.safety) m = BilinearSafetyPass(m);
    // The map as stored, quantised once for the statistics and the writer (a float map
    // is not copied: fresh pages cost this host's VM 3-7 ms per MB, docs/cone_maps.md).
    ConeMap scratch;
    const ConeMap& stored = StoredConeMap(m, enc, scratch);
    StatusDone();
    const ConeMapStats s = ComputeConeMapStats(stored, o.bins);
    PrintStats(stored, s);
    if (!o.out.empty()) {
        // The map and its statistics replace what was there together or not at all; a
        // missing folder is created only then.
        OutputSet outputs("--out \"" + o.out + "\"");
        outputs.Add(o.out);
        outputs.Add(StatsPath(o.out));  // both destinations checked before any writing
        WriteConeMap(o.out, m, enc, &outputs, &stored);
        nlohmann::json stats = nlohmann::json::parse(ConeMapStatsJson(stored, s, enc));
        stats["cone_bounds"] = std::string(kConeBoundsNames.Name(o.bounds));
        outputs.Write(StatsPath(o.out), stats.dump(2) + "\n");
        outputs.Commit();
        std::printf("wrote %s and %s\n", o.out.c_str(), StatsPath(o.out).c_str());
    }
}

}  // namespace

void RegisterMapsCommand(CLI::App& root) {
    auto o = std::make_shared<MapsOptions>();
    auto* cmd = root.add_subcommand(
        "maps",
        "generate a derived map (cone family, mip pyramids), print and write statistics");
    AddMapOptions(cmd, o->map);
    AddEnumOption(cmd, "--kind", o->kind, kConeKindNames,
                  "the derived map (docs/cone_maps.md)");
    AddEnumOption(cmd, "--encoding", o->encoding, kConeEncodingNames,
                  "how ratios are stored (quantisation rounds toward smaller ratios)");
    cmd->add_flag(
        "--adaptive", o->adaptive,
        "adaptive hierarchical preprocessing (000 Algorithm 1; cone, quad, acm4, acm8)");
    cmd->add_option("--threshold", o->threshold,
                    "adaptive: copy the parent's ratio when depths differ by <= this")
        ->capture_default_str();
    cmd->add_option("--levels", o->levels, "adaptive: hierarchy levels above the finest")
        ->capture_default_str();
    cmd->add_option("--search-steps", o->searchSteps,
                    "relaxed: Listing 18-2 search steps")
        ->capture_default_str();
    cmd->add_option("--stacked-count", o->stackedCount, "stacked: number of cones")
        ->capture_default_str();
    cmd->add_flag(
        "--relaxed", o->relaxed,
        "cone-normal, stacked: relaxed cones (Listing 18-2) instead of conservative");
    cmd->add_flag("--normal", o->normal,
                  "stacked: store n_z = r / sqrt(1 + r^2) of each cone (mcns) instead of "
                  "its ratio");
    cmd->add_flag("--safety", o->safety, "3x3-minimum bilinear safety pass (Ban et al.)");
    AddEnumOption(cmd, "--cone-bounds", o->bounds, kConeBoundsNames,
                  "the surface the cones bound: texel centres (the papers) or the "
                  "bilinear surface between them (cone, cone-normal, quad, acm4, acm8)");
    cmd->add_option("--out", o->out,
                    "output: .exr (float, one channel per ratio) or .png (8-bit)");
    cmd->add_option("--cache-dir", o->cacheDir,
                    "disk cache of generated maps (content-hash keys)");
    cmd->add_option("--external", o->external,
                    "use a cone map made elsewhere (e.g. GPU Gems 3 *_cone.tga) instead "
                    "of generating");
    AddEnumOption(cmd, "--external-channel", o->externalChannel, kExternalChannelNames,
                  "the channel of --external holding the ratios (GPU Gems 3 maps: B), "
                  "or all four");
    cmd->add_option(
        "--animate", o->animate,
        "N frames of the dynamic sinusoid map at the --map size, regenerated and "
        "preprocessed with adaptive ACM each frame; prints per-frame times");
    cmd->add_option("--bins", o->bins, "histogram bins over [0,1]")
        ->capture_default_str();
    o->command = cmd;
    cmd->callback([o] { Run(*o); });
}

}  // namespace reliefsim
