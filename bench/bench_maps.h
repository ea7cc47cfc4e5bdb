// Height maps the benchmarks build at run time: the classic maps of ../shared/data
// resized to an artist's sizes and bit depths, and the built-ins.
#pragma once

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>

#include "texture/depth_field.h"
#include "texture/image_io.h"

namespace reliefsim::bench {

#ifndef RS_SHARED_DATA
#define RS_SHARED_DATA "../shared/data"
#endif

/// `field` resampled bilinearly (repeat) to size x size floats: a map with as many
/// distinct depths as a 16-bit or float artist's map.
inline DepthField Upsample(const DepthField& f, int size) {
    DepthField out = UpsampleBilinear(f, size, size);
    out.name = f.name + "@" + std::to_string(size);
    return out;
}

/// The depths rounded to `bits` (8 or 16) unorm codes, as an 8- or 16-bit file stores
/// them (8 bits keep depth8, as a loaded 8-bit map does).
inline DepthField Quantize(DepthField f, int bits) {
    const double top = bits == 8 ? 255.0 : 65535.0;
    if (bits == 8) f.depth8.resize(f.depth.size());
    for (size_t i = 0; i < f.depth.size(); ++i) {
        const double code = std::nearbyint(double(f.depth[i]) * top);
        if (bits == 8) {
            f.depth8[i] = uint8_t(code);
            f.depth[i] = Unorm8ToFloat(uint8_t(code));
        } else {
            f.depth[i] = float(code / top);
        }
    }
    f.name += bits == 8 ? " 8-bit" : " 16-bit";
    return f;
}

/// The DirectX SDK map `name` (e.g. "rocks"; height in A) from ../shared/data, or none
/// when the folder is absent (a user's clone).
inline std::optional<DepthField> SharedMap(const std::string& name) {
    const std::string path =
        std::string(RS_SHARED_DATA) + "/dxsdk-pom/" + name + "_NM_height.tga";
    if (!std::filesystem::exists(path)) return std::nullopt;
    MapLoadOptions o;
    o.channel = Channel::A;
    DepthField f = LoadHeightMap(path, o);
    f.name = name;
    return f;
}

}  // namespace reliefsim::bench
