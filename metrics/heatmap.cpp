// Heatmap PNGs with a fixed-range legend, colour PNGs and multi-channel EXRs.
#include "metrics/heatmap.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <set>

#include "core/error.h"
#include "core/output_set.h"

namespace OIIO = OIIO_NAMESPACE;

namespace reliefsim {
namespace {

constexpr const char* kFontPath = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
constexpr int kMinHeightForRightLegend = 128;  // shorter images get the legend below
constexpr int kBelowLegendHeight = 160;        // panel height when placed below
constexpr float kMaskGrey = 40.0f / 255.0f;  // masked / NaN pixels, exactly 40 in 8 bits
constexpr const char* kColormapNames =
    "\"inferno\", \"viridis\", \"magma\", \"plasma\", \"turbo\", \"blue-red\", "
    "\"spectrum\", \"heat\"";
constexpr const char* kChannelOrderAttr = "reliefsim:channelOrder";

std::string Quote(const std::string& s) { return "\"" + s + "\""; }

/// Writes `path` through `write(tempPath)`, staged in `outputs` (committed by the caller
/// with the rest of its files) or, when null, in a set of its own committed here. Errors
/// name `path`, never the temporary. `write` returns an empty string on success, else the
/// reason.
template <typename WriteFn>
void WriteStaged(const std::string& what, const std::string& path, OutputSet* outputs,
                 WriteFn&& write) {
    OutputSet own(what);
    OutputSet& set = outputs ? *outputs : own;
    const std::string reason = write(set.Add(path));
    if (!reason.empty())
        throw Error(what + " " + Quote(path) + ": cannot write (" +
                    set.UserFacing(reason) +
                    "); nothing was written; hint: check the free space");
    if (!outputs) own.Commit();
}

/// Writes float pixels (spec.nchannels interleaved, row 0 at the top) to `tempPath` in
/// the given OIIO format, converting to spec.format. Returns "" on success, else the
/// reason.
std::string WriteImageFile(const std::string& tempPath, const char* format,
                           const OIIO::ImageSpec& spec, const void* pixels,
                           OIIO::TypeDesc type = OIIO::TypeDesc::FLOAT) {
    auto out = OIIO::ImageOutput::create(format);
    if (!out) return "no " + std::string(format) + " writer: " + OIIO::geterror();
    if (!out->open(tempPath, spec)) {
        std::string err = out->geterror();
        return err.empty() ? OIIO::geterror() : err;
    }
    const bool ok = out->write_image(type, pixels);
    std::string err = ok ? std::string() : out->geterror();
    if (!out->close() && err.empty()) err = out->geterror();
    if (!ok && err.empty()) err = "write_image failed";
    return err;
}

void CheckSize(const std::string& what, const std::string& path, int width, int height) {
    if (width <= 0 || height <= 0)
        throw Error(what + " " + Quote(path) + ": size " + std::to_string(width) + "x" +
                    std::to_string(height) +
                    " is empty; expected width > 0 and height > 0");
}

// ---- Drawing -------------------------------------------------------------------------
// The output is assembled in an RGB float ImageBuf (row 0 at the top, pixel (0, 0) at the
// top-left, ROI ends exclusive but render_box/render_line corners inclusive) and
// converted to 8 bits only when written, so image and colour bar keep color_map's exact
// floats.

namespace IBA = OIIO::ImageBufAlgo;

constexpr float kWhite[3] = {1.0f, 1.0f, 1.0f};
constexpr float kBlack[3] = {0.0f, 0.0f, 0.0f};
constexpr float kGrey[3] = {kMaskGrey, kMaskGrey, kMaskGrey};

/// The TrueType font used for legend text, or "" when none can be loaded (then the
/// legend has no text, only the bar and its ticks). Probed once per process.
const std::string& LegendFont() {
    static const std::string font = [] {
        std::string found;
        for (const char* candidate : {kFontPath, "DejaVuSans", ""}) {
            if (IBA::text_size("0.5", 12, candidate).defined()) {
                found = candidate[0] ? candidate : "<default>";
                break;
            }
        }
        OIIO::geterror();  // clear the errors of failed candidates
        return found;
    }();
    return font;
}

/// OIIO font argument for LegendFont() ("<default>" means OIIO's own search).
std::string FontArg() {
    const std::string& f = LegendFont();
    return f == "<default>" ? std::string() : f;
}

/// Width in pixels of `text` at `fontSize`; 0 without a font (the text is left out).
int TextWidth(const std::string& text, int fontSize) {
    if (LegendFont().empty() || text.empty()) return 0;
    const OIIO::ROI r = IBA::text_size(text, fontSize, FontArg());
    return r.defined() ? r.width() : 0;
}

/// Draws black `text` with its left edge at x, vertically centred on y. Without a font,
/// or if FreeType fails, the text is left out and the canvas is unchanged.
void DrawText(OIIO::ImageBuf& canvas, int x, int y, const std::string& text,
              int fontSize) {
    if (LegendFont().empty() || text.empty()) return;
    if (!IBA::render_text(canvas, x, y, text, fontSize, FontArg(), kBlack,
                          IBA::TextAlignX::Left, IBA::TextAlignY::Center))
        canvas.geterror();  // clear it: a legend without this label is still usable
}

/// Draws black `text` on white, rotated to read bottom to top, centred on (cx, cy).
/// render_text cannot rotate, so the text is rendered into a buffer of its own, turned
/// with rotate270 and pasted. Without a font, or if FreeType fails, nothing is drawn.
void DrawVerticalText(OIIO::ImageBuf& canvas, int cx, int cy, const std::string& text,
                      int fontSize) {
    if (LegendFont().empty() || text.empty()) return;
    const OIIO::ROI size = IBA::text_size(text, fontSize, FontArg());
    if (!size.defined()) return;
    const int w = size.width() + 4, h = size.height() + 4;  // 2 px margin each side
    OIIO::ImageBuf line = IBA::fill(kWhite, OIIO::ROI(0, w, 0, h, 0, 1, 0, 3));
    // text_size is relative to the baseline's left end; shift its box to (2, 2).
    if (!IBA::render_text(line, 2 - size.xbegin, 2 - size.ybegin, text, fontSize,
                          FontArg(), kBlack))
        return;
    // rotate270 turns the row "AB" into the column B-over-A: the text reads upwards.
    OIIO::ImageBuf rotated = IBA::rotate270(line);
    rotated.set_origin(0, 0);  // paste() places the buffer's (0, 0); it is h wide, w tall
    IBA::paste(canvas, cx - h / 2, cy - w / 2, 0, 0, rotated);
}

// ---- Ticks ---------------------------------------------------------------------------

struct Tick {
    double value;
    std::string text;
};

bool IsIntegral(double v) { return std::isfinite(v) && std::floor(v) == v; }

/// Formats a tick value with `decimals` digits after the point. Values off that grid (the
/// range ends need not be round numbers) get 6 significant digits instead, so an end is
/// never printed as a different number.
std::string FormatValue(double v, int decimals) {
    char buf[64];
    const double a = std::abs(v), unit = std::pow(10.0, -decimals);
    if (a != 0.0 && (a >= 1e7 || a < 1e-4))
        std::snprintf(buf, sizeof(buf), "%.6g", v);
    else if (std::abs(v / unit - std::round(v / unit)) > 1e-6)
        std::snprintf(buf, sizeof(buf), "%.6g", v);
    else
        std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
    return buf;
}

/// Ticks at lo, hi and at multiples of a 1/2/5 x 10^k step strictly between them, aiming
/// at `targetIntervals` intervals. An interior tick closer than `minGap` (in units of
/// value) to an end is dropped so that labels do not overlap. Integral ranges (integer lo
/// and hi at least 2 apart) get integer ticks.
std::vector<Tick> ComputeTicks(double lo, double hi, int targetIntervals, double minGap) {
    const bool integral = IsIntegral(lo) && IsIntegral(hi) && hi - lo >= 2.0;
    const double raw = (hi - lo) / double(std::max(1, targetIntervals));
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double r = raw / mag;
    double step = (r < 1.5 ? 1.0 : r < 3.0 ? 2.0 : r < 7.0 ? 5.0 : 10.0) * mag;
    if (integral) step = std::max(1.0, std::round(step));
    const int decimals =
        integral ? 0 : std::clamp(int(-std::floor(std::log10(step) + 1e-9)), 0, 6);

    std::vector<Tick> ticks{{lo, FormatValue(lo, decimals)}};
    for (double k = std::ceil(lo / step); k * step < hi; k += 1.0) {
        double v = k * step;
        if (v - lo < minGap || hi - v < minGap) continue;
        if (std::abs(v) < 0.5 * step) v = 0.0;  // k == -0.0 or rounding: never print "-0"
        ticks.push_back({v, FormatValue(v, decimals)});
    }
    ticks.push_back({hi, FormatValue(hi, decimals)});
    return ticks;
}

// ---- Colour mapping ------------------------------------------------------------------

/// color_map of the single-channel `t` image through `colormap`, as RGB floats. Both the
/// heatmap and its colour bar go through here, so equal t gives equal colours. Throws
/// Error for an unknown colormap.
OIIO::ImageBuf ColorMapT(const std::string& path, const OIIO::ImageBuf& t,
                         const std::string& colormap) {
    OIIO::ImageBuf rgb = IBA::color_map(t, 0, colormap);
    if (rgb.has_error() || rgb.nchannels() != 3)
        throw Error("heatmap " + Quote(path) + ": colormap " + Quote(colormap) +
                    " is unknown (" + rgb.geterror() +
                    "); must be one of: " + kColormapNames);
    return rgb;
}

/// The heatmap: t = clamp((v - min) / (max - min), 0, 1) through the colormap, with NaN
/// and masked pixels grey.
OIIO::ImageBuf MapColors(const std::string& path, const float* values,
                         const uint8_t* mask, int width, int height,
                         const HeatmapScale& scale) {
    const size_t n = size_t(width) * size_t(height);
    const double lo = double(scale.min), range = double(scale.max) - double(scale.min);
    std::vector<float> t(n);
    for (size_t i = 0; i < n; ++i) {
        const double v = double(values[i]);
        t[i] = std::isnan(v) ? 0.0f : float(std::clamp((v - lo) / range, 0.0, 1.0));
    }
    const OIIO::ImageBuf tBuf(OIIO::ImageSpec(width, height, 1, OIIO::TypeDesc::FLOAT),
                              t.data());
    OIIO::ImageBuf rgb = ColorMapT(path, tBuf, scale.colormap);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            if ((mask && mask[i] == 0) || std::isnan(values[i]))
                rgb.setpixel(x, y, kGrey);
        }
    return rgb;
}

/// The colour bar, barWidth x barLength: a vertical gradient fill of t from 1 (top row)
/// to 0 (bottom row), so row i holds t = 1 - i / (barLength - 1), through ColorMapT.
OIIO::ImageBuf ColorBar(const std::string& path, int barWidth, int barLength,
                        const std::string& colormap) {
    const float top[1] = {1.0f}, bottom[1] = {0.0f};
    const OIIO::ImageBuf t =
        IBA::fill(top, bottom, OIIO::ROI(0, barWidth, 0, barLength, 0, 1, 0, 1));
    return ColorMapT(path, t, colormap);
}

}  // namespace

