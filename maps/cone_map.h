// Cone maps and their relatives (issue #3): conservative, relaxed, n-sector, adaptive,
// cone-normal and stacked cones, each with a brute-force oracle and a fast generator
// equal to it bit for bit.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/enum_names.h"
#include "texture/depth_field.h"

namespace reliefsim {

class OutputSet;

/// Which derived map. Sector order of the multi-channel kinds is fixed
/// (docs/cone_maps.md):
///   Quad : +x, -x, +y, -y (QDCSM half planes: channel +x bounds blockers with du > 0,
///   ...) Acm4 : closed quadrants counter-clockwise from +u: [0°,90°], [90°,180°],
///   [180°,270°], [270°,360°] Acm8 : closed 45° sectors counter-clockwise from +u
///   (+u is increasing i, +v increasing j; angles are taken in uv space, so non-square
///   maps
///    get the right sectors.)
enum class ConeKind {
    Cone,     ///< conservative cone ratio (Dummer; 000 §II-A)
    Relaxed,  ///< relaxed cone, Policarpo & Oliveira Listing 18-1/18-2 (search steps)
    RelaxedExact,  ///< exact relaxed cone of Bán et al. (only limiting texels bound it)
    Quad,          ///< quad-directional cone map, 4 channels
    Acm4,          ///< anisotropic cone map, 4 sectors
    Acm8,          ///< anisotropic cone map, 8 sectors
    ConeNormal,  ///< n_z of the cone side normal (dissertation ch. 3): r / sqrt(1 + r^2)
    Stacked,     ///< K conservative cones at apex depths d*(1 - k/K) (dissertation §3.4,
                 ///< method 1)
    MinMip,      ///< min-height pyramid (stored as depth: per block max depth)
    MaxMip,      ///< max-height pyramid (stored as depth: per block min depth)
};

/// How ratios are stored. Every quantised encoding rounds toward smaller ratios (never
/// wider).
enum class ConeEncoding {
    Float,  ///< 32-bit float, unclamped up to kConeRatioCap
    U8,     ///< ratio clamped to [0,1], code = floor(255 r); decode code/255 (GPU Gems 3)
    U8Sqrt,  ///< sqrt(ratio) clamped to [0,1] in 8 bits (Dummer); decode (code/255)^2
    U16,     ///< ratio clamped to [0,1], code = floor(65535 r); decode code/65535
};

/// The names of the kinds and encodings (--kind, --encoding, cache keys, statistics).
inline constexpr auto kConeKindNames = MakeEnumNames<ConeKind>({
    {"cone", ConeKind::Cone},
    {"relaxed", ConeKind::Relaxed},
    {"relaxed-exact", ConeKind::RelaxedExact},
    {"quad", ConeKind::Quad},
    {"acm4", ConeKind::Acm4},
    {"acm8", ConeKind::Acm8},
    {"cone-normal", ConeKind::ConeNormal},
    {"stacked", ConeKind::Stacked},
    {"minmip", ConeKind::MinMip},
    {"maxmip", ConeKind::MaxMip},
});
inline constexpr auto kConeEncodingNames = MakeEnumNames<ConeEncoding>({
    {"float", ConeEncoding::Float},
    {"u8", ConeEncoding::U8},
    {"u8sqrt", ConeEncoding::U8Sqrt},
    {"u16", ConeEncoding::U16},
});

inline std::string_view ToString(ConeKind k) { return kConeKindNames.Name(k); }
inline std::string_view ToString(ConeEncoding e) { return kConeEncodingNames.Name(e); }
inline std::optional<ConeKind> ParseConeKind(std::string_view s) {
    return kConeKindNames.Parse(s);
}
inline std::optional<ConeEncoding> ParseConeEncoding(std::string_view s) {
    return kConeEncodingNames.Parse(s);
}
/// The names quoted and comma separated ("cone", "relaxed", ...), for messages.
inline std::string ConeKindList() { return kConeKindNames.QuotedList(); }
inline std::string ConeEncodingList() { return kConeEncodingNames.QuotedList(); }

/// Ratio stored where no texel of the surface lies above the apex (an unbounded cone).
/// Any value is conservative there; 1024 spans the texture a thousand times over.
constexpr float kConeRatioCap = 1024.0f;

/// Generation parameters. Defaults follow the papers.
/// Progress of a long generation: called with the fraction done in (0, 1], from any
/// worker thread but never concurrently, at most about 100 times per map and with growing
/// fractions.
using ConeMapProgress = std::function<void(double fraction)>;

struct ConeMapParams {
    int searchSteps = 128;  ///< Relaxed: Listing 18-2 search steps, in [1, 4096]
    int stackedCount = 4;   ///< Stacked: number of cones K, in [1, 16]
    bool relaxed = false;   ///< ConeNormal/Stacked: relaxed (Listing 18-2) cones instead
                            ///< of conservative
    bool normal = false;  ///< Stacked: store n_z of each cone's side normal (dissertation
                          ///< §3.1, for mcns) instead of its ratio
    bool adaptive =
        false;  ///< Quad/Acm4/Acm8/Cone: 000 Algorithm 1 (never wider than exact)
    float threshold =
        0.25f;  ///< adaptive: copy the parent's ratio when its depth range <= this
    int adaptiveLevels =
        3;  ///< adaptive: levels of hierarchy above the finest, in [0, 12]
    ConeMapProgress
        progress;  ///< optional; not part of the definition (not in cache keys)
};

/// Throws Error ("--search-steps: ...") for out-of-range parameters.
void ValidateConeMapParams(const ConeMapParams& p);

/// A derived map: W x H texels with `channels` interleaved floats each.
/// Ratio = cone radius / cone height, radius in uv and height in depth units (DESIGN.md),
/// so a map does not depend on the depth scale. Texel (i,j) is at values[(j*W +
/// i)*channels + c].
struct ConeMap {
    ConeKind kind = ConeKind::Cone;
    int width = 0, height = 0, channels = 1;
    std::vector<float> values;
    float At(int i, int j, int c = 0) const {
        return values[(size_t(j) * size_t(width) + size_t(i)) * size_t(channels) +
                      size_t(c)];
    }
};

/// Number of channels a kind produces (Stacked: params.stackedCount).
int ChannelCount(ConeKind k, const ConeMapParams& p = {});
/// EXR channel names in storage order, e.g. {"+x","-x","+y","-y"} for Quad.
std::vector<std::string> ChannelNames(ConeKind k, const ConeMapParams& p = {});

/// Generates a cone-family map (every kind except MinMip/MaxMip) with the fast generator.
/// Deterministic and bit-identical for any thread count (oneTBB inside). Throws Error on
/// bad input (empty field, NaN/Inf or out-of-range depths, bad parameters).
ConeMap GenerateConeMap(const DepthField& hf, ConeKind kind, const ConeMapParams& p = {});

/// The brute-force oracle of the same definition (every texel against every other):
/// Θ(N⁴) (Relaxed: Θ(N⁴·S)). For tests; use at most 128².
ConeMap GenerateConeMapBruteForce(const DepthField& hf, ConeKind kind,
                                  const ConeMapParams& p = {});

/// The plain ACM search of 000 §II-C (per texel and sector, rings of growing radius with
/// the current minimum as short circuit). Exact; equal to the brute force.
/// Quad/Acm4/Acm8/Cone.
ConeMap GenerateSectorMapPlainSearch(const DepthField& hf, ConeKind kind);

/// Adaptive hierarchical preprocessing (000 Algorithm 1) for Cone/Quad/Acm4/Acm8: a
/// min/max depth pyramid; block ratios are conservative bounds for every texel of the
/// block, so copying a parent's ratio is always safe; a block whose depth range exceeds
/// `threshold` is searched, with the parent's ratio as the initial short circuit. Result
/// <= exact ratio, always.
struct AdaptiveStats {
    int64_t nCopied = 0, nSearched = 0;  ///< texels (all levels) copied / searched
};
ConeMap GenerateAdaptiveSectorMap(const DepthField& hf, ConeKind kind, float threshold,
                                  int levels = 3, AdaptiveStats* stats = nullptr);

/// Buffers reused across calls (pyramid levels, sorted block offsets, output), so that a
/// map regenerated every frame (000's water demo) allocates and page-faults nothing after
/// the first frame. Not thread-safe: one workspace per caller thread.
class AdaptiveWorkspace {
  public:
    AdaptiveWorkspace();
    ~AdaptiveWorkspace();
    AdaptiveWorkspace(const AdaptiveWorkspace&) = delete;
    AdaptiveWorkspace& operator=(const AdaptiveWorkspace&) = delete;
    struct Impl;
    Impl& Get() { return *impl; }

