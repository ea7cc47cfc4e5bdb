// Min and max mip pyramids with wrap-aware 2x2 reductions, for any size (odd sizes
// included).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace reliefsim {

class OutputSet;

enum class MipReduce { Min, Max };

/// One level: width x height texels of `channels` interleaved floats.
struct MipLevel {
    int width = 0, height = 0, channels = 1;
    std::vector<float> values;
    float At(int i, int j, int c = 0) const {
        return values[(size_t(j) * size_t(width) + size_t(i)) * size_t(channels) +
                      size_t(c)];
    }
};

/// Level 0 is the input; level l+1 has ceil(w/2) x ceil(h/2) texels, texel (i, j)
/// reducing the children (2i + a, 2j + b), a, b in {0, 1}, indices wrapped (repeat): for
/// an odd width the last parent also covers child 0, so each parent bounds every child it
/// overlaps. Stops at 1x1. Min of cone ratios is the conservative mip of a cone map (001,
/// "Mipmapping"); Max of heights (= Min of depths) is the maximum mipmap of Tevs et al.
std::vector<MipLevel> BuildMipPyramid(const std::vector<float>& values, int width,
                                      int height, int channels, MipReduce op);

/// Checks that `path` names a file format that holds MIP levels (OpenEXR, ".exr"); throws
/// Error naming the path otherwise (PNG holds one image, and OpenImageIO writes TIFF
/// without MIP levels).
void CheckMipPyramidPath(const std::string& path);

/// Writes a one-channel pyramid (levels as BuildMipPyramid makes them: each ceil(w/2) x
/// ceil(h/2) of the one before, down to 1x1) as one MIP-mapped float OpenEXR: tiled, zip,
/// level rounding ROUND_UP (whose level sizes are exactly the ceil-halving chain),
/// channel "depth", attribute "reliefsim:kind" = `kind` (e.g. "minmip"), no time stamp
/// (equal levels give equal bytes). Atomic like WriteFloatImage; with `outputs`, staged
/// in that set until the caller commits it. Throws Error naming `path`.
void WriteMipPyramidFile(const std::string& path, const std::vector<MipLevel>& levels,
                         std::string_view kind, OutputSet* outputs = nullptr);

/// Reads a file written by WriteMipPyramidFile (or any one-channel MIP-mapped image whose
/// levels follow the ceil-halving chain down to 1x1) back into its levels, bit-exact for
/// float files. Throws Error naming the path when it cannot be read, has more than one
/// channel, lacks levels, has a level of the wrong size, or holds a non-finite value.
std::vector<MipLevel> ReadMipPyramidFile(const std::string& path);

}  // namespace reliefsim
