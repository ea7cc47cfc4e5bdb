// Tests for heatmap PNGs (fixed-range colour mapping, mask, legend) and EXR round trips.
#include "metrics/heatmap.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"

namespace OIIO = OIIO_NAMESPACE;
namespace fs = std::filesystem;

namespace reliefsim {
namespace {

using Rgb8 = std::array<int, 3>;

/// A fresh directory under ::testing::TempDir(), unique per test.
std::string TestDir() {
    const ::testing::TestInfo* info =
        ::testing::UnitTest::GetInstance()->current_test_info();
    fs::path dir =
        fs::path(::testing::TempDir()) /
        ("rs_heatmap_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir.string();
}

struct Png {
    int width = 0, height = 0;
    std::vector<uint8_t> px;  // 3 per pixel
    Rgb8 At(int x, int y) const {
        const size_t i = (size_t(y) * size_t(width) + size_t(x)) * 3;
        return {px[i], px[i + 1], px[i + 2]};
    }
};

Png ReadPng(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    EXPECT_TRUE(in) << OIIO::geterror();
    Png png;
    if (!in) return png;
    EXPECT_EQ(in->spec().nchannels, 3);
    EXPECT_EQ(in->spec().format, OIIO::TypeDesc::UINT8);
    png.width = in->spec().width;
    png.height = in->spec().height;
    png.px.resize(size_t(png.width) * size_t(png.height) * 3);
    EXPECT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, png.px.data()));
    return png;
}

/// The 8-bit colour OIIO's color_map gives for t in [0, 1].
Rgb8 MapColor(const std::string& colormap, float t) {
    OIIO::ImageBuf src(OIIO::ImageSpec(1, 1, 1, OIIO::TypeDesc::FLOAT));
    src.setpixel(0, 0, &t, 1);
    OIIO::ImageBuf rgb = OIIO::ImageBufAlgo::color_map(src, 0, colormap);
    EXPECT_FALSE(rgb.has_error()) << rgb.geterror();
    uint8_t c[3] = {0, 0, 0};
    rgb.get_pixels(OIIO::ROI(0, 1, 0, 1, 0, 1, 0, 3), OIIO::TypeDesc::UINT8, c);
    return {c[0], c[1], c[2]};
}

constexpr Rgb8 kGrey = {40, 40, 40};

TEST(Heatmap, RampEndsUseColormapEndColoursAndClamp) {
    const std::string dir = TestDir();
    for (const std::string colormap : {"inferno", "viridis", "turbo"}) {
        // Columns: below min, min, midpoint, max, above max; three identical rows.
        const std::vector<float> row = {-100.0f, 10.0f, 30.0f, 50.0f, 1e9f};
        std::vector<float> values;
        for (int y = 0; y < 3; ++y) values.insert(values.end(), row.begin(), row.end());
        const std::string path = dir + "/ramp_" + colormap + ".png";
        WriteHeatmapPng(path, values.data(), nullptr, 5, 3,
                        {10.0f, 50.0f, colormap, "v"});

        const Png png = ReadPng(path);
        for (int y = 0; y < 3; ++y) {
            EXPECT_EQ(png.At(0, y), MapColor(colormap, 0.0f)) << colormap;
            EXPECT_EQ(png.At(1, y), MapColor(colormap, 0.0f)) << colormap;
            EXPECT_EQ(png.At(2, y), MapColor(colormap, 0.5f)) << colormap;
            EXPECT_EQ(png.At(3, y), MapColor(colormap, 1.0f)) << colormap;
            EXPECT_EQ(png.At(4, y), MapColor(colormap, 1.0f)) << colormap;
        }
        EXPECT_NE(MapColor(colormap, 0.0f), MapColor(colormap, 1.0f));
    }
}

TEST(Heatmap, SameScaleMapsEqualValuesToEqualColours) {
    const std::string dir = TestDir();
    // Different data ranges (0..7 and 5..500) share the value 5 at pixel (1, 0).
    const std::vector<float> a = {0.0f, 5.0f, 7.0f, 1.0f};
    const std::vector<float> b = {500.0f, 5.0f, 6.0f, 250.0f};
    const HeatmapScale scale{0.0f, 20.0f, "viridis", "count"};
    WriteHeatmapPng(dir + "/a.png", a.data(), nullptr, 2, 2, scale);
    WriteHeatmapPng(dir + "/b.png", b.data(), nullptr, 2, 2, scale);
    const Png pa = ReadPng(dir + "/a.png"), pb = ReadPng(dir + "/b.png");
    EXPECT_EQ(pa.At(1, 0), pb.At(1, 0));
    EXPECT_EQ(pa.At(1, 0), MapColor("viridis", 0.25f));
    // Per-image normalisation would have made a's maximum (7) the top colour.
    EXPECT_EQ(pa.At(0, 1), MapColor("viridis", 7.0f / 20.0f));
    EXPECT_EQ(pb.At(0, 0), MapColor("viridis", 1.0f));
}

TEST(Heatmap, MaskedAndNanPixelsAreDarkGrey) {
    const std::string dir = TestDir();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<float> values = {0.5f, 0.5f, nan, 0.5f, 0.5f, 0.5f};
    const std::vector<uint8_t> mask = {1, 0, 1, 1, 0, 1};
    WriteHeatmapPng(dir + "/m.png", values.data(), mask.data(), 3, 2, HeatmapScale{});
    const Png png = ReadPng(dir + "/m.png");
    for (int i = 0; i < 6; ++i) {
        const Rgb8 c = png.At(i % 3, i / 3);
        if (mask[size_t(i)] == 0 || std::isnan(values[size_t(i)]))
            EXPECT_EQ(c, kGrey) << "pixel " << i;
        else
            EXPECT_EQ(c, MapColor("inferno", 0.5f)) << "pixel " << i;
    }
}

TEST(Heatmap, LegendEnlargesOutputBesideOrBelowTheImage) {
    const std::string dir = TestDir();
    struct Case {
        int width, height;
        bool right;  // legend to the right (tall enough) or below
    };
    for (const Case c : {Case{64, 200, true}, Case{200, 20, false}, Case{3, 3, false}}) {
        std::vector<float> values(size_t(c.width) * size_t(c.height));
        for (size_t i = 0; i < values.size(); ++i) values[i] = float(i % 97);
        const std::string path = dir + "/legend.png";
        WriteHeatmapPng(path, values.data(), nullptr, c.width, c.height,
                        {0.0f, 96.0f, "magma", "iterations (coarse + refine)"});
        const Png png = ReadPng(path);
        if (c.right) {
            EXPECT_GT(png.width, c.width);
            EXPECT_EQ(png.height, c.height);
        } else {
            EXPECT_GE(png.width, c.width);
            EXPECT_GT(png.height, c.height);
        }
        // The image sits unscaled at the top-left corner.
        EXPECT_EQ(png.At(0, 0), MapColor("magma", 0.0f));
        EXPECT_EQ(png.At(c.width - 1, c.height - 1),
                  MapColor("magma", values.back() / 96.0f));
        // The legend's colour bar shows both ends of the colormap.
        bool hasTop = false, hasBottom = false;
        for (int y = 0; y < png.height; ++y)
            for (int x = 0; x < png.width; ++x) {
                if (x < c.width && y < c.height) continue;
                hasTop |= png.At(x, y) == MapColor("magma", 1.0f);
                hasBottom |= png.At(x, y) == MapColor("magma", 0.0f);
            }
        EXPECT_TRUE(hasTop && hasBottom) << c.width << "x" << c.height;
    }
}

/// The colour bar's interior and its one-pixel black frame, found by scanning the legend
/// panel (whose top-left is (panelX, panelY)) along its middle row: the first black
/// pixel is the frame's left side, the next one its right side.
struct Bar {
    int x0 = -1, x1 = -1, y0 = -1, y1 = -1;  // interior, inclusive, in output pixels
};

Bar FindBar(const Png& png, int panelX, int panelY) {
    constexpr Rgb8 black = {0, 0, 0};
    Bar bar;
    const int midY = (panelY + png.height) / 2;
    int left = -1, right = -1;
    for (int x = panelX; x < png.width && right < 0; ++x)
        if (png.At(x, midY) == black) (left < 0 ? left : right) = x;
    if (left < 0 || right <= left + 1) return bar;
    int top = -1, bottom = -1;
    for (int y = panelY; y < png.height && bottom < 0; ++y)
        if (png.At(left + 1, y) == black) (top < 0 ? top : bottom) = y;
    if (top < 0 || bottom <= top + 1) return bar;
    return {left + 1, right - 1, top + 1, bottom - 1};
}

TEST(Heatmap, ColourBarIsColorMapOfItsFramedGradient) {
    // viridis: no colour of the map is black, so the frame can be found by colour.
    const std::string dir = TestDir();
    struct Case {
        int width, height, panelX, panelY;  // legend to the right or below
    };
    for (const Case c : {Case{40, 200, 40, 0}, Case{180, 20, 0, 20}}) {
        std::vector<float> values(size_t(c.width) * size_t(c.height), 0.25f);
        const std::string path = dir + "/bar.png";
        WriteHeatmapPng(path, values.data(), nullptr, c.width, c.height,
                        {-3.0f, 7.5f, "viridis", "fetches per pixel"});
        const Png png = ReadPng(path);
        const Bar bar = FindBar(png, c.panelX, c.panelY);
        ASSERT_GE(bar.x0, 0) << c.width << "x" << c.height << ": no framed bar";
        ASSERT_GT(bar.y1, bar.y0 + 10);
        // Row i of an n-row bar is the vertical gradient fill's t = 1 - i / (n - 1)
        // (OIIO lerps top to bottom), mapped by color_map like the image pixels.
        const int n = bar.y1 - bar.y0 + 1;
        for (int i = 0; i < n; ++i) {
            const float t = 1.0f - float(i) / float(n - 1);
            for (int x = bar.x0; x <= bar.x1; ++x)
                ASSERT_EQ(png.At(x, bar.y0 + i), MapColor("viridis", t))
                    << "bar row " << i << " of " << n << ", x " << x;
        }
        EXPECT_EQ(png.At(bar.x0, bar.y0), MapColor("viridis", 1.0f));  // max at the top
        EXPECT_EQ(png.At(bar.x0, bar.y1), MapColor("viridis", 0.0f));
        // The frame is closed: one black pixel all round.
        constexpr Rgb8 black = {0, 0, 0};
        for (int x = bar.x0 - 1; x <= bar.x1 + 1; ++x) {
            EXPECT_EQ(png.At(x, bar.y0 - 1), black) << "top frame x " << x;
            EXPECT_EQ(png.At(x, bar.y1 + 1), black) << "bottom frame x " << x;
        }
        for (int y = bar.y0 - 1; y <= bar.y1 + 1; ++y) {
            EXPECT_EQ(png.At(bar.x0 - 1, y), black) << "left frame y " << y;
            EXPECT_EQ(png.At(bar.x1 + 1, y), black) << "right frame y " << y;
        }
    }
}

TEST(Heatmap, LegendHasTickMarksAndLabelsBesideTheBar) {
    const std::string dir = TestDir();
    std::vector<float> values(size_t(64) * 256, 1.0f);
    WriteHeatmapPng(dir + "/t.png", values.data(), nullptr, 64, 256,
                    {0.0f, 100.0f, "viridis", "iterations"});
    const Png png = ReadPng(dir + "/t.png");
    const Bar bar = FindBar(png, 64, 0);
    ASSERT_GE(bar.x0, 0);
    // Tick marks start right of the frame at the max (top) and min (bottom) rows.
    constexpr Rgb8 black = {0, 0, 0}, white = {255, 255, 255};
    EXPECT_EQ(png.At(bar.x1 + 2, bar.y0), black);
    EXPECT_EQ(png.At(bar.x1 + 2, bar.y1), black);
    EXPECT_EQ(png.At(png.width - 1, 0), white);  // the panel's background
    // Right of the tick marks there is text exactly when a TrueType font loads (the
    // writer's fallback leaves the text out and keeps the ticks).
    bool hasFont = false;
    for (const char* font :
         {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "DejaVuSans", ""})
        hasFont |= OIIO::ImageBufAlgo::text_size("0.5", 12, font).defined();
    OIIO::geterror();
    int dark = 0;
    for (int y = 0; y < png.height; ++y)
        for (int x = bar.x1 + 8; x < png.width; ++x) dark += png.At(x, y)[0] < 128;
    if (hasFont)
        EXPECT_GT(dark, 20) << "no tick label or title text drawn";
    else
        EXPECT_EQ(dark, 0) << "no font, yet something drawn beside the ticks";
}

TEST(Heatmap, PngIsByteIdenticalAcrossWrites) {
    // Same input twice, a second apart: no time stamp, no randomness in the legend.
    const std::string dir = TestDir();
    std::vector<float> values(size_t(50) * 160);
    for (size_t i = 0; i < values.size(); ++i) values[i] = float(i % 53) * 0.37f;
    const std::vector<uint8_t> mask(values.size(), 1);
    const HeatmapScale scale{0.0f, 20.0f, "inferno", "steps (coarse + refine)"};
    WriteHeatmapPng(dir + "/a.png", values.data(), mask.data(), 50, 160, scale);
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    WriteHeatmapPng(dir + "/b.png", values.data(), mask.data(), 50, 160, scale);
    auto bytes = [](const std::string& p) {
        std::ifstream f(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(f), {});
    };
    const std::string a = bytes(dir + "/a.png");
    EXPECT_GT(a.size(), 100u);
    EXPECT_EQ(a, bytes(dir + "/b.png"));
}

TEST(Heatmap, RecordsScaleInPngMetadata) {
    const std::string dir = TestDir();
    const float v = 3.0f;
    WriteHeatmapPng(dir + "/meta.png", &v, nullptr, 1, 1,
                    {2.0f, 17.0f, "plasma", "steps"});
    auto in = OIIO::ImageInput::open(dir + "/meta.png");
    ASSERT_TRUE(in);
    // Stored as text (PNG has no float metadata), printed with %.9g so it parses exactly.
    EXPECT_EQ(std::stof(in->spec().get_string_attribute("reliefsim:min")), 2.0f);
    EXPECT_EQ(std::stof(in->spec().get_string_attribute("reliefsim:max")), 17.0f);
    EXPECT_EQ(in->spec().get_string_attribute("reliefsim:colormap"), "plasma");
    EXPECT_EQ(in->spec().get_string_attribute("reliefsim:label"), "steps");
}

TEST(Heatmap, ColorPngRoundTrips) {
    const std::string dir = TestDir();
    const std::vector<float> rgb = {0.0f, 0.5f,  1.0f, 1.0f, 0.0f,
                                    2.0f, -1.0f, 0.2f, 0.8f};
    WriteColorPng(dir + "/c.png", rgb.data(), 3, 1);
    const Png png = ReadPng(dir + "/c.png");
    ASSERT_EQ(png.width, 3);
    ASSERT_EQ(png.height, 1);
    for (size_t i = 0; i < rgb.size(); ++i) {
        const float clamped = std::fmin(std::fmax(rgb[i], 0.0f), 1.0f);
        EXPECT_EQ(int(png.px[i]), int(std::lround(clamped * 255.0f)))
            << "component " << i;
    }
}

TEST(Heatmap, ExrRoundTripsBitExactlyWithChannelNames) {
    const std::string dir = TestDir();
    const int width = 7, height = 5;
    const size_t n = size_t(width) * size_t(height);
    // Names out of alphabetical order: EXR sorts channels, the reader restores the order.
    const std::vector<std::string> names = {"steps", "fetches", "A", "iterations"};
    std::vector<std::vector<float>> data(names.size(), std::vector<float>(n));
    uint32_t state = 12345u;
    for (auto& plane : data)
        for (float& v : plane) {
            state = state * 1664525u + 1013904223u;
            v = float(state >> 8) * (1.0f / 16777216.0f) * 1000.0f - 500.0f;
        }
    data[0][0] = -0.0f;
    data[0][1] = std::numeric_limits<float>::denorm_min();
    data[0][2] = std::numeric_limits<float>::infinity();
    data[0][3] = std::numeric_limits<float>::max();
    std::vector<const float*> planes;
    for (const auto& plane : data) planes.push_back(plane.data());

    const std::string path = dir + "/counters.exr";
    WriteMultiChannelExr(path, width, height, names, planes);
    for (const auto& e : fs::directory_iterator(dir))  // no temporary left beside it
        EXPECT_EQ(e.path().filename(), "counters.exr") << e.path();
    const ExrPlanes read = ReadMultiChannelExr(path);
    EXPECT_EQ(read.width, width);
    EXPECT_EQ(read.height, height);
    EXPECT_EQ(read.names, names);
    ASSERT_EQ(read.planes.size(), data.size());
    for (size_t c = 0; c < data.size(); ++c) {
        ASSERT_EQ(read.planes[c].size(), n);
        EXPECT_EQ(std::memcmp(read.planes[c].data(), data[c].data(), n * sizeof(float)),
                  0)
            << names[c];
    }
}

TEST(Heatmap, UnwritablePathThrowsAndLeavesNoFile) {
    const std::string dir = TestDir();
    std::ofstream(dir + "/file") << "x";       // a file where a folder would have to be
    fs::create_directory(dir + "/taken.exr");  // a folder where the file goes
    const float v = 1.0f;
    const std::string png = dir + "/file/sub/h.png", color = dir + "/file/c.png",
                      exr = dir + "/taken.exr";
    try {
        WriteHeatmapPng(png, &v, nullptr, 1, 1, HeatmapScale{});
        ADD_FAILURE() << "expected Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << e.what();
    }
    const float rgb[3] = {0.0f, 0.0f, 0.0f};
    EXPECT_THROW(WriteColorPng(color, rgb, 1, 1), Error);
    EXPECT_THROW(WriteMultiChannelExr(exr, 1, 1, {"v"}, {&v}), Error);
    EXPECT_THROW(ReadMultiChannelExr(dir + "/missing.exr"), Error);
    // Nothing beside the two obstacles, no temporary.
    std::vector<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        names.push_back(fs::relative(e.path(), dir).string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"file", "taken.exr"}));
}