void WriteHeatmapPng(const std::string& path, const float* values, const uint8_t* mask,
                     int width, int height, const HeatmapScale& scale,
                     OutputSet* outputs) {
    CheckSize("heatmap", path, width, height);
    if (!values)
        throw Error("heatmap " + Quote(path) + ": values is null; expected data");
    if (!std::isfinite(scale.min) || !std::isfinite(scale.max) ||
        !(scale.max > scale.min))
        throw Error("heatmap " + Quote(path) + ": scale [" + std::to_string(scale.min) +
                    ", " + std::to_string(scale.max) +
                    "] is invalid; expected finite min < max; hint: pass the fixed range "
                    "shared by all images that are compared, never a per-image one");
    const OIIO::ImageBuf image = MapColors(path, values, mask, width, height, scale);

    // Legend geometry (see heatmap.h). The panel is laid out in its own coordinates.
    const bool right = height >= kMinHeightForRightLegend;
    const int fontSize = right ? std::clamp(height / 32, 12, 22) : 12;
    const int pad = std::max(6, fontSize / 2);
    const int barWidth = std::max(12, fontSize);
    const int tickLength = std::max(3, fontSize / 4);
    const int gap = std::max(3, fontSize / 3);
    const int panelHeight = right ? height : kBelowLegendHeight;
    const int barTop = pad + fontSize * 2 / 3;  // room for half a label above max
    const int barBottom = panelHeight - 1 - barTop;
    const int barLength = barBottom - barTop + 1;
    // About 5 intervals, fewer on short bars; labels keep 1.3 font heights apart.
    const double range = double(scale.max) - double(scale.min);
    const int targetIntervals =
        std::clamp(int(double(barLength) / (2.5 * fontSize)), 1, 5);
    const std::vector<Tick> ticks =
        ComputeTicks(double(scale.min), double(scale.max), targetIntervals,
                     1.3 * fontSize * range / double(std::max(1, barLength - 1)));
    int tickTextWidth = 0;
    for (const Tick& t : ticks)
        tickTextWidth = std::max(tickTextWidth, TextWidth(t.text, fontSize));
    // The label runs along the bar; shrink its font until it fits the bar's length.
    int labelSize = fontSize;
    const bool hasLabel = TextWidth(scale.label, labelSize) > 0;
    while (hasLabel && labelSize > 9 && TextWidth(scale.label, labelSize) > barLength)
        --labelSize;
    const int labelThickness = hasLabel ? labelSize * 5 / 4 + 4 : 0;

    const int barX = pad + 1;               // + 1 for the frame
    const int tickX = barX + barWidth + 1;  // first tick pixel, right of the frame
    const int tickTextX = tickX + tickLength + gap;
    const int labelCenterX = tickTextX + tickTextWidth + 2 * gap + labelThickness / 2;
    const int panelWidth =
        tickTextX + tickTextWidth + (hasLabel ? 2 * gap + labelThickness : 0) + pad;

    // Panel coordinates (px, py) are canvas (panelX + px, panelY + py).
    const int panelX = right ? width : 0, panelY = right ? 0 : height;
    OIIO::ImageBuf canvas = IBA::fill(
        kWhite, OIIO::ROI(0, right ? width + panelWidth : std::max(width, panelWidth), 0,
                          right ? height : height + panelHeight, 0, 1, 0, 3));
    IBA::paste(canvas, 0, 0, 0, 0, image);

    // Colour bar rows barTop..barBottom, framed by a one-pixel black box just outside.
    IBA::paste(canvas, panelX + barX, panelY + barTop, 0, 0,
               ColorBar(path, barWidth, barLength, scale.colormap));
    IBA::render_box(canvas, panelX + barX - 1, panelY + barTop - 1,
                    panelX + barX + barWidth, panelY + barBottom + 1, kBlack);

    // Ticks at the row whose t is the tick's, and their labels.
    for (const Tick& t : ticks) {
        const int y = panelY + barBottom -
                      int(std::lround((t.value - double(scale.min)) / range *
                                      double(barLength - 1)));
        IBA::render_line(canvas, panelX + tickX, y, panelX + tickX + tickLength - 1, y,
                         kBlack);
        DrawText(canvas, panelX + tickTextX, y, t.text, fontSize);
    }
    if (hasLabel)
        DrawVerticalText(canvas, panelX + labelCenterX, panelY + (barTop + barBottom) / 2,
                         scale.label, labelSize);
    if (canvas.has_error())
        throw Error("heatmap " + Quote(path) + ": cannot draw the legend (" +
                    canvas.geterror() + "); nothing was written");

    const OIIO::ImageSpec& cs = canvas.spec();
    OIIO::ImageSpec spec(cs.width, cs.height, 3, OIIO::TypeDesc::UINT8);
    // PNG text chunks hold strings only; %.9g round-trips a float exactly.
    char minText[32], maxText[32];
    std::snprintf(minText, sizeof(minText), "%.9g", double(scale.min));
    std::snprintf(maxText, sizeof(maxText), "%.9g", double(scale.max));
    spec.attribute("reliefsim:min", minText);
    spec.attribute("reliefsim:max", maxText);
    spec.attribute("reliefsim:colormap", scale.colormap);
    spec.attribute("reliefsim:label", scale.label);
    // canvas owns contiguous float RGB pixels (IBA::fill allocated it).
    const float* pixels = static_cast<const float*>(canvas.localpixels());
    WriteStaged("heatmap", path, outputs, [&](const std::string& tempPath) {
        return WriteImageFile(tempPath, "png", spec, pixels);
    });
}

