// The kernel interface: how a kernel describes itself, and the per-trip shape every
// kernel has (docs/architecture.md "Kernels and the fragment driver").
//
// A kernel is a type K with
//   static const KernelInfo& Info();                 name, title, source, parameters,
//   maps,
//                                                    GLSL twin: defined once
//   struct Params; static Params FromValues(const ParamValues&);
//   template <class L> struct State;                 per-lane state, all in L::F / L::M
//   template <class L> static void Begin(const Params&, const LaneRay<L>&, State<L>&,
//                                        Fetch<L>& first);
//   template <class L> static typename L::M Step(const Params&, const LaneRay<L>&,
//                                        State<L>&, const Sample<L>& sampled,
//                                        typename L::M active, Fetch<L>& next);
//   template <class L> static void End(const Params&, const LaneRay<L>&, const State<L>&,
//                                      LaneOutcome<L>&);
// Begin sets every field of State (the driver reuses a pack's State without clearing
// it) and names the first fetch of every lane. The driver (render/lane_driver.h) then
// runs trips: one fetch per active lane, then Step, which consumes the sample and returns
// the lanes that want another fetch (naming it in `next`). Before every fetch the driver
// applies the fetch budget; a lane refused a fetch stops with its state as it is, so End
// must answer from State what the lane returns if it stopped there. The GLSL twin is the
// same step in a do-while loop (kernels/glsl/). A kernel with `static constexpr bool
// kReadsRatio = true` reads a cone-family map: each of its fetches returns the depth and
// the decoded cone ratio at the same uv (one fetch of the combined texture); one with
// `kConeLayers = n` reads an n-layer map and names the layer of each lane in Begin
// (Fetch::layer). One with `kReadsPyramid = true` fetches nodes of the cell pyramid and
// cell corners by index (Fetch::level, cx, cy; the hierarchical tracers).
#pragma once

#include <array>
#include <cstdint>
#include <glm/vec2.hpp>
#include <map>
#include <span>
#include <string>
#include <string_view>

#include "kernels/lanes.h"

