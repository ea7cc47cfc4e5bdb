#include "texture/padded_texels.h"

#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>

#include "core/error.h"
#include "texture/lane_sampler.h"

namespace reliefsim {

bool GatherFootprints() {
    static const bool gather = [] {
        if (const char* env = std::getenv("RS_FOOTPRINT")) {
            const std::string_view mode(env);
            if (mode == "gather") return true;
            if (mode == "loads") return false;
        }
#if (defined(__x86_64__) || defined(__i386__)) && \
    (defined(__GNUC__) || defined(__clang__))
        return __builtin_cpu_is("intel") != 0;
#else
        return false;
#endif
    }();
    return gather;
}

PaddedTexels PadTexels(const DepthField& field, WrapMode wrap) {
    RS_CHECK(!field.Empty());
    PaddedTexels p;
    p.width = field.width;
    p.height = field.height;
    p.stride = field.width + 1;
    p.wrap = wrap;
    p.texels.resize(size_t(p.stride) * size_t(field.height + 1));
    const bool repeat = wrap == WrapMode::Repeat;
    for (int j = 0; j <= field.height; ++j) {
        const int sj = j < field.height ? j : (repeat ? 0 : field.height - 1);
        float* row = p.texels.data() + size_t(j) * size_t(p.stride);
        for (int i = 0; i < field.width; ++i) row[i] = field.At(i, sj);
        row[field.width] = field.At(repeat ? 0 : field.width - 1, sj);
    }
    return p;
}

void BindConeChannel(Textures& t, std::vector<DepthField> layers, bool squared) {
    RS_CHECK(t.depth && !layers.empty());
    const DepthField& d = *t.depth;
    const int64_t n = int64_t(layers.size());
    // The lanes address every layer's texels with 32-bit indices.
    const int64_t padded = int64_t(d.width + 1) * int64_t(d.height + 1);
    if (n * padded > int64_t(std::numeric_limits<int32_t>::max()))
        throw Error("cone map of " + std::to_string(n) + " layers of " +
                    std::to_string(d.width) + "x" + std::to_string(d.height) +
                    ": too large for the lane sampler (" + std::to_string(n * padded) +
                    " texels; at most 2^31 - 1)");
    const bool eightBit = !layers[0].depth8.empty();
    PaddedTexels all;
    std::vector<uint8_t> codes;
    t.cone.clear();
    for (DepthField& layer : layers) {
        RS_CHECK(layer.width == d.width && layer.height == d.height &&
                 layer.depth8.empty() != eightBit);
        PaddedTexels p = PadTexels(layer, t.sampler.wrap);
        if (all.texels.empty()) {
            all = std::move(p);
            all.texels.reserve(all.texels.size() * size_t(n));
        } else {
            all.texels.insert(all.texels.end(), p.texels.begin(), p.texels.end());
        }
        if (eightBit) codes.insert(codes.end(), layer.depth8.begin(), layer.depth8.end());
        t.cone.push_back(std::make_shared<const DepthField>(std::move(layer)));
    }
    t.conePadded = std::make_shared<const PaddedTexels>(std::move(all));
    t.cone8 = eightBit ? std::make_shared<const std::vector<uint8_t>>(std::move(codes))
                       : nullptr;
    t.coneSquared = squared;
    t.coneFilter = t.sampler.filter;  // sampled as the height unless told otherwise
}

}  // namespace reliefsim
