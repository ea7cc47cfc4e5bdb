// DepthField construction and validation.
#include "texture/depth_field.h"

#include <cmath>
#include <sstream>

#include "core/error.h"

namespace reliefsim {

DepthField DepthFieldFromUnorm8(int width, int height, std::vector<uint8_t> depth8,
                                std::string name) {
    DepthField hf;
    hf.width = width;
    hf.height = height;
    hf.name = std::move(name);
    hf.depth.resize(depth8.size());
    for (size_t k = 0; k < depth8.size(); ++k) hf.depth[k] = Unorm8ToFloat(depth8[k]);
    hf.depth8 = std::move(depth8);
    return hf;
}

DepthField QuantizeToUnorm8(const DepthField& hf) {
    std::vector<uint8_t> d8(hf.depth.size());
    for (size_t k = 0; k < d8.size(); ++k)
        d8[k] = uint8_t(std::lround(double(hf.depth[k]) * 255.0));
    return DepthFieldFromUnorm8(hf.width, hf.height, std::move(d8), hf.name + " (8-bit)");
}

void ValidateDepthField(const DepthField& hf) {
    if (hf.Empty())
        throw Error("height map \"" + hf.name + "\": has zero size (" +
                    std::to_string(hf.width) + "x" + std::to_string(hf.height) + ")");
    if (hf.depth.size() != size_t(hf.width) * size_t(hf.height))
        throw Error("height map \"" + hf.name +
                    "\": pixel count does not match its size");
    for (size_t k = 0; k < hf.depth.size(); ++k) {
        float d = hf.depth[k];
        if (!std::isfinite(d) || d < 0.0f || d > 1.0f) {
            std::ostringstream s;
            s << "height map \"" << hf.name << "\": texel (" << k % size_t(hf.width)
              << ", " << k / size_t(hf.width) << ") is " << d
              << "; heights must be finite and in [0,1] (NaN/Inf are not allowed)";
            throw Error(s.str());
        }
    }
}

}  // namespace reliefsim
