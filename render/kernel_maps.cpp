// The kernels' derived maps (render/kernel_maps.h).
#include "render/kernel_maps.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "core/error.h"
#include "core/param_name.h"
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

KernelMapSpec KernelConeSpec(const Kernel& kernel) {
    const KernelInfo& info = kernel.Info();
    RS_CHECK(info.maps.size() == 1);
    const auto spec = ParseKernelMap(info.maps[0]);
    RS_CHECK(spec.has_value());
    return *spec;
}

}  // namespace

std::optional<KernelMapSpec> ParseKernelMap(std::string_view name) {
    KernelMapSpec spec;
    const size_t space = name.find(' ');
    const auto kind = ParseConeKind(name.substr(0, space));
    if (!kind) return std::nullopt;
    spec.kind = *kind;
    std::string_view flags = space == name.npos ? "" : name.substr(space + 1);
    while (!flags.empty()) {
        const size_t end = flags.find(' ');
        const std::string_view flag = flags.substr(0, end);
        if (flag == "--relaxed")
            spec.params.relaxed = true;
        else if (flag == "--normal")
            spec.params.normal = true;
        else
            return std::nullopt;
        flags = end == flags.npos ? "" : flags.substr(end + 1);
    }
    return spec;
}

ConeEncoding KernelMapEncoding(const Kernel& kernel, const KernelMapSettings& maps) {
    if (maps.encoding) return *maps.encoding;
    const auto e = ParseConeEncoding(kernel.Info().mapEncoding);
    return e ? *e : ConeEncoding::Float;
}

void ValidateKernelMaps(const Kernel& kernel, const SamplerState& sampler,
                        const KernelMapSettings& maps) {
    if (kernel.Info().readsPyramid && sampler.wrap != WrapMode::Repeat)
        throw Error(ParamName("method") + " " + std::string(kernel.Info().name) +
                    " with " + ParamName("wrap") + " " +
                    std::string(ToString(sampler.wrap)) +
                    ": its cell pyramid tiles the texture (cells between texel centres "
                    "wrap around); use " +
                    ParamName("wrap") + " repeat");
    if (kernel.Info().maps.empty()) return;
    const Filter coneFilter = KernelConeFilter(kernel, sampler.filter);
    if (sampler.precision == Precision::Llvmpipe8 && coneFilter != sampler.filter)
        throw Error(ParamName("set") +
                    " cone_filter=" + std::string(kFilterNames.Name(coneFilter)) +
                    ": with an 8-bit height texture (" + ParamName("texture_format") +
                    " r8) the cone map is sampled as the height (" + ParamName("filter") +
                    " " + std::string(kFilterNames.Name(sampler.filter)) +
                    "; llvmpipe's 8-bit path is modelled for one filter per texture); "
                    "use " +
                    ParamName("texture_format") + " r32f or cone_filter=auto");
    const ConeEncoding e = KernelMapEncoding(kernel, maps);
    const bool eightBit = e == ConeEncoding::U8 || e == ConeEncoding::U8Sqrt;
    if (sampler.precision == Precision::Llvmpipe8 && !eightBit)
        throw Error(std::string(maps.coneMap.empty()
                                    ? ParamName("cone_encoding") + " "
                                    : ParamName("cone_map_encoding") + " ") +
                    std::string(ToString(e)) + ": an 8-bit height texture (" +
                    ParamName("texture_format") +
                    " r8) holds the cone "
                    "ratio in 8 bits too; use u8 or u8sqrt");
}

namespace {

/// The channels each layer takes the maximum over (kernels/cone_step.h): one layer per
/// channel, except quad, whose layers are the direction classes of qcsm.
std::vector<std::vector<int>> LayerChannels(ConeKind kind, int channels) {
    if (kind == ConeKind::Quad)  // channels +x, -x, +y, -y
        return {{0, 2}, {1, 2}, {1, 3}, {0, 3}, {0}, {2}, {1}, {3}};
    std::vector<std::vector<int>> layers;
    for (int c = 0; c < channels; ++c) layers.push_back({c});
    return layers;
}

}  // namespace

