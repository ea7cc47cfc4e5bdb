// Height-map loading and image writing through OpenImageIO.
#include "texture/image_io.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <cmath>

#include "core/error.h"
#include "core/output_set.h"
#include "texture/procedural.h"

namespace reliefsim {

namespace OIIO = OIIO_NAMESPACE;

std::optional<Channel> ParseChannel(std::string_view s) {
    if (s == "R" || s == "r") return Channel::R;
    if (s == "G" || s == "g") return Channel::G;
    if (s == "B" || s == "b") return Channel::B;
    if (s == "A" || s == "a") return Channel::A;
    if (s == "auto") return Channel::Auto;
    return std::nullopt;
}

std::optional<Stores> ParseStores(std::string_view s) {
    if (s == "height") return Stores::Height;
    if (s == "depth") return Stores::Depth;
    return std::nullopt;
}

HeightField LoadHeightMapFile(const std::string& path, const MapLoadOptions& options) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        std::string err = OIIO::geterror();
        throw Error("height map \"" + path + "\": cannot open (" +
                    (err.empty() ? std::string("unreadable or unknown format") : err) + ")");
    }
    const OIIO::ImageSpec& spec = in->spec();
    const int w = spec.width, h = spec.height, nc = spec.nchannels;
    if (w <= 0 || h <= 0 || nc <= 0)
        throw Error("height map \"" + path + "\": has zero size");
    int c = 0;
    switch (options.channel) {
        case Channel::Auto: c = nc <= 2 ? 0 : (nc >= 4 ? 3 : -1); break;
        case Channel::R: c = 0; break;
        case Channel::G: c = 1; break;
        case Channel::B: c = 2; break;
        case Channel::A: c = nc == 2 ? 1 : 3; break;
    }
    if (c < 0)
        throw Error("height map \"" + path + "\": has " + std::to_string(nc) +
                    " channels and no alpha; pick one with --map-channel R|G|B");
    if (c >= nc)
        throw Error("height map \"" + path + "\": --map-channel asks for channel " +
                    std::to_string(c) + " but the image has " + std::to_string(nc) +
                    " channels");
    const bool is8 = spec.format.basetype == OIIO::TypeDesc::UINT8;
    const bool flip = options.stores == Stores::Height;
    HeightField hf;
    if (is8) {
        std::vector<uint8_t> px(size_t(w) * size_t(h));
        if (!in->read_image(0, 0, c, c + 1, OIIO::TypeDesc::UINT8, px.data()))
            throw Error("height map \"" + path + "\": cannot read pixels (" + in->geterror() +
                        ")");
        if (flip)
            for (auto& v : px) v = uint8_t(255 - v);
        hf = HeightFieldFromUnorm8(w, h, std::move(px), path);
    } else {
        std::vector<float> px(size_t(w) * size_t(h));
        if (!in->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, px.data()))
            throw Error("height map \"" + path + "\": cannot read pixels (" + in->geterror() +
                        ")");
        for (size_t k = 0; k < px.size(); ++k) {
            if (!std::isfinite(px[k]))
                throw Error("height map \"" + path + "\": texel (" +
                            std::to_string(k % size_t(w)) + ", " +
                            std::to_string(k / size_t(w)) +
                            ") is NaN or infinite; heights must be finite");
            if (flip) px[k] = 1.0f - px[k];
        }
        hf.width = w;
        hf.height = h;
        hf.depth = std::move(px);
        hf.name = path;
    }
    in->close();
    ValidateHeightField(hf);
    return hf;
}

HeightField LoadHeightMap(const std::string& spec, const MapLoadOptions& options) {
    if (spec.rfind("builtin:", 0) == 0) return MakeBuiltinMap(spec);
    if (spec.empty()) throw Error("--map: empty; give a file or builtin:NAME[:SIZE]");
    return LoadHeightMapFile(spec, options);
}

namespace {

/// Writes pixels of `type` to `path` through OpenImageIO (format by extension), staged in
/// `outputs` or, when null, in a set of its own committed here (core/output_set.h).
void WriteImage(const std::string& path, OIIO::ImageSpec spec, OIIO::TypeDesc type,
                const void* pixels, OutputSet* outputs) {
    // EXR and TIFF writers stamp the current time unless DateTime is set; an empty value
    // writes none, so equal pixels give byte-identical files.
    spec.attribute("DateTime", "");
    OutputSet own;
    OutputSet& set = outputs ? *outputs : own;
    const std::string temp = set.Add(path);
    bool ok = false;
    std::string reason;
    {  // the writer is destroyed, its file complete, before anything is renamed
        auto out = OIIO::ImageOutput::create(path);
        if (!out) {
            reason = OIIO::geterror();
        } else {
            ok = out->open(temp, spec) && out->write_image(type, pixels) && out->close();
            if (!ok) reason = out->geterror();
        }
    }
    if (!ok)
        throw Error("\"" + path + "\": cannot write image (" + set.UserFacing(reason) +
                    "); nothing was written");
    if (!outputs) own.Commit();
}

}  // namespace

void WriteFloatImage(const std::string& path, int width, int height, int channels,
                     const float* pixels, const std::vector<std::string>& channelNames,
                     OutputSet* outputs) {
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
    if (!channelNames.empty()) spec.channelnames = channelNames;
    spec.attribute("compression", "zip");
    WriteImage(path, spec, OIIO::TypeDesc::FLOAT, pixels, outputs);
}

void WriteRgb8Image(const std::string& path, int width, int height, int channels,
                    const uint8_t* pixels, OutputSet* outputs) {
    WriteImage(path, OIIO::ImageSpec(width, height, channels, OIIO::TypeDesc::UINT8),
               OIIO::TypeDesc::UINT8, pixels, outputs);
}

}  // namespace reliefsim
