// DepthField construction and validation.
#include "texture/depth_field.h"

#include <cmath>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/wrap.h"

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

DepthField UpsampleBilinear(const DepthField& hf, int width, int height) {
    DepthField out;
    out.width = width;
    out.height = height;
    out.name = hf.name + "@" + std::to_string(width) + "x" + std::to_string(height);
    out.depth.resize(size_t(width) * size_t(height));
    const auto at = [&](int a, int b) {
        return double(hf.At(Wrap(a, hf.width), Wrap(b, hf.height)));
    };
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            const double x = (i + 0.5) * hf.width / width - 0.5,
                         y = (j + 0.5) * hf.height / height - 0.5;
            const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
            const double fx = x - x0, fy = y - y0;
            out.depth[size_t(j) * size_t(width) + size_t(i)] =
                float((at(x0, y0) * (1 - fx) + at(x0 + 1, y0) * fx) * (1 - fy) +
                      (at(x0, y0 + 1) * (1 - fx) + at(x0 + 1, y0 + 1) * fx) * fy);
        }
    return out;
}

}  // namespace reliefsim
