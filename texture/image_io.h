// Loading height maps (OpenImageIO lives only behind this header and texture/image_io.cpp).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "texture/height_field.h"

namespace reliefsim {

class OutputSet;

enum class Channel { Auto, R, G, B, A };
enum class Stores { Height, Depth };

std::optional<Channel> ParseChannel(std::string_view s);
std::optional<Stores> ParseStores(std::string_view s);

/// How an image file becomes a HeightField.
struct MapLoadOptions {
    Channel channel = Channel::Auto;  ///< Auto: the grey channel of a 1-2 channel image, else A
    Stores stores = Stores::Height;   ///< Height: white = top, depth = 1 - value
};

/// Loads PNG, TGA, EXR, TIFF (anything OpenImageIO reads; 8-bit, 16-bit or float).
/// 8-bit sources keep their 8-bit depths (HeightField::depth8). Float values are validated
/// (finite, in [0,1]). Throws Error naming the file on any problem.
HeightField LoadHeightMapFile(const std::string& path, const MapLoadOptions& options);

/// Loads "builtin:NAME[:SIZE]" or a file path.
HeightField LoadHeightMap(const std::string& spec, const MapLoadOptions& options);

/// Writes a float image (1..n channels, row-major, interleaved) to path; format by extension.
/// Channel names are used for EXR. No time stamp is written: equal pixels give equal bytes.
/// The file appears complete or not at all: written to a temporary beside `path` and
/// renamed (core/output_set.h); with `outputs`, staged in that set until the caller commits
/// it. Throws Error naming `path` on failure.
void WriteFloatImage(const std::string& path, int width, int height, int channels,
                     const float* pixels, const std::vector<std::string>& channelNames = {},
                     OutputSet* outputs = nullptr);

/// Writes 8-bit RGB(A) pixels (row-major, interleaved), like WriteFloatImage. Throws Error
/// on failure.
void WriteRgb8Image(const std::string& path, int width, int height, int channels,
                    const uint8_t* pixels, OutputSet* outputs = nullptr);

}  // namespace reliefsim
