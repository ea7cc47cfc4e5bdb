// Height-map loading and image writing through OpenImageIO.
#include "texture/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <mutex>
#include <sstream>
#include <vector>

#include "core/error.h"
#include "core/memory.h"
#include "core/output_set.h"
#include "core/param_name.h"
#include "texture/procedural.h"

namespace reliefsim {

namespace OIIO = OIIO_NAMESPACE;

namespace {

/// Formats this tool reads height and cone maps from (OpenImageIO plugin names). Anything
/// else OpenImageIO can open (its "null" and "term" pseudo-formats, movies, volumes) is
/// refused: a path ending in ".null" must not become a blank map.
constexpr const char* kImageFormats[] = {"png", "targa", "tiff", "openexr", "jpeg",
                                         "bmp", "hdr",   "pnm",  "webp"};
constexpr const char* kImageFormatList = "PNG, TGA, TIFF, EXR, JPEG, BMP, HDR, PNM, WebP";

std::string Quote(const std::string& s) { return "\"" + s + "\""; }

/// Redirects file descriptor 2 into a temporary file while an image is decoded: libpng's
/// default error handler prints "libpng error: ..." straight to stderr, which would give
/// the user a second, unrelated error line. What was captured goes into our one line.
/// Serialised by a mutex (stderr is process-wide).
class StderrCapture {
  public:
    StderrCapture() : lock_(Mutex()) {
        std::fflush(stderr);
        saved_ = ::dup(2);
        file_ = std::tmpfile();
        if (saved_ >= 0 && file_) ::dup2(::fileno(file_), 2);
    }
    ~StderrCapture() {
        Restore();
        if (file_) std::fclose(file_);
    }
    /// Restores stderr and returns what was written to it meanwhile.
    std::string Finish() {
        Restore();
        std::string text;
        if (file_) {
            std::rewind(file_);
            char buf[512];
            size_t n;
            while ((n = std::fread(buf, 1, sizeof buf, file_)) > 0 && text.size() < 4096)
                text.append(buf, n);
            std::fclose(file_);
            file_ = nullptr;
        }
        return text;
    }
    StderrCapture(const StderrCapture&) = delete;
    StderrCapture& operator=(const StderrCapture&) = delete;

  private:
    static std::mutex& Mutex() {
        static std::mutex m;
        return m;
    }
    void Restore() {
        if (saved_ >= 0) {
            std::fflush(stderr);
            ::dup2(saved_, 2);
            ::close(saved_);
            saved_ = -1;
        }
    }
    std::lock_guard<std::mutex> lock_;
    int saved_ = -1;
    std::FILE* file_ = nullptr;
};

/// A regular file opened once and mapped read-only; OpenImageIO decodes it from memory,
/// so a FIFO, a device or a directory is refused before anything reads from it, and the
/// file is never opened a second time.
class MappedFile {
  public:
    MappedFile(const std::string& path, const std::string& subject) {
        // O_NONBLOCK: opening a FIFO for reading must not wait for a writer.
        fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
        if (fd_ < 0) {
            const int e = errno;
            if (e == ENOENT) throw Error(subject + ": does not exist");
            throw Error(subject + ": cannot open (" + std::strerror(e) + ")");
        }
        struct stat st {};
        if (::fstat(fd_, &st) != 0) {
            const int e = errno;
            ::close(fd_);
            throw Error(subject + ": cannot stat (" + std::strerror(e) + ")");
        }
        const char* kind = S_ISDIR(st.st_mode)    ? "a directory"
                           : S_ISFIFO(st.st_mode) ? "a named pipe (FIFO)"
                           : S_ISCHR(st.st_mode)  ? "a character device"
                           : S_ISBLK(st.st_mode)  ? "a block device"
                           : S_ISSOCK(st.st_mode) ? "a socket"
                           : S_ISREG(st.st_mode)  ? nullptr
                                                  : "not a regular file";
        if (kind) {
            ::close(fd_);
            throw Error(subject + ": is " + kind + "; expected a regular image file (" +
                        kImageFormatList + ")");
        }
        if (st.st_size == 0) {
            ::close(fd_);
            throw Error(subject + ": is empty (0 bytes); expected an image file (" +
                        kImageFormatList + ")");
        }
        size_ = size_t(st.st_size);
        void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd_, 0);
        if (p == MAP_FAILED) {
            const int e = errno;
            ::close(fd_);
            throw Error(subject + ": cannot read (" + std::strerror(e) + ")");
        }
        data_ = p;
    }
    ~MappedFile() {
        if (data_) ::munmap(data_, size_);
        if (fd_ >= 0) ::close(fd_);
    }
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    const void* Data() const { return data_; }
    size_t Size() const { return size_; }

