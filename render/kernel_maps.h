// The derived maps a kernel reads (KernelInfo::maps), made for a height field and bound
// with its textures: generated with the maps/ generators, encoded as the kernel's paper
// stores them (KernelInfo::mapEncoding, --cone-encoding overrides), and kept in the disk
// cache (maps/map_cache.h) keyed by the field's texels and the map's parameters.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "kernels/registry.h"
#include "maps/cone_map.h"
#include "maps/cone_map_bilinear.h"
#include "texture/lane_sampler.h"

namespace reliefsim {

/// Where and how the kernels' maps are made (render, trace, glcompare, sweep).
struct KernelMapSettings {
    std::optional<ConeEncoding> encoding;  ///< --cone-encoding; unset: the kernel's own
    std::string cacheDir;                  ///< --cache-dir; "": DefaultMapCacheDir()
    bool useCache = true;                  ///< --no-cache turns it off
    /// --cone-map: a map made elsewhere, used instead of generating one. Its values are
    /// the stored ratios in `encoding` (--cone-map-encoding; unset: the kernel's).
    std::string coneMap;
    /// --cone-map-channel for one-ratio kernels: 0..3 = R, G, B, A; -1 (unset): R.
    /// Directional kernels read all four (RGBA, as maps --kind quad|acm4 writes them).
    int coneMapChannel = -1;
    /// --cone-bounds: the surface a generated conservative map bounds; bilinear makes
    /// GenerateBilinearConeMap's maps (csm, qcsm, acm4, acm8, cns only).
    ConeBounds bounds = ConeBounds::Texel;
    /// When set, makes the kernel's map (float ratios, the kind's channels) instead of
    /// GenerateConeMap and the cache: `render --animate` preprocesses every frame's map
    /// with adaptive ACM this way. The map is then encoded like a generated one.
    std::function<ConeMap(const DepthField& field, ConeKind kind,
                          const ConeMapParams& params)>
        generator;
};

/// A KernelMapSettings::generator that makes a cone, quad, acm4 or acm8 map with
/// adaptive ACM (000 Algorithm 1, GenerateAdaptiveSectorMap) into buffers kept across
/// calls, as a renderer preprocessing a dynamic map every frame would (`render
/// --animate`); *millis, when given, receives each call's time in milliseconds.
std::function<ConeMap(const DepthField&, ConeKind, const ConeMapParams&)>
AdaptiveMapGenerator(float threshold, int levels, double* millis = nullptr);

/// A map as a kernel names it (KernelInfo::maps): a `maps --kind` name, optionally with
/// the flags " --relaxed" (relaxed cones) and " --normal" (stacked cones as n_z), as
/// `reliefsim maps` makes it.
struct KernelMapSpec {
    ConeKind kind = ConeKind::Cone;
    ConeMapParams params;
};
std::optional<KernelMapSpec> ParseKernelMap(std::string_view name);

/// $XDG_CACHE_HOME/reliefsim, else $HOME/.cache/reliefsim, else "" (no cache).
std::string DefaultMapCacheDir();

/// The encoding the kernel's maps are stored in: the override, else the kernel's.
ConeEncoding KernelMapEncoding(const Kernel& kernel, const KernelMapSettings& maps);

/// Throws Error for settings no kernel map can use with this sampler (an 8-bit height
/// texture needs an 8-bit cone encoding: the GL texture holds both in one RG8).
void ValidateKernelMaps(const Kernel& kernel, const SamplerState& sampler,
                        const KernelMapSettings& maps);

/// The textures `kernel` reads over `field`: the height (BindTextures) and, for a kernel
/// with maps, its cone channel. A cache that cannot be written is skipped (the map is
/// still made); *cacheHit tells whether the map came from the cache.
Textures BindKernelTextures(const DepthField& field, const SamplerState& sampler,
                            const Kernel& kernel, const KernelMapSettings& maps,
                            bool* cacheHit = nullptr);

/// The cone channel's layers as BindKernelTextures binds them (the stored texel values;
/// codes in depth8 for 8-bit encodings): what the GL runner uploads as the texture's G
/// channel. One layer per channel of the map, except quad: qcsm's eight direction
/// classes (kernels/cone_step.h), each the maximum of the half-plane channels it takes.
std::vector<DepthField> KernelConeLayers(const DepthField& field, const Kernel& kernel,
                                         const KernelMapSettings& maps,
                                         bool* cacheHit = nullptr);

}  // namespace reliefsim
