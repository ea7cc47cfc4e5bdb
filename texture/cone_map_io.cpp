// Cone maps on disk: writing .exr/.png atomically, reading maps made elsewhere (GPU Gems 3).
#include <OpenImageIO/imageio.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "texture/cone_map.h"
#include "texture/image_io.h"

namespace reliefsim {

namespace OIIO = OIIO_NAMESPACE;

namespace {

std::string Lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

}  // namespace

void WriteConeMap(const std::string& path, const ConeMap& m, ConeEncoding enc,
                  OutputSet* outputs) {
    const std::string ext = Lower(std::filesystem::path(path).extension().string());
    if (ext != ".exr" && ext != ".png")
        throw Error("--out \"" + path + "\": unsupported extension; expected .exr (float) or .png (8-bit)");
    // The image writers stage the file (in `outputs`, or on their own), so a failure
    // leaves nothing behind.
    if (ext == ".exr") {
        const ConeMap q = QuantizeConeMap(m, enc);
        WriteFloatImage(path, m.width, m.height, m.channels, q.values.data(),
                        ChannelNames(m.kind), outputs);
        return;
    }
    if (m.channels > 4 && m.channels != 8)
        throw Error("--out \"" + path + "\": " + std::to_string(m.channels) +
                    " channels do not fit a PNG; use .exr");
    const ConeEncoding e8 = enc == ConeEncoding::U8Sqrt ? ConeEncoding::U8Sqrt : ConeEncoding::U8;
    std::vector<uint16_t> codes;
    QuantizeConeMap(m, e8, &codes);
    if (m.channels == 8) {  // two RGBA halves side by side (000 §II-D)
        std::vector<uint8_t> px(size_t(m.width) * 2 * size_t(m.height) * 4);
        for (int j = 0; j < m.height; ++j)
            for (int i = 0; i < m.width; ++i)
                for (int c = 0; c < 8; ++c) {
                    const int x = i + (c / 4) * m.width;
                    px[(size_t(j) * size_t(2 * m.width) + size_t(x)) * 4 + size_t(c % 4)] =
                        uint8_t(codes[(size_t(j) * size_t(m.width) + size_t(i)) * 8 + size_t(c)]);
                }
        WriteRgb8Image(path, 2 * m.width, m.height, 4, px.data(), outputs);
        return;
    }
    std::vector<uint8_t> px(codes.size());
    for (size_t i = 0; i < codes.size(); ++i) px[i] = uint8_t(codes[i]);
    WriteRgb8Image(path, m.width, m.height, m.channels, px.data(), outputs);
}

ConeMap LoadExternalConeMap(const std::string& path, ConeKind kind, int channel,
                            int expectWidth, int expectHeight) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw Error("--external \"" + path + "\": cannot open (" + OIIO::geterror() + ")");
    const OIIO::ImageSpec spec = in->spec();
    const int W = spec.width, H = spec.height, nc = spec.nchannels;
    if (expectWidth > 0 && (W != expectWidth || H != expectHeight)) {
        in->close();
        throw Error("--external \"" + path + "\": is " + std::to_string(W) + "x" +
                    std::to_string(H) + ", expected " + std::to_string(expectWidth) + "x" +
                    std::to_string(expectHeight) + " (the height map's size)");
    }
    const int want = channel < 0 ? 4 : 1;
    if ((channel < 0 && nc < 4) || channel >= nc) {
        in->close();
        throw Error("--external \"" + path + "\": has " + std::to_string(nc) +
                    " channels; the ratio channel is missing (GPU Gems 3 maps: ratio in B)");
    }
    std::vector<float> all(size_t(W) * size_t(H) * size_t(nc));
    // 8-bit sources: read the codes and convert like the GPU (unorm8), not OIIO's division.
    const bool is8 = spec.format == OIIO::TypeDesc::UINT8;
    if (is8) {
        std::vector<uint8_t> raw(all.size());
        if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::UINT8, raw.data()))
            throw Error("--external \"" + path + "\": read failed (" + in->geterror() + ")");
        for (size_t i = 0; i < raw.size(); ++i) all[i] = Unorm8ToFloat(raw[i]);
    } else if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, all.data())) {
        throw Error("--external \"" + path + "\": read failed (" + in->geterror() + ")");
    }
    in->close();
    ConeMap m;
    m.kind = kind;
    m.width = W;
    m.height = H;
    m.channels = want;
    m.values.resize(size_t(W) * size_t(H) * size_t(want));
    for (size_t t = 0; t < size_t(W) * size_t(H); ++t)
        for (int c = 0; c < want; ++c) {
            const float v = all[t * size_t(nc) + size_t(channel < 0 ? c : channel)];
            if (!std::isfinite(v) || v < 0.0f)
                throw Error("--external \"" + path + "\": holds a negative or non-finite ratio");
            m.values[t * size_t(want) + size_t(c)] = v;
        }
    return m;
}

}  // namespace reliefsim