void WriteColorPng(const std::string& path, const float* rgb, int width, int height,
                   OutputSet* outputs) {
    CheckSize("color png", path, width, height);
    if (!rgb) throw Error("color png " + Quote(path) + ": rgb is null; expected data");
    const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    WriteStaged("color png", path, outputs, [&](const std::string& tempPath) {
        return WriteImageFile(tempPath, "png", spec, rgb);
    });
}

void WriteMultiChannelExr(const std::string& path, int width, int height,
                          const std::vector<std::string>& channelNames,
                          const std::vector<const float*>& planes, OutputSet* outputs) {
    if (channelNames.size() != planes.size())
        throw Error("exr " + Quote(path) + ": " + std::to_string(channelNames.size()) +
                    " channel names for " + std::to_string(planes.size()) +
                    " planes; expected one name per plane and at least one plane");
    std::vector<ExrChannel> channels;
    for (size_t c = 0; c < planes.size(); ++c)
        channels.push_back({channelNames[c], planes[c], nullptr});
    WriteMultiChannelExr(path, width, height, channels, outputs);
}

void WriteMultiChannelExr(const std::string& path, int width, int height,
                          const std::vector<ExrChannel>& channels, OutputSet* outputs) {
    CheckSize("exr", path, width, height);
    if (channels.empty())
        throw Error("exr " + Quote(path) +
                    ": 0 channels; expected one name per plane and at least one plane");
    std::set<std::string> seen;
    std::string order;
    std::vector<std::string> names;
    std::vector<OIIO::TypeDesc> formats;
    for (size_t c = 0; c < channels.size(); ++c) {
        const std::string& name = channels[c].name;
        if (name.empty() || name.find('\n') != std::string::npos ||
            !seen.insert(name).second)
            throw Error("exr " + Quote(path) + ": channel name " + Quote(name) +
                        " is empty, repeated or has a newline; expected unique names");
        if (!channels[c].values == !channels[c].counts)
            throw Error("exr " + Quote(path) + ": plane " + Quote(name) +
                        " is null; expected width*height floats or counts");
        order += (c ? "\n" : "") + name;
        names.push_back(name);
        formats.push_back(channels[c].counts ? OIIO::TypeDesc::UINT32
                                             : OIIO::TypeDesc::FLOAT);
    }
    // Both pixel types are 4 bytes: each pixel's channels are 32-bit words, in the
    // channels' native formats (what write_image takes for per-channel formats).
    const size_t n = size_t(width) * size_t(height), nc = channels.size();
    std::vector<uint32_t> interleaved(n * nc);
    for (size_t c = 0; c < nc; ++c) {
        const ExrChannel& ch = channels[c];
        for (size_t i = 0; i < n; ++i) {
            uint32_t word;
            if (ch.counts)
                word = ch.counts[i];
            else
                std::memcpy(&word, &ch.values[i], sizeof word);
            interleaved[i * nc + c] = word;
        }
    }
    const bool mixed =
        std::any_of(channels.begin(), channels.end(),
                    [](const ExrChannel& ch) { return ch.counts != nullptr; });
    OIIO::ImageSpec spec(width, height, int(nc), OIIO::TypeDesc::FLOAT);
    spec.channelnames = names;
    if (mixed) spec.channelformats = formats;
    spec.alpha_channel = -1;  // a channel named "A" is data here, not coverage
    spec.attribute("compression", "zip");
    spec.attribute(kChannelOrderAttr, order);
    // OpenImageIO stamps EXRs with the current time unless DateTime is set; an empty
    // value writes none, so the same record gives the same bytes on every run.
    spec.attribute("DateTime", "");
    WriteStaged("exr", path, outputs, [&](const std::string& tempPath) {
        return WriteImageFile(tempPath, "openexr", spec, interleaved.data(),
                              mixed ? OIIO::TypeDesc::UNKNOWN : OIIO::TypeDesc::FLOAT);
    });
}