namespace {

/// The map's texels as the texture stores them, per texel and channel: `stored` the
/// texture's value (the ratio for float, code / 255 for 8-bit, code / 65535 for u16)
/// and, for the 8-bit encodings, the codes.
struct StoredMap {
    int channels = 1;
    std::vector<float> stored;
    std::vector<uint8_t> codes8;
};

StoredMap GeneratedMap(const DepthField& field, ConeKind kind,
                       const ConeMapParams& params, ConeEncoding enc,
                       const KernelMapSettings& maps, bool* cacheHit) {
    ConeMap map;
    bool hit = false;
    const std::string dir = maps.cacheDir.empty() ? DefaultMapCacheDir() : maps.cacheDir;
    const auto generate = [&] {
        return maps.bounds == ConeBounds::Bilinear
                   ? GenerateBilinearConeMap(field, kind, params)
                   : GenerateConeMap(field, kind, params);
    };
    if (maps.generator) {
        RS_CHECK(maps.bounds == ConeBounds::Texel);
        map = maps.generator(field, kind, params);
    } else if (maps.useCache && !dir.empty()) {
        try {
            map = MapCache(dir).GetOrCreate(field, kind, params, generate, &hit,
                                            maps.bounds);
        } catch (const Error&) {
            // An unwritable cache costs the regeneration next time, not this run.
            if (map.values.empty()) map = generate();
        }
    } else {
        map = generate();
    }
    if (cacheHit) *cacheHit = hit;
    RS_CHECK(map.width == field.width && map.height == field.height &&
             map.channels == ChannelCount(kind, params));
    StoredMap m;
    m.channels = map.channels;
    if (enc == ConeEncoding::Float) {
        m.stored = std::move(map.values);
        return m;
    }
    std::vector<uint16_t> codes;
    QuantizeConeMap(map, enc, &codes);
    RS_CHECK(codes.size() == map.values.size());
    const bool eightBit = enc == ConeEncoding::U8 || enc == ConeEncoding::U8Sqrt;
    m.stored.resize(codes.size());
    if (eightBit) m.codes8.resize(codes.size());
    for (size_t i = 0; i < codes.size(); ++i) {
        if (eightBit) {
            m.codes8[i] = uint8_t(codes[i]);
            m.stored[i] = Unorm8ToFloat(uint8_t(codes[i]));  // the texture's value
        } else {
            m.stored[i] = float(codes[i]) * float(1.0 / 65535.0);
        }
    }
    return m;
}

StoredMap ExternalMap(const DepthField& field, ConeKind kind, ConeEncoding enc,
                      const KernelMapSettings& maps) {
    const std::string subject = ParamName("cone_map") + " \"" + maps.coneMap + "\"";
    const int need = ChannelCount(kind);
    if (need != 1 && need != 4 && need != 8)
        throw Error(subject + ": this method reads a " + std::to_string(need) +
                    "-channel map (" + std::string(ToString(kind)) +
                    "); external maps of 1, 4 or 8 channels only");
    ConeMap map = LoadExternalConeMap(maps.coneMap, kind,
                                      need == 1 ? std::max(maps.coneMapChannel, 0) : -1,
                                      field.width, field.height, ParamName("cone_map"));
    RS_CHECK(map.channels == need);
    StoredMap m;
    m.channels = map.channels;
    m.stored = std::move(map.values);
    if (enc == ConeEncoding::U8 || enc == ConeEncoding::U8Sqrt) {
        m.codes8.resize(m.stored.size());
        for (size_t i = 0; i < m.stored.size(); ++i) {
            const float v = m.stored[i];
            const float c = std::nearbyint(v * 255.0f);
            if (!(c >= 0.0f && c <= 255.0f) || Unorm8ToFloat(uint8_t(c)) != v)
                throw Error(
                    subject + ": texel (" +
                    std::to_string(i / size_t(need) % size_t(field.width)) + ", " +
                    std::to_string(i / size_t(need) / size_t(field.width)) +
                    ") is not an 8-bit code; " + ParamName("cone_map_encoding") + " " +
                    std::string(ToString(enc)) + " needs an 8-bit map (or use float)");
            m.codes8[i] = uint8_t(c);
        }
    }
    return m;
}

}  // namespace