  private:
    int fd_ = -1;
    void* data_ = nullptr;
    size_t size_ = 0;
};

/// OpenEXR sizes its tables from the header's dataWindow while it opens a file, before
/// anything can be checked, so a 400-byte file claiming a vast window costs gigabytes and
/// seconds. This scan reads the headers the way the format defines them (attributes of
/// name, type, int32 size, value, up to an empty name; multi-part files repeat headers up
/// to an empty one) and refuses attributes that run past the end of the file and data
/// windows over kMaxImageSide, before OpenEXR sees the file.
void PrescanExrHeader(const unsigned char* p, size_t n, const std::string& subject) {
    if (n < 8 || !(p[0] == 0x76 && p[1] == 0x2f && p[2] == 0x31 && p[3] == 0x01)) return;
    const bool multipart = (p[5] & 0x10) != 0;  // version field bit 12
    auto bad = [&](const std::string& why) {
        throw Error(subject + ": is not a valid OpenEXR file (" + why + ")");
    };
    auto readString = [&](size_t& o) {
        std::string t;
        while (o < n && p[o] != 0 && t.size() < 256) t += char(p[o++]);
        if (o >= n || p[o] != 0) bad("header truncated or name too long");
        ++o;
        return t;
    };
    auto readInt = [&](size_t o) {
        uint32_t v = uint32_t(p[o]) | uint32_t(p[o + 1]) << 8 | uint32_t(p[o + 2]) << 16 |
                     uint32_t(p[o + 3]) << 24;
        return int32_t(v);
    };
    size_t o = 8;
    for (int part = 0; part < 1024; ++part) {
        if (o >= n) bad("header truncated");
        if (multipart && part > 0 && p[o] == 0) return;  // the empty header ends the list
        for (;;) {
            if (o >= n) bad("header truncated");
            if (p[o] == 0) {  // end of this header
                ++o;
                break;
            }
            const std::string name = readString(o);
            const std::string type = readString(o);
            if (o + 4 > n) bad("header truncated");
            const int32_t size = readInt(o);
            o += 4;
            if (size < 0 || uint64_t(size) > n - o)
                bad("attribute \"" + name + "\" claims " + std::to_string(size) +
                    " bytes, past the end of the file");
            if ((name == "dataWindow" || name == "displayWindow") && type == "box2i" &&
                size == 16) {
                const int64_t w = int64_t(readInt(o + 8)) - readInt(o) + 1;
                const int64_t h = int64_t(readInt(o + 12)) - readInt(o + 4) + 1;
                if (name == "dataWindow" &&
                    (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide))
                    throw Error(subject + ": header says " + std::to_string(w) + "x" +
                                std::to_string(h) + ", outside 1.." +
                                std::to_string(kMaxImageSide) +
                                " pixels a side (llvmpipe's largest texture)");
            }
            o += size_t(size);
        }
        if (!multipart) return;
    }
}

}  // namespace

