// Loading height maps (OpenImageIO lives only behind this header and
// texture/image_io.cpp).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/enum_names.h"
#include "texture/depth_field.h"

namespace reliefsim {

class OutputSet;

enum class Channel { Auto, R, G, B, A };
enum class Stores { Height, Depth };

/// --map-channel's names; letters match in either case ("r" is R).
inline constexpr auto kChannelNames = MakeEnumNames<Channel>(
    {
        {"R", Channel::R},
        {"G", Channel::G},
        {"B", Channel::B},
        {"A", Channel::A},
        {"auto", Channel::Auto},
    },
    /*ignoreCase=*/true);
inline constexpr auto kStoresNames = MakeEnumNames<Stores>({
    {"height", Stores::Height},
    {"depth", Stores::Depth},
});

inline std::optional<Channel> ParseChannel(std::string_view s) {
    return kChannelNames.Parse(s);
}
inline std::optional<Stores> ParseStores(std::string_view s) {
    return kStoresNames.Parse(s);
}
inline std::string_view ToString(Channel c) { return kChannelNames.Name(c); }
inline std::string_view ToString(Stores s) { return kStoresNames.Name(s); }

/// How an image file becomes a DepthField.
struct MapLoadOptions {
    Channel channel =
        Channel::Auto;  ///< Auto: the grey channel of a 1-2 channel image, else A
    Stores stores = Stores::Height;  ///< Height: white = top, depth = 1 - value
};

/// Largest width or height of an image file that is read (llvmpipe's GL_MAX_TEXTURE_SIZE,
/// so every map has a GL twin). Checked from the header, before any pixel is decoded.
constexpr int kMaxImageSide = 16384;
/// Most channels an image file may declare.
constexpr int kMaxImageChannels = 64;

/// The channels of an image file that ReadImageFile decoded.
struct ImageData {
    int width = 0, height = 0;
    int channels = 0;      ///< channels read (interleaved)
    int fileChannels = 0;  ///< channels in the file
    bool is8 = false;      ///< values8 holds the file's 8-bit codes; else values (float)
    std::vector<uint8_t> values8;
    std::vector<float> values;  ///< OpenImageIO's conversion: unorm -> [0,1], float as is
    std::string format;         ///< OpenImageIO format name ("png", "openexr", ...)
};

/// Given the file's channel count, returns the half-open channel range [first, end) to
/// read, or throws Error.
using ChannelPicker = std::function<std::pair<int, int>(int fileChannels)>;

/// Reads one image file, robustly: it must be a regular file (no directory, FIFO,
/// device), opened once and decoded from memory; of a format in the documented list (PNG,
/// TGA, TIFF, EXR, JPEG, BMP, HDR, PNM, WebP); with a header within kMaxImageSide per
/// side and kMaxImageChannels, checked (and the memory it needs) before pixels are
/// decoded; and decoded completely (a truncated or damaged file, even one the decoder
/// "recovers", is refused). keep8: 8-bit files keep their codes in values8. Every failure
/// is one Error line beginning with `subject` (e.g. `height map "rock.png"`); third-party
/// decoder text printed to stderr meanwhile is folded into it.
ImageData ReadImageFile(const std::string& path, const std::string& subject,
                        const ChannelPicker& pickChannels, bool keep8);

/// Loads PNG, TGA, EXR, TIFF (anything OpenImageIO reads; 8-bit, 16-bit or float).
/// 8-bit sources keep their 8-bit depths (DepthField::depth8). Float values are
/// validated (finite, in [0,1]). Throws Error naming the file on any problem.
DepthField LoadHeightMapFile(const std::string& path, const MapLoadOptions& options);

/// Loads "builtin:NAME[:SIZE]" or a file path.
DepthField LoadHeightMap(const std::string& spec, const MapLoadOptions& options);

/// Writes a float image (1..n channels, row-major, interleaved) to path; format by
/// extension. Channel names are used for EXR. No time stamp is written: equal pixels give
/// equal bytes. The file appears complete or not at all: written to a temporary beside
/// `path` and renamed (core/output_set.h); with `outputs`, staged in that set until the
/// caller commits it. Throws Error naming `path` on failure.
void WriteFloatImage(const std::string& path, int width, int height, int channels,
                     const float* pixels,
                     const std::vector<std::string>& channelNames = {},
                     OutputSet* outputs = nullptr);

/// Writes 8-bit RGB(A) pixels (row-major, interleaved), like WriteFloatImage. Throws
/// Error on failure.
void WriteRgb8Image(const std::string& path, int width, int height, int channels,
                    const uint8_t* pixels, OutputSet* outputs = nullptr);

}  // namespace reliefsim