std::vector<DepthField> KernelConeLayers(const DepthField& field, const Kernel& kernel,
                                         const KernelMapSettings& maps, bool* cacheHit) {
    const KernelMapSpec spec = KernelConeSpec(kernel);
    const ConeKind kind = spec.kind;
    const ConeEncoding enc = KernelMapEncoding(kernel, maps);
    if (cacheHit) *cacheHit = false;
    const StoredMap map =
        maps.coneMap.empty() ? GeneratedMap(field, kind, spec.params, enc, maps, cacheHit)
                             : ExternalMap(field, kind, enc, maps);
    const size_t n = size_t(field.width) * size_t(field.height);
    const size_t nc = size_t(map.channels);
    RS_CHECK(map.stored.size() == n * nc &&
             (map.codes8.empty() || map.codes8.size() == n * nc));
    const auto layerChannels = LayerChannels(kind, map.channels);
    std::vector<DepthField> layers;
    for (size_t l = 0; l < layerChannels.size(); ++l) {
        const std::vector<int>& chans = layerChannels[l];
        DepthField c;
        c.width = field.width;
        c.height = field.height;
        c.name = field.name + " (" + std::string(ToString(kind)) + " " +
                 std::string(ToString(enc)) +
                 (layerChannels.size() > 1 ? " layer " + std::to_string(l) : "") + ")";
        c.depth.resize(n);
        if (!map.codes8.empty()) c.depth8.resize(n);
        for (size_t i = 0; i < n; ++i) {
            // The widest of the layer's channels, on the stored value (every decode is
            // monotone, so the stored maximum decodes to the ratios' maximum).
            float r = map.stored[i * nc + size_t(chans[0])];
            for (int ch : chans) r = std::max(r, map.stored[i * nc + size_t(ch)]);
            c.depth[i] = r;
            if (c.depth8.empty()) continue;
            uint8_t code = map.codes8[i * nc + size_t(chans[0])];
            for (int ch : chans) code = std::max(code, map.codes8[i * nc + size_t(ch)]);
            c.depth8[i] = code;
        }
        layers.push_back(std::move(c));
    }
    RS_CHECK(int(layers.size()) == kernel.Info().mapLayers);
    return layers;
}

std::function<ConeMap(const DepthField&, ConeKind, const ConeMapParams&)>
AdaptiveMapGenerator(float threshold, int levels, double* millis) {
    struct State {
        AdaptiveWorkspace workspace;
        ConeMap map;
    };
    auto state = std::make_shared<State>();
    return [state, threshold, levels, millis](const DepthField& field, ConeKind kind,
                                              const ConeMapParams&) {
        const auto t0 = std::chrono::steady_clock::now();
        GenerateAdaptiveSectorMap(field, kind, threshold, levels, state->workspace,
                                  state->map);
        if (millis)
            *millis = std::chrono::duration<double, std::milli>(
                          std::chrono::steady_clock::now() - t0)
                          .count();
        return state->map;
    };
}

Textures BindKernelTextures(const DepthField& field, const SamplerState& sampler,
                            const Kernel& kernel, const KernelMapSettings& maps,
                            bool* cacheHit) {
    Textures t = BindTextures(field, sampler);
    if (cacheHit) *cacheHit = false;
    if (kernel.Info().readsPyramid) {
        ValidateKernelMaps(kernel, sampler, maps);
        t.pyramid = std::make_shared<const CellPyramid>(BuildCellPyramid(field));
    }
    if (kernel.Info().maps.empty()) return t;
    ValidateKernelMaps(kernel, sampler, maps);
    const bool squared = KernelMapEncoding(kernel, maps) == ConeEncoding::U8Sqrt;
    BindConeChannel(t, KernelConeLayers(field, kernel, maps, cacheHit), squared);
    t.coneFilter = KernelConeFilter(kernel, sampler.filter);
    return t;
}

}  // namespace reliefsim