ImageData ReadImageFile(const std::string& path, const std::string& subject,
                        const ChannelPicker& pickChannels, bool keep8) {
    if (path.empty()) throw Error(subject + ": empty path; give an image file");
    MappedFile file(path, subject);
    PrescanExrHeader(static_cast<const unsigned char*>(file.Data()), file.Size(),
                     subject);
    OIIO::Filesystem::IOMemReader proxy(file.Data(), file.Size());
    StderrCapture capture;
    // Texel values as stored: OIIO would otherwise premultiply colour by alpha on read
    // (PNG, TGA), which a texture upload never does, and the maps of GPU Gems 3 keep the
    // depth in A next to ratios in B.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config, &proxy);
    if (!in) {
        std::string err = OIIO::geterror();
        const std::string printed = capture.Finish();
        if (err.empty()) err = printed;
        throw Error(subject + ": is not a readable image (" +
                    (err.empty() ? std::string("unknown or unsupported format")
                                 : OneLine(err, 400)) +
                    "); expected " + kImageFormatList);
    }
    const std::string format = in->format_name();
    if (std::find_if(std::begin(kImageFormats), std::end(kImageFormats),
                     [&](const char* f) { return format == f; }) ==
        std::end(kImageFormats))
        throw Error(subject + ": format \"" + format +
                    "\" is not an image file format read "
                    "here; expected " +
                    kImageFormatList);
    const OIIO::ImageSpec& spec = in->spec();
    const int64_t w = spec.width, h = spec.height, nc = spec.nchannels;
    if (w <= 0 || h <= 0 || nc <= 0)
        throw Error(subject + ": has zero size (" + std::to_string(w) + "x" +
                    std::to_string(h) + ", " + std::to_string(nc) + " channels)");
    if (w > kMaxImageSide || h > kMaxImageSide)
        throw Error(subject + ": header says " + std::to_string(w) + "x" +
                    std::to_string(h) + ", larger than the " +
                    std::to_string(kMaxImageSide) + "x" + std::to_string(kMaxImageSide) +
                    " limit (llvmpipe's largest texture)");
    if (nc > kMaxImageChannels)
        throw Error(subject + ": header says " + std::to_string(nc) +
                    " channels; at most " + std::to_string(kMaxImageChannels) +
                    " are read");
    if (spec.depth != 1 || spec.deep)
        throw Error(subject + ": is a volume or deep image; expected a flat 2D image");
    if (spec.tile_width > 0 &&
        (int64_t(spec.tile_width) * std::max(1, spec.tile_height) >
             int64_t(kMaxImageSide) * 64 ||
         spec.tile_width > kMaxImageSide || spec.tile_height > kMaxImageSide))
        throw Error(subject + ": header says tiles of " +
                    std::to_string(spec.tile_width) + "x" +
                    std::to_string(spec.tile_height) + " pixels; implausible for a " +
                    std::to_string(w) + "x" + std::to_string(h) + " image");
    const auto [c0, c1] = pickChannels(int(nc));
    RS_CHECK(c0 >= 0 && c1 > c0 && c1 <= nc);
    const bool as8 = keep8 && spec.format.basetype == OIIO::TypeDesc::UINT8;
    // What the decode needs: our copy of the channels plus one decoded image of all
    // channels in the file's type (OpenImageIO's conversion buffer, worst case).
    const uint64_t pixels = uint64_t(w) * uint64_t(h);
    const uint64_t need = pixels * uint64_t(c1 - c0) * (as8 ? 1u : 4u) +
                          pixels * uint64_t(nc) * uint64_t(spec.format.size());
    RequireMemory(need,
                  subject + " (" + std::to_string(w) + "x" + std::to_string(h) + ")",
                  "use a smaller image");
    ImageData img;
    img.width = int(w);
    img.height = int(h);
    img.fileChannels = int(nc);
    img.channels = c1 - c0;
    img.is8 = as8;
    img.format = format;
    bool ok;
    if (as8) {
        img.values8.resize(pixels * size_t(img.channels));
        ok = in->read_image(0, 0, c0, c1, OIIO::TypeDesc::UINT8, img.values8.data());
    } else {
        img.values.resize(pixels * size_t(img.channels));
        ok = in->read_image(0, 0, c0, c1, OIIO::TypeDesc::FLOAT, img.values.data());
    }
    // Decoders report damage (a short strip, data past the end of the file, a JPEG cut
    // off mid-scan) as errors while still returning true with the missing pixels filled:
    // a file that was not read completely is refused.
    std::string err = in->geterror();
    in->close();
    const std::string printed = capture.Finish();
    if (!ok || !err.empty()) {
        if (!printed.empty()) err += "; " + printed;
        throw Error(
            subject + ": is damaged or truncated (" +
            (err.empty() ? std::string("the decoder stopped early") : OneLine(err, 400)) +
            ")");
    }
    return img;
}

