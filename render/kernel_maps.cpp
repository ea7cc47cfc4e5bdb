// The kernels' derived maps (render/kernel_maps.h).
#include "render/kernel_maps.h"

#include <cstdlib>
#include <filesystem>

#include "core/error.h"
#include "maps/map_cache.h"

namespace reliefsim {

std::string DefaultMapCacheDir() {
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
        return (std::filesystem::path(x) / "reliefsim").string();
    if (const char* h = std::getenv("HOME"); h && *h)
        return (std::filesystem::path(h) / ".cache" / "reliefsim").string();
    return "";
}

namespace {

ConeKind KernelConeKind(const Kernel& kernel) {
    const KernelInfo& info = kernel.Info();
    RS_CHECK(info.maps.size() == 1);
    const auto kind = ParseConeKind(info.maps[0]);
    RS_CHECK(kind.has_value());
    return *kind;
}

}  // namespace

ConeEncoding KernelMapEncoding(const Kernel& kernel, const KernelMapSettings& maps) {
    if (maps.encoding) return *maps.encoding;
    const auto e = ParseConeEncoding(kernel.Info().mapEncoding);
    return e ? *e : ConeEncoding::Float;
}

void ValidateKernelMaps(const Kernel& kernel, const SamplerState& sampler,
                        const KernelMapSettings& maps) {
    if (kernel.Info().maps.empty()) return;
    const ConeEncoding e = KernelMapEncoding(kernel, maps);
    const bool eightBit = e == ConeEncoding::U8 || e == ConeEncoding::U8Sqrt;
    if (sampler.precision == Precision::Llvmpipe8 && !eightBit)
        throw Error("--cone-encoding " + std::string(ToString(e)) +
                    ": an 8-bit height texture (--texture-format r8) holds the cone "
                    "ratio in 8 bits too; use u8 or u8sqrt");
}

DepthField KernelConeChannel(const DepthField& field, const Kernel& kernel,
                             const KernelMapSettings& maps, bool* cacheHit) {
    const ConeKind kind = KernelConeKind(kernel);
    const ConeEncoding enc = KernelMapEncoding(kernel, maps);
    const ConeMapParams params;
    ConeMap map;
    bool hit = false;
    const std::string dir = maps.cacheDir.empty() ? DefaultMapCacheDir() : maps.cacheDir;
    if (maps.useCache && !dir.empty()) {
        try {
            map = MapCache(dir).GetOrCreate(
                field, kind, params, [&] { return GenerateConeMap(field, kind, params); },
                &hit);
        } catch (const Error&) {
            // An unwritable cache costs the regeneration next time, not this run.
            if (map.values.empty()) map = GenerateConeMap(field, kind, params);
        }
    } else {
        map = GenerateConeMap(field, kind, params);
    }
    if (cacheHit) *cacheHit = hit;
    RS_CHECK(map.channels == 1 && map.width == field.width && map.height == field.height);
    DepthField c;
    c.width = field.width;
    c.height = field.height;
    c.name = field.name + " (" + std::string(ToString(kind)) + " " +
             std::string(ToString(enc)) + ")";
    if (enc == ConeEncoding::Float) {
        c.depth = map.values;
    } else {
        c.depth.resize(map.values.size());
        std::vector<uint16_t> codes;
        QuantizeConeMap(map, enc, &codes);
        RS_CHECK(codes.size() == map.values.size());
        const bool eightBit = enc == ConeEncoding::U8 || enc == ConeEncoding::U8Sqrt;
        if (eightBit) c.depth8.resize(codes.size());
        for (size_t i = 0; i < codes.size(); ++i) {
            if (eightBit) {
                c.depth8[i] = uint8_t(codes[i]);
                c.depth[i] = Unorm8ToFloat(uint8_t(codes[i]));  // the texture's value
            } else {
                c.depth[i] = float(codes[i]) * float(1.0 / 65535.0);
            }
        }
    }
    return c;
}

Textures BindKernelTextures(const DepthField& field, const SamplerState& sampler,
                            const Kernel& kernel, const KernelMapSettings& maps,
                            bool* cacheHit) {
    Textures t = BindTextures(field, sampler);
    if (cacheHit) *cacheHit = false;
    if (kernel.Info().maps.empty()) return t;
    ValidateKernelMaps(kernel, sampler, maps);
    const bool squared = KernelMapEncoding(kernel, maps) == ConeEncoding::U8Sqrt;
    BindConeChannel(t, KernelConeChannel(field, kernel, maps, cacheHit), squared);
    return t;
}

}  // namespace reliefsim