ExrPlanes ReadMultiChannelExr(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        throw Error("exr " + Quote(path) + ": cannot open (" + OIIO::geterror() +
                    "); expected a readable image file");
    const OIIO::ImageSpec spec = in->spec();
    const int nc = spec.nchannels;
    const size_t n = size_t(spec.width) * size_t(spec.height);
    // UINT channels (counts) are read as their integers: OpenImageIO's conversion to
    // float would normalise them to [0, 1]. A file of FLOAT and UINT channels only is
    // read in its native 4-byte words; anything else is converted to float.
    auto isUint = [&](int c) {
        return size_t(c) < spec.channelformats.size() &&
               spec.channelformats[size_t(c)] == OIIO::TypeDesc::UINT32;
    };
    bool native = !spec.channelformats.empty();
    for (int c = 0; c < nc && native; ++c)
        native = isUint(c) || spec.channelformats[size_t(c)] == OIIO::TypeDesc::FLOAT;
    std::vector<float> interleaved(n * size_t(nc));
    if (!in->read_image(0, 0, 0, nc,
                        native ? OIIO::TypeDesc::UNKNOWN : OIIO::TypeDesc::FLOAT,
                        interleaved.data()))
        throw Error("exr " + Quote(path) + ": cannot read pixels (" + in->geterror() +
                    "); expected an intact file");
    if (native)
        for (int c = 0; c < nc; ++c) {
            if (!isUint(c)) continue;
            for (size_t i = 0; i < n; ++i) {
                float& v = interleaved[i * size_t(nc) + size_t(c)];
                uint32_t word;
                std::memcpy(&word, &v, sizeof word);
                v = float(word);
            }
        }

    ExrPlanes result;
    result.width = spec.width;
    result.height = spec.height;
    std::vector<int> fileIndex(static_cast<size_t>(nc));
    for (int c = 0; c < nc; ++c) fileIndex[size_t(c)] = c;
    // Restore the writer's channel order when it names exactly the file's channels.
    const std::string order = spec.get_string_attribute(kChannelOrderAttr);
    std::vector<std::string> wanted;
    for (size_t start = 0; !order.empty() && start <= order.size();) {
        const size_t end = std::min(order.find('\n', start), order.size());
        wanted.push_back(order.substr(start, end - start));
        start = end + 1;
    }
    if (wanted.size() == size_t(nc)) {
        std::vector<int> reordered;
        for (const std::string& name : wanted) {
            const int c = spec.channelindex(name);
            if (c < 0) break;
            reordered.push_back(c);
        }
        if (reordered.size() == size_t(nc) &&
            std::set<int>(reordered.begin(), reordered.end()).size() == size_t(nc))
            fileIndex = reordered;
    }
    for (int c : fileIndex) {
        result.names.push_back(spec.channel_name(c));
        std::vector<float> plane(n);
        for (size_t i = 0; i < n; ++i) plane[i] = interleaved[i * size_t(nc) + size_t(c)];
        result.planes.push_back(std::move(plane));
    }
    return result;
}

}  // namespace reliefsim
