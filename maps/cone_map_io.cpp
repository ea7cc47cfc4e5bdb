// Cone maps on disk: writing .exr/.png atomically, reading maps made elsewhere (GPU Gems
// 3).
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "core/file_extension.h"
#include "core/param_name.h"
#include "maps/cone_map.h"
#include "texture/image_io.h"

namespace reliefsim {

namespace OIIO = OIIO_NAMESPACE;

ConeMapFormat ConeMapFormatOf(const std::string& path) {
    const std::string ext = LowerExtension(path);
    if (ext == ".exr") return ConeMapFormat::Exr;
    if (ext == ".png") return ConeMapFormat::Png;
    throw Error(ParamName("out") + " \"" + path +
                "\": unsupported extension; expected .exr (float) or .png (8-bit)");
}

void WriteConeMap(const std::string& path, const ConeMap& m, ConeEncoding enc,
                  OutputSet* outputs, const ConeMap* stored) {
    // The image writers stage the file (in `outputs`, or on their own), so a failure
    // leaves nothing behind.
    if (ConeMapFormatOf(path) == ConeMapFormat::Exr) {
        ConeMap scratch;
        const ConeMap& values = stored ? *stored : StoredConeMap(m, enc, scratch);
        RS_CHECK(values.values.size() == m.values.size());
        WriteFloatImage(path, m.width, m.height, m.channels, values.values.data(),
                        ChannelNames(m.kind), outputs);
        return;
    }
    if (m.channels > 4 && m.channels != 8)
        throw Error(ParamName("out") + " \"" + path + "\": " +
                    std::to_string(m.channels) + " channels do not fit a PNG; use .exr");
    const ConeEncoding e8 =
        enc == ConeEncoding::U8Sqrt ? ConeEncoding::U8Sqrt : ConeEncoding::U8;
    std::vector<uint16_t> codes;
    QuantizeConeMap(m, e8, &codes);
    if (m.channels == 8) {  // two RGBA halves side by side (000 §II-D)
        std::vector<uint8_t> px(size_t(m.width) * 2 * size_t(m.height) * 4);
        for (int j = 0; j < m.height; ++j)
            for (int i = 0; i < m.width; ++i)
                for (int c = 0; c < 8; ++c) {
                    const int x = i + (c / 4) * m.width;
                    px[(size_t(j) * size_t(2 * m.width) + size_t(x)) * 4 +
                       size_t(c % 4)] =
                        uint8_t(codes[(size_t(j) * size_t(m.width) + size_t(i)) * 8 +
                                      size_t(c)]);
                }
        WriteRgb8Image(path, 2 * m.width, m.height, 4, px.data(), outputs);
        return;
    }
    std::vector<uint8_t> px(codes.size());
    for (size_t i = 0; i < codes.size(); ++i) px[i] = uint8_t(codes[i]);
    WriteRgb8Image(path, m.width, m.height, m.channels, px.data(), outputs);
}

ConeMap LoadExternalConeMap(const std::string& path, ConeKind kind, int channel,
                            int expectWidth, int expectHeight,
                            const std::string& option) {
    const std::string subject = option + " \"" + path + "\"";
    // acm8: eight channels (an EXR as `maps --kind acm8 --out m.exr` writes it), or two
    // RGBA halves side by side (000 §II-D; the PNG `maps` writes).
    const bool eight = kind == ConeKind::Acm8;
    const int want = eight ? 8 : (channel < 0 ? 4 : 1);
    auto pick = [&](int nc) -> std::pair<int, int> {
        if (eight) {
            if (nc >= 8) return {0, 8};
            if (nc == 4) return {0, 4};
            throw Error(subject + ": has " + std::to_string(nc) + " channel" +
                        (nc == 1 ? "" : "s") +
                        "; acm8 reads 8 channels, or two RGBA halves side by side (the "
                        "PNG of `maps --kind acm8`)");
        }
        if ((channel < 0 && nc < 4) || channel >= nc)
            throw Error(subject + ": has " + std::to_string(nc) + " channel" +
                        (nc == 1 ? "" : "s") + "; the ratio channel " +
                        (channel < 0 ? std::string("set RGBA")
                                     : std::string(1, "RGBA"[channel])) +
                        " is missing (GPU Gems 3 maps: ratio in B)");
        return channel < 0 ? std::pair<int, int>{0, 4}
                           : std::pair<int, int>{channel, channel + 1};
    };
    // 8-bit sources: the codes are converted like the GPU's unorm8, not OIIO's division.
    ImageData img = ReadImageFile(path, subject, pick, /*keep8=*/true);
    const bool halves = eight && img.channels == 4;
    const int W = halves ? img.width / 2 : img.width, H = img.height;
    if (halves && img.width % 2 != 0)
        throw Error(
            subject + ": is " + std::to_string(img.width) + "x" + std::to_string(H) +
            " with 4 channels; an acm8 map of two RGBA halves is twice as wide as "
            "the height map");
    if (expectWidth > 0 && (W != expectWidth || H != expectHeight))
        throw Error(subject + ": is " + std::to_string(img.width) + "x" +
                    std::to_string(H) + ", expected " +
                    std::to_string(halves ? 2 * expectWidth : expectWidth) + "x" +
                    std::to_string(expectHeight) +
                    (halves ? " (two RGBA halves, each the height map's size)"
                            : " (the height map's size)"));
    ConeMap m;
    m.kind = kind;
    m.width = W;
    m.height = H;
    m.channels = want;
    m.values.resize(size_t(W) * size_t(H) * size_t(want));
    for (size_t t = 0; t < m.values.size(); ++t) {
        const size_t texel = t / size_t(want), c = t % size_t(want);
        const size_t i = texel % size_t(W), j = texel / size_t(W);
        // The file's value: channel c of the texel, from its half for two halves.
        const size_t at =
            halves ? (j * size_t(img.width) + i + (c / 4) * size_t(W)) * 4 + c % 4 : t;
        const float v = img.is8 ? Unorm8ToFloat(img.values8[at]) : img.values[at];
        if (!std::isfinite(v) || v < 0.0f)
            throw Error(subject + ": texel (" + std::to_string(i) + ", " +
                        std::to_string(j) +
                        ") holds a negative or non-finite ratio; ratios must be >= 0");
        m.values[t] = v;
    }
    return m;
}

}  // namespace reliefsim
