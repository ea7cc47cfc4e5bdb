// Heatmap PNGs with a fixed-range legend, colour PNGs and multi-channel EXRs.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace reliefsim {

class OutputSet;

/// How values become colours in WriteHeatmapPng. The range is fixed and explicit: a value
/// v maps to t = clamp((v - min) / (max - min), 0, 1) and then through the colormap.
/// Images are never normalised on their own, so two heatmaps written with the same scale
/// compare colour for colour (STYLE.md §4). min and max must be finite with max > min.
struct HeatmapScale {
    float min = 0.0f;  // value drawn with the colormap's first colour (t = 0)
    float max = 1.0f;  // value drawn with the colormap's last colour (t = 1)
    // Any name OIIO::ImageBufAlgo::color_map accepts: "inferno", "viridis", "magma",
    // "plasma", "turbo", "blue-red", "spectrum", "heat".
    std::string colormap = "inferno";
    std::string label;  // legend title, e.g. "iterations (coarse + refine)"; may be empty
};

/// Writes an RGB 8-bit PNG heatmap of `values` (width x height floats, row-major, row 0
/// at the top) coloured through scale.colormap over the fixed range
/// [scale.min, scale.max], with a colour legend beside it.
///
/// Layout (all sizes in pixels; the output is larger than width x height):
///  * The heatmap sits unscaled at the top-left corner: output pixel (x, y) with
///    x < width and y < height is input pixel (x, y). Pixels with mask[i] == 0 are dark
///    grey (40, 40, 40), as are NaN values ("no data"); +-inf clamp to the ends of the
///    range. `mask` may be null (every pixel valid).
///  * The legend is a white panel. If height >= 128 it is a strip to the right of the
///    image, as tall as the image; otherwise (a short image cannot hold a readable bar)
///    it is a block 160 pixels tall below the image, and the output is as wide as the
///    wider of the two. Everything outside the image and the panel is white.
///  * Inside the panel, left to right: a vertical colour bar (scale.max at the top,
///    scale.min at the bottom; row i of its n rows holds t = 1 - i / (n - 1), a vertical
///    gradient fill put through the same color_map as the image; framed one pixel wide
///    in black), tick marks with labels at min, max and "nice" values in between (1, 2 or
///    5 x 10^k steps, about 5 intervals, none crowding an end label; integers when min
///    and max are integers at least 2 apart), and scale.label written along the bar,
///    reading bottom to top, its font shrunk (down to 9 px) to fit the bar's length. The
///    panel is as wide as the bar, the widest tick label and the label text need.
///  * Text uses DejaVuSans through OIIO's FreeType text renderer, with the font size
///    growing with the image height (12 to 22 px). If no TrueType font can be loaded (or
///    FreeType fails), the text is left out; the bar, its frame and the tick marks stay.
///  * min, max, colormap and label are also recorded as PNG text metadata
///    ("reliefsim:min" and "reliefsim:max" as %.9g text, "reliefsim:colormap",
///    "reliefsim:label").
///
/// The file is written to a temporary beside `path` and renamed onto it
/// (core/output_set.h), so no partial file is left behind. With `outputs`, the file is
/// staged in that set instead and appears only when the caller commits the set. Throws
/// Error (naming the path) for bad arguments, an unknown colormap or a failed write.
void WriteHeatmapPng(const std::string& path, const float* values, const uint8_t* mask,
                     int width, int height, const HeatmapScale& scale,
                     OutputSet* outputs = nullptr);

/// Writes an RGB 8-bit PNG of an already coloured image: `rgb` holds width x height
/// pixels of 3 floats in [0, 1] (clamped; row-major, row 0 at the top). Same atomic-write
/// and error rules as WriteHeatmapPng.
void WriteColorPng(const std::string& path, const float* rgb, int width, int height,
                   OutputSet* outputs = nullptr);

/// Writes a float32 OpenEXR with one named channel per plane (zip compression). Each
/// plane holds width x height floats, row-major, row 0 at the top. Names must be
/// non-empty, unique and contain no newline. EXR files store channels sorted by name; the
/// given order is kept in the "reliefsim:channelOrder" attribute, and ReadMultiChannelExr
/// restores it. No time stamp is written, so equal inputs give byte-identical files. Same
/// atomic-write and error rules as WriteHeatmapPng.
void WriteMultiChannelExr(const std::string& path, int width, int height,
                          const std::vector<std::string>& channelNames,
                          const std::vector<const float*>& planes,
                          OutputSet* outputs = nullptr);

/// One channel of WriteMultiChannelExr: width x height values, either floats (stored as
/// FLOAT) or counts (stored as 32-bit UINT, which EXR has: exact at any size).
struct ExrChannel {
    std::string name;
    const float* values = nullptr;
    const uint32_t* counts = nullptr;
};

/// WriteMultiChannelExr with a pixel type per channel (FLOAT or UINT).
void WriteMultiChannelExr(const std::string& path, int width, int height,
                          const std::vector<ExrChannel>& channels,
                          OutputSet* outputs = nullptr);

/// The contents of a multi-channel EXR: planes[i] (width x height floats, row 0 at the
/// top) is the channel called names[i].
struct ExrPlanes {
    int width = 0, height = 0;               // in pixels
    std::vector<std::string> names;          // channel names
    std::vector<std::vector<float>> planes;  // one plane per name, same order
};

/// Reads an EXR (or any image OIIO reads) as float planes (UINT channels converted: exact
/// below 2^24): in the order written by
/// WriteMultiChannelExr when the file carries that order, else in file order. Values are
/// bit-exact for float32 files. Throws Error naming the path on failure.
ExrPlanes ReadMultiChannelExr(const std::string& path);

}  // namespace reliefsim