namespace reliefsim {

/// A fragment's view ray in texture space (DESIGN.md conventions): it enters the relief
/// at (uvEntry, depth 0) and p(t) = (uvEntry + t * dirUv, t), so t is the ray's depth and
/// t = 1 reaches the bottom of the relief.
struct MarchInput {
    glm::vec2 uvEntry;  ///< uv where the ray enters the relief (tiling included)
    glm::vec2 dirUv;    ///< uv travelled per unit depth: -view.xy / view.z * depthScale *
                        ///< tiling
    /// |view.z| of the unit tangent-space view direction (the cosine of the view angle
    /// to the normal): what offset limiting (Welsh 2004) scales by. A ray built by hand
    /// without it looks straight down (1).
    float viewZ = 1.0f;
};

/// What a kernel returns for one fragment. Iterations are loop trips of the paper's
/// algorithm; fetches are counted by the driver's sampler.
struct MarchResult {
    glm::vec2 uvHit{0.0f};         ///< uv of the returned point (unwrapped)
    float depthHit = 0.0f;         ///< ray depth t of the returned point, in [0,1]
    uint16_t nCoarse = 0;          ///< coarse-search iterations (linear / cone steps)
    uint16_t nRefine = 0;          ///< refinement iterations (binary / secant / interval)
    bool hit = false;              ///< the coarse search found the ray below the surface
    bool budgetExhausted = false;  ///< stopped by the fetch budget; the point is the
                                   ///< estimate then
};

/// A numeric kernel parameter as given to `--set name=value`, defined once with its
/// kernel. A parameter with `choices` takes one of their names (or its index), and its
/// value is the index: `--set cone_filter=min4`.
struct ParamSpec {
    std::string_view name;
    double defaultValue;
    double minValue, maxValue;  ///< inclusive valid range
    bool integer;               ///< integers only (booleans are integers in [0,1])
    std::string_view help;
    std::string_view uniform;  ///< the GLSL twin's uniform ("" = none)
    std::span<const std::string_view> choices = {};  ///< names of 0, 1, ... (or none)
};

/// A uniform the twin needs that is fixed by the kernel, not a parameter.
struct GlslConstant {
    std::string_view uniform;
    int value;
};

/// A kernel's self-description: everything the command line, the GL runner and the docs
/// read about it.
struct KernelInfo {
    std::string_view name;    ///< the --method name
    std::string_view title;   ///< one line
    std::string_view source;  ///< paper and equation / algorithm numbers
    std::span<const ParamSpec> params;
    std::span<const std::string_view> maps;  ///< derived maps it needs besides the height
    std::string_view glslFile;               ///< its twin in kernels/glsl/
    std::span<const GlslConstant> glslConstants;
    /// How its maps are stored by default (a kConeEncodingNames name: as its paper
    /// stores them); "" when it reads none.
    std::string_view mapEncoding = "";
    /// Layers of its map as it reads it (kConeLayers: one per direction class of the
    /// directional cones; 1 otherwise).
    int mapLayers = 1;
    /// Its answer is where it stopped even above the surface (KernelAnswersAtStop).
    bool answersAtStop = false;
    /// It reads the cell pyramid (texture/cell_pyramid.h; KernelReadsPyramid) and, with
    /// it, needs a repeating height texture.
    bool readsPyramid = false;
};

/// Parameter values by name: every parameter of the method, defaults filled in.
using ParamValues = std::map<std::string, double, std::less<>>;

/// The value of parameter `name`, else its default among `specs` (so defaults live only
/// in the ParamSpecs), else 0: a parameter the kernel does not have and does not read.
/// What every kernel's FromValues reads its parameters with.
inline double ParamValue(const ParamValues& v, std::span<const ParamSpec> specs,
                         std::string_view name) {
    if (auto it = v.find(name); it != v.end()) return it->second;
    for (const ParamSpec& p : specs)
        if (p.name == name) return p.defaultValue;
    return 0.0;
}

/// The parameters every kernel has; the driver reads "budget".
inline constexpr ParamSpec kEarlyExitParam = {
    "early_exit",
    1,
    0,
    1,
    true,
    "1: break out of loops; 0: GPU-style fixed loops (result latched)",
    "uEarlyExit"};
inline constexpr ParamSpec kBudgetParam = {
    "budget", 0, 0, 1000000, true, "fetch budget per fragment; 0 = none", "uBudget"};

/// How the cone kernels sample their cone map (kernels/cone_step.h): as the height map
/// (`--filter`), or bilinear (the papers), nearest, min of the bilinear footprint (the
/// conservative choice). The values of the `cone_filter` parameter, in this order.
inline constexpr std::array<std::string_view, 4> kConeFilterChoices = {"auto", "bilinear",
                                                                       "nearest", "min4"};
inline constexpr ParamSpec kConeFilterParam = {
    "cone_filter",
    0,
    0,
    3,
    true,
    "cone-map sampling: auto (as --filter), bilinear (the papers), nearest, min4 (the "
    "minimum of the bilinear footprint)",
    "uConeFilter",
    kConeFilterChoices};

/// A pack of rays, one per lane.
template <class L>
struct LaneRay {
    using F = typename L::F;
    F uEntry, vEntry;  ///< MarchInput::uvEntry
    F du, dv;          ///< MarchInput::dirUv
    F viewZ;           ///< MarchInput::viewZ
    /// The height map's size in texels (the driver sets it; kernels that step by texel
    /// cells read it).
    float mapW = 1.0f, mapH = 1.0f;
    F U(const F& t) const { return uEntry + du * t; }
    F V(const F& t) const { return vEntry + dv * t; }
};

/// Stacked cones a kernel can read in one fetch (kReadsAllLayers).
inline constexpr int kMaxStackedCones = 4;

/// What one fetch returns per lane: the depth, and the decoded cone ratio for kernels
/// that read one (kReadsRatio; unspecified otherwise). A kernel with `kReadsAllLayers`
/// gets every layer's value at the point in `stack` (stack[0] == ratio).
template <class L>
struct Sample {
    typename L::F h, ratio;
    std::array<typename L::F, kMaxStackedCones> stack;
    /// A kernel with `kReadsPyramid` fetching a cell's corners (Fetch::level < 0): the
    /// texels at (i, j), (i+1, j), (i, j+1), (i+1, j+1) of cell (i, j).
    std::array<typename L::F, 4> corners;
};

/// Whether kernel K reads a cone map with its depths.
template <class K>
concept KernelReadsRatio = requires {
    requires K::kReadsRatio;
};

/// Where each lane fetches next: uv, and the ray depth there (for traces). `layer` picks
/// the cone map's layer for kernels whose map has several (kConeLayers > 1: the
/// directional cones, one layer per ray direction class); the driver keeps it from Begin
/// on, kernels with one layer leave it 0.
template <class L>
struct Fetch {
    typename L::F u, v, t;
    typename L::I layer = typename L::I(0);
    /// Kernels with `kReadsPyramid` (the hierarchical tracers, kernels/max_mip.h) fetch
    /// by index, not by uv (u, v, t stay the ray point, for traces): the node of `level`
    /// holding level-0 cell (cx, cy) of the cell pyramid (texture/cell_pyramid.h); for
    /// level -1 the four corners of cell (cx, cy); for level -2 the height at (u, v)
    /// with the height sampler, as every other kernel fetches.
    typename L::I level = typename L::I(0), cx = typename L::I(0), cy = typename L::I(0);
};

/// Whether kernel K reads the cell pyramid by index (kReadsPyramid).
template <class K>
concept KernelReadsPyramid = requires {
    requires K::kReadsPyramid;
};

/// Whether kernel K reads every layer of its map in each fetch (the stacked cones of
/// mcns) rather than one layer per ray.
template <class K>
concept KernelReadsAllLayers = requires {
    requires K::kReadsAllLayers;
};

/// The number of cone-map layers kernel K reads (kConeLayers, else 1).
template <class K>
constexpr int KernelConeLayers() {
    if constexpr (requires { K::kConeLayers; })
        return K::kConeLayers;
    else
        return 1;
}

/// Whether kernel K's answer is the point where it stopped even when that point lies
/// above the surface (kAnswersAtStop: the cone family, whose conservative march only
/// approaches the surface, as the papers' shaders shade wherever it stopped); the
/// driver then shades and lights that point. Otherwise a lane without a hit is a miss.
template <class K>
concept KernelAnswersAtStop = requires {
    requires K::kAnswersAtStop;
};

/// What a kernel reports per lane when the driver is done with it.
template <class L>
struct LaneOutcome {
    typename L::F u, v, depth;  ///< the returned point
    typename L::F nCoarse, nRefine;
    typename L::M hit;
};

}  // namespace reliefsim