TEST(Heatmap, MissingFolderIsCreatedWithTheFile) {
    const std::string dir = TestDir() + "/does/not/exist";
    const float v = 1.0f;
    WriteHeatmapPng(dir + "/h.png", &v, nullptr, 1, 1, HeatmapScale{});
    EXPECT_TRUE(fs::is_regular_file(dir + "/h.png"));
}

TEST(Heatmap, ExrIsByteIdenticalAcrossWrites) {
    // OpenImageIO would stamp the time (DateTime); two writes must give the same bytes.
    const std::string dir = TestDir();
    const std::vector<float> plane = {0.5f, 1.5f, -2.0f, 3.0f};
    WriteMultiChannelExr(dir + "/a.exr", 2, 2, {"v"}, {plane.data()});
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    WriteMultiChannelExr(dir + "/b.exr", 2, 2, {"v"}, {plane.data()});
    auto bytes = [](const std::string& p) {
        std::ifstream f(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(f), {});
    };
    EXPECT_EQ(bytes(dir + "/a.exr"), bytes(dir + "/b.exr"));
}

TEST(Heatmap, BadScaleOrColormapThrowsWithValidChoices) {
    const std::string dir = TestDir();
    const float v = 1.0f;
    EXPECT_THROW(
        WriteHeatmapPng(dir + "/s.png", &v, nullptr, 1, 1, {1.0f, 1.0f, "inferno", ""}),
        Error);
    try {
        WriteHeatmapPng(dir + "/c.png", &v, nullptr, 1, 1, {0.0f, 1.0f, "nope", ""});
        ADD_FAILURE() << "expected Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("\"viridis\""), std::string::npos)
            << e.what();
    }
    EXPECT_FALSE(fs::exists(dir + "/s.png"));
    EXPECT_FALSE(fs::exists(dir + "/c.png"));
}

}  // namespace
}  // namespace reliefsim
