// MIP pyramids on disk: one MIP-mapped OpenEXR per pyramid, written atomically, read back
// with every level checked.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

#include "core/error.h"
#include "core/file_extension.h"
#include "core/output_set.h"
#include "maps/mip_pyramid.h"

namespace reliefsim {

namespace OIIO = OIIO_NAMESPACE;

namespace {

constexpr int kMaxLevelSide = 1 << 16;  // sanity bound on level 0 read from a file
constexpr int kTileSize = 64;           // EXR tile side; MIP-mapped EXRs must be tiled

std::string Quote(const std::string& s) { return "\"" + s + "\""; }

std::string SizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

}  // namespace

void CheckMipPyramidPath(const std::string& path) {
    const std::string ext = LowerExtension(path);
    if (ext == ".exr") return;
    throw Error(
        Quote(path) + ": " + (ext.empty() ? std::string("no extension") : ext) +
        " cannot hold MIP levels; expected .exr (one MIP-mapped OpenEXR with every "
        "level)" +
        (ext == ".png" ? "; PNG holds a single image" : ""));
}

void WriteMipPyramidFile(const std::string& path, const std::vector<MipLevel>& levels,
                         std::string_view kind, OutputSet* outputs) {
    CheckMipPyramidPath(path);
    if (levels.empty()) throw Error(Quote(path) + ": no MIP levels to write");
    for (size_t l = 0; l < levels.size(); ++l) {
        const MipLevel& v = levels[l];
        const bool sizeOk = l == 0 ? v.width > 0 && v.height > 0
                                   : v.width == (levels[l - 1].width + 1) / 2 &&
                                         v.height == (levels[l - 1].height + 1) / 2;
        if (!sizeOk || v.channels != 1 ||
            v.values.size() != size_t(v.width) * size_t(v.height))
            throw Error(Quote(path) + ": level " + std::to_string(l) + " is " +
                        SizeText(v.width, v.height) + " x" + std::to_string(v.channels) +
                        "; expected one channel and each level ceil(w/2) x ceil(h/2) of "
                        "the one before");
    }
    if (levels.back().width != 1 || levels.back().height != 1)
        throw Error(Quote(path) + ": the last level is " +
                    SizeText(levels.back().width, levels.back().height) +
                    "; expected levels down to 1x1");

    OutputSet own;
    OutputSet& set = outputs ? *outputs : own;
    const std::string temp = set.Add(path);
    std::string reason;
    {  // the writer is destroyed, its file complete, before anything is renamed
        auto out = OIIO::ImageOutput::create("openexr");
        if (!out) {
            reason = OIIO::geterror();
        } else if (!out->supports("mipmap")) {
            reason = "this OpenImageIO writes no MIP-mapped OpenEXR";
        } else {
            for (size_t l = 0; l < levels.size() && reason.empty(); ++l) {
                OIIO::ImageSpec spec(levels[l].width, levels[l].height, 1,
                                     OIIO::TypeDesc::FLOAT);
                spec.channelnames = {"depth"};
                spec.tile_width = spec.tile_height = kTileSize;
                spec.attribute("compression", "zip");
                // OpenImageIO makes a tiled EXR MIP-mapped only for a texture format.
                spec.attribute("textureformat", "Plain Texture");
                spec.attribute("openexr:roundingmode", 1);  // ROUND_UP: ceil(w / 2^l)
                spec.attribute("reliefsim:kind", std::string(kind));
                spec.attribute("DateTime", "");  // an empty value writes no time stamp
                const auto mode = l == 0 ? OIIO::ImageOutput::Create
                                         : OIIO::ImageOutput::AppendMIPLevel;
                if (!out->open(temp, spec, mode) ||
                    !out->write_image(OIIO::TypeDesc::FLOAT, levels[l].values.data()))
                    reason = "level " + std::to_string(l) + ": " + out->geterror();
            }
            if (reason.empty() && !out->close()) reason = out->geterror();
        }
    }
    if (!reason.empty())
        throw Error(Quote(path) + ": cannot write the MIP-mapped file (" +
                    set.UserFacing(reason) + "); nothing was written");
    if (!outputs) own.Commit();
}

std::vector<MipLevel> ReadMipPyramidFile(const std::string& path) {
    const std::string subject = "mip pyramid " + Quote(path);
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw Error(subject +
                    ": not a readable file; expected a MIP-mapped .exr written by "
                    "`reliefsim maps --kind minmip|maxmip`");
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        throw Error(subject + ": cannot open (" + OIIO::geterror() +
                    "); expected a MIP-mapped .exr written by `reliefsim maps --kind "
                    "minmip|maxmip`");
    std::vector<MipLevel> levels;
    for (int l = 0; in->seek_subimage(0, l); ++l) {
        const OIIO::ImageSpec& spec = in->spec();
        const std::string where = subject + ": level " + std::to_string(l);
        if (spec.nchannels != 1)
            throw Error(where + " has " + std::to_string(spec.nchannels) +
                        " channels; expected 1 (depth)");
        if (spec.depth > 1 || spec.width < 1 || spec.height < 1 ||
            spec.width > kMaxLevelSide || spec.height > kMaxLevelSide)
            throw Error(where + " is " + SizeText(spec.width, spec.height) +
                        "; expected a 2D level of 1 to " + std::to_string(kMaxLevelSide) +
                        " texels per side");
        if (l > 0) {
            const int w = (levels.back().width + 1) / 2,
                      h = (levels.back().height + 1) / 2;
            if (spec.width != w || spec.height != h)
                throw Error(where + " is " + SizeText(spec.width, spec.height) +
                            "; expected " + SizeText(w, h) +
                            " (each level ceil(w/2) x ceil(h/2) of the one before)");
        }
        MipLevel level;
        level.width = spec.width;
        level.height = spec.height;
        level.channels = 1;
        level.values.resize(size_t(spec.width) * size_t(spec.height));
        if (!in->read_image(0, l, 0, 1, OIIO::TypeDesc::FLOAT, level.values.data()))
            throw Error(where + ": cannot read pixels (" + in->geterror() +
                        "); expected an intact file");
        const auto bad = std::find_if(level.values.begin(), level.values.end(),
                                      [](float v) { return !std::isfinite(v); });
        if (bad != level.values.end()) {
            const size_t t = size_t(bad - level.values.begin());
            throw Error(where + " texel (" + std::to_string(t % size_t(spec.width)) +
                        ", " + std::to_string(t / size_t(spec.width)) +
                        ") is not finite; expected finite depths");
        }
        levels.push_back(std::move(level));
        if (levels.back().width == 1 && levels.back().height == 1) break;
    }
    if (levels.empty())
        throw Error(subject + ": holds no image; expected MIP levels down to 1x1");
    if (levels.back().width != 1 || levels.back().height != 1)
        throw Error(
            subject + ": has " + std::to_string(levels.size()) + " level(s), the last " +
            SizeText(levels.back().width, levels.back().height) +
            "; expected MIP levels down to 1x1 (written by `reliefsim maps --kind "
            "minmip|maxmip`)");
    return levels;
}

}  // namespace reliefsim