  private:
    Impl* impl;
};

/// As above, writing into `out` (its storage is reused when the size matches). Same
/// result.
void GenerateAdaptiveSectorMap(const DepthField& hf, ConeKind kind, float threshold,
                               int levels, AdaptiveWorkspace& ws, ConeMap& out,
                               AdaptiveStats* stats = nullptr);

/// Encodes to `enc` and decodes back: the ratios a kernel sees. Codes (u8/u16) go to
/// *codes when given. Never widens: decoded <= input for every value. Float: values
/// unchanged.
ConeMap QuantizeConeMap(const ConeMap& m, ConeEncoding enc,
                        std::vector<uint16_t>* codes = nullptr);
/// The map as `enc` stores it (the ratios a kernel sees, as QuantizeConeMap gives them):
/// `m` itself for float, without a copy (a float acm8 map at 1024² is 32 MB), else the
/// quantised map, built in `scratch`. The result refers to `m` or to `scratch`.
const ConeMap& StoredConeMap(const ConeMap& m, ConeEncoding enc, ConeMap& scratch);
/// Decodes one code of enc to the ratio the GPU sees (unorm conversion, float
/// arithmetic).
float DecodeRatio(uint16_t code, ConeEncoding enc);
/// Encodes one ratio, rounding toward smaller ratios.
uint16_t EncodeRatio(float ratio, ConeEncoding enc);

/// The 3x3-minimum "bilinear safety" pass (Bán et al.), wrap-around: each texel gets the
/// minimum of its 3x3 neighbourhood per channel. Afterwards bilinear sampling anywhere in
/// the texel's footprint never exceeds the exact ratio of the texels the footprint
/// touches.
ConeMap BilinearSafetyPass(const ConeMap& m);

/// Statistics of a ratio map (all channels; cap values count as "unbounded" and are left
/// out of min/mean/max). Histogram: `bins` bins over [0, 1], last bin also holds ratios
/// > 1.
struct ConeMapStats {
    double minRatio = 0, meanRatio = 0, maxRatio = 0;
    int64_t nValues = 0, nUnbounded = 0;
    std::vector<int64_t> histogram;
};
ConeMapStats ComputeConeMapStats(const ConeMap& m, int bins = 32);
/// JSON text of the statistics (plus kind, size, encoding).
std::string ConeMapStatsJson(const ConeMap& m, const ConeMapStats& s, ConeEncoding enc);

/// The format WriteConeMap picks by `path`'s extension, in either case (".exr",
/// ".EXR"). Throws Error naming ParamName("out") and the path for any other extension.
enum class ConeMapFormat { Exr, Png };
ConeMapFormat ConeMapFormatOf(const std::string& path);

/// Writes the map: ".exr" float (one channel per ratio, names from ChannelNames), ".png"
/// 8-bit (channels 1..4; Acm8 as two 4-channel halves side by side, as 000 §II-D).
/// Atomic: written to a temporary beside `path` and renamed (core/output_set.h); with
/// `outputs`, staged in that set until the caller commits it (a map and its statistics
/// together). `stored`, when given, must be StoredConeMap(m, enc): a caller that has it
/// already saves quantising again for ".exr" (".png" takes its codes from `m`). Throws
/// Error.
void WriteConeMap(const std::string& path, const ConeMap& m, ConeEncoding enc,
                  OutputSet* outputs = nullptr, const ConeMap* stored = nullptr);

/// Loads a cone map made elsewhere (e.g. GPU Gems 3 "*_cone.tga": ratio linear in B, 8
/// bit). channel: 0..3 = R,G,B,A; -1 = all four (Quad: R,G,B,A = +x,-x,+y,-y). Acm8 reads
/// eight channels (channel ignored): an image with 8 or more channels, or one of 4 twice
/// as wide (two RGBA halves side by side, sectors 0-3 left, 4-7 right, as WriteConeMap
/// writes a PNG). The size must equal (expectWidth, expectHeight) when they are > 0.
/// Throws Error naming the file after `option` (the parameter that named it).
ConeMap LoadExternalConeMap(const std::string& path, ConeKind kind, int channel,
                            int expectWidth = 0, int expectHeight = 0,
                            const std::string& option = "--external");

/// The dynamic-map demo of 000 (water): a sum of four travelling sinusoids at time t
/// (seconds), depth in [0.05, 0.95], periodic in u and v. Regenerated every frame by
/// `reliefsim maps --animate N`.
DepthField MakeSinusoidMap(int width, int height, float t);
/// The same into an existing field (storage reused; name, size and depths overwritten).
void FillSinusoidMap(DepthField& hf, int width, int height, float t);

}  // namespace reliefsim