DepthField LoadHeightMapFile(const std::string& path, const MapLoadOptions& options) {
    const std::string subject = "height map " + Quote(path);
    auto pick = [&](int nc) -> std::pair<int, int> {
        int c = 0;
        switch (options.channel) {
            case Channel::Auto:
                c = nc <= 2 ? 0 : (nc >= 4 ? 3 : -1);
                break;
            case Channel::R:
                c = 0;
                break;
            case Channel::G:
                c = 1;
                break;
            case Channel::B:
                c = 2;
                break;
            case Channel::A:
                c = nc == 2 ? 1 : 3;
                break;
        }
        if (c < 0)
            throw Error(subject + ": has " + std::to_string(nc) +
                        " channels and no alpha; pick one with " +
                        ParamName("map_channel") + " R|G|B");
        if (c >= nc)
            throw Error(subject + ": " + ParamName("map_channel") + " asks for channel " +
                        "RGBA"[c] + " but the image has " + std::to_string(nc) +
                        " channel" + (nc == 1 ? "" : "s"));
        return {c, c + 1};
    };
    ImageData img = ReadImageFile(path, subject, pick, /*keep8=*/true);
    const bool flip = options.stores == Stores::Height;
    const int w = img.width, h = img.height;
    DepthField hf;
    if (img.is8) {
        if (flip)
            for (auto& v : img.values8) v = uint8_t(255 - v);
        hf = DepthFieldFromUnorm8(w, h, std::move(img.values8), path);
    } else {
        // Validate as the file stores it, so a message shows the value that is in the
        // file.
        for (size_t k = 0; k < img.values.size(); ++k) {
            const float v = img.values[k];
            if (!std::isfinite(v) || v < 0.0f || v > 1.0f) {
                std::ostringstream s;
                s << subject << ": texel (" << k % size_t(w) << ", " << k / size_t(w)
                  << ") holds ";
                if (std::isnan(v))
                    s << "NaN";
                else if (std::isinf(v))
                    s << (v > 0 ? "+Inf" : "-Inf");
                else
                    s << v;
                s << " (as stored in the file); "
                  << (options.stores == Stores::Height ? "heights" : "depths")
                  << " must be finite (no NaN or Inf) and in [0, 1]";
                throw Error(s.str());
            }
            if (flip) img.values[k] = 1.0f - v;
        }
        hf.width = w;
        hf.height = h;
        hf.depth = std::move(img.values);
        hf.name = path;
    }
    ValidateDepthField(hf);
    return hf;
}

DepthField LoadHeightMap(const std::string& spec, const MapLoadOptions& options) {
    if (spec.rfind("builtin:", 0) == 0) return MakeBuiltinMap(spec);
    if (spec.empty())
        throw Error(ParamName("map") + ": empty; give a file or builtin:NAME[:SIZE]");
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
    // Values as given: without this, a PNG writer divides colour by alpha (it takes the
    // pixels for premultiplied), which would change a 4-channel map's ratios.
    spec.attribute("oiio:UnassociatedAlpha", 1);
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
