// Height-map loading: formats, channels, conventions, bad files.
#include "texture/image_io.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

#include "core/error.h"

using namespace reliefsim;
namespace fs = std::filesystem;

namespace {

fs::path TempDir() {
    fs::path p =
        fs::path(::testing::TempDir()) /
        ("rs_image_io_" +
         std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(p);
    fs::create_directories(p);
    return p;
}

template <typename T>
void WriteWithOiio(const std::string& path, int w, int h, int nc, OIIO::TypeDesc type,
                   const std::vector<T>& px) {
    OIIO::ImageSpec spec(w, h, nc, type);
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out && out->open(path, spec) && out->write_image(type, px.data()) &&
                out->close());
}

}  // namespace

TEST(ImageIo, Grey8BitHeightBecomesDepth) {
    fs::path d = TempDir();
    std::string path = (d / "g.png").string();
    WriteWithOiio<uint8_t>(path, 2, 1, 1, OIIO::TypeDesc::UINT8, {255, 51});
    DepthField f = LoadHeightMap(path, {});
    ASSERT_EQ(f.width, 2);
    EXPECT_EQ(f.At(0, 0), 0.0f);  // white = top
    EXPECT_EQ(f.At(1, 0), Unorm8ToFloat(204));
    ASSERT_EQ(f.depth8.size(), 2u);
    EXPECT_EQ(f.depth8[1], 204);
    MapLoadOptions depth;
    depth.stores = Stores::Depth;
    EXPECT_EQ(LoadHeightMap(path, depth).At(1, 0), Unorm8ToFloat(51));
}

TEST(ImageIo, RgbaDefaultsToAlphaAndChannelPicks) {
    fs::path d = TempDir();
    std::string path = (d / "c.tga").string();
    WriteWithOiio<uint8_t>(path, 1, 1, 4, OIIO::TypeDesc::UINT8, {10, 20, 30, 255});
    EXPECT_EQ(LoadHeightMap(path, {}).At(0, 0), 0.0f);
    MapLoadOptions g;
    g.channel = Channel::G;
    g.stores = Stores::Depth;
    EXPECT_EQ(LoadHeightMap(path, g).At(0, 0), Unorm8ToFloat(20));
}

TEST(ImageIo, SixteenBitAndFloat) {
    fs::path d = TempDir();
    std::string p16 = (d / "h.png").string();
    WriteWithOiio<uint16_t>(p16, 1, 1, 1, OIIO::TypeDesc::UINT16, {65535});
    DepthField f16 = LoadHeightMap(p16, {});
    EXPECT_EQ(f16.At(0, 0), 0.0f);
    EXPECT_TRUE(f16.depth8.empty());
    std::string pf = (d / "f.exr").string();
    WriteWithOiio<float>(pf, 2, 1, 1, OIIO::TypeDesc::FLOAT, {0.25f, 1.0f});
    DepthField ff = LoadHeightMap(pf, {});
    EXPECT_EQ(ff.At(0, 0), 0.75f);
    EXPECT_EQ(ff.At(1, 0), 0.0f);
}

TEST(ImageIo, NanHeightsAreRejected) {
    fs::path d = TempDir();
    std::string pf = (d / "nan.exr").string();
    WriteWithOiio<float>(pf, 2, 1, 1, OIIO::TypeDesc::FLOAT, {0.5f, std::nanf("")});
    try {
        LoadHeightMap(pf, {});
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("nan.exr"), std::string::npos) << e.what();
    }
}

TEST(ImageIo, OutOfRangeFloatHeightsAreRejected) {
    fs::path d = TempDir();
    std::string pf = (d / "big.exr").string();
    WriteWithOiio<float>(pf, 1, 1, 1, OIIO::TypeDesc::FLOAT, {3.0f});
    EXPECT_THROW(LoadHeightMap(pf, {}), Error);
}

TEST(ImageIo, MissingAndCorruptFilesNameTheFile) {
    fs::path d = TempDir();
    try {
        LoadHeightMap((d / "missing.png").string(), {});
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos);
    }
    std::string bad = (d / "corrupt.png").string();
    std::ofstream(bad) << "this is not a png";
    EXPECT_THROW(LoadHeightMap(bad, {}), Error);
    // a truncated PNG: valid header, no data
    std::string p = (d / "trunc.png").string();
    WriteWithOiio<uint8_t>(p, 64, 64, 1, OIIO::TypeDesc::UINT8,
                           std::vector<uint8_t>(4096, 7));
    fs::resize_file(p, 60);
    EXPECT_THROW(LoadHeightMap(p, {}), Error);
}

TEST(ImageIo, ChannelBeyondImageIsAnError) {
    fs::path d = TempDir();
    std::string path = (d / "g.png").string();
    WriteWithOiio<uint8_t>(path, 1, 1, 1, OIIO::TypeDesc::UINT8, {1});
    MapLoadOptions b;
    b.channel = Channel::B;
    EXPECT_THROW(LoadHeightMap(path, b), Error);
}

TEST(ImageIo, EmptyFieldIsRejected) {
    DepthField f;
    f.name = "empty";
    EXPECT_THROW(ValidateDepthField(f), Error);
}

namespace {
std::string ErrorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}
}  // namespace

TEST(ImageIo, OnlyRegularFilesAreRead) {
    fs::path d = TempDir();
    fs::create_directories(d / "dir.png");
    ASSERT_EQ(::mkfifo((d / "fifo.png").c_str(), 0600), 0);
    std::string e = ErrorOf([&] { LoadHeightMap((d / "dir.png").string(), {}); });
    EXPECT_NE(e.find("is a directory"), std::string::npos) << e;
    e = ErrorOf([&] { LoadHeightMap((d / "fifo.png").string(), {}); });
    EXPECT_NE(e.find("named pipe"), std::string::npos) << e;
    e = ErrorOf([&] { LoadHeightMap("/dev/null", {}); });
    EXPECT_NE(e.find("character device"), std::string::npos) << e;
}

TEST(ImageIo, ReadImageFileReportsFormatAndPicksChannels) {
    fs::path d = TempDir();
    std::string path = (d / "c.tga").string();
    WriteWithOiio<uint8_t>(path, 2, 1, 4, OIIO::TypeDesc::UINT8,
                           {10, 20, 30, 255, 40, 50, 60, 255});
    int seen = 0;
    ImageData img = ReadImageFile(
        path, "test",
        [&](int nc) {
            seen = nc;
            return std::pair<int, int>{1, 3};
        },
        true);
    EXPECT_EQ(seen, 4);
    EXPECT_EQ(img.format, "targa");
    ASSERT_TRUE(img.is8);
    ASSERT_EQ(img.channels, 2);
    EXPECT_EQ(img.values8, (std::vector<uint8_t>{20, 30, 50, 60}));
    // The picker's Error propagates unchanged.
    std::string e = ErrorOf([&] {
        ReadImageFile(
            path, "test", [](int) -> std::pair<int, int> { throw Error("mine"); }, true);
    });
    EXPECT_EQ(e, "mine");
}

TEST(ImageIo, DamageReportedByTheDecoderIsAnError) {
    fs::path d = TempDir();
    std::string path = (d / "t.tif").string();
    std::vector<uint8_t> px(64 * 64);
    for (size_t i = 0; i < px.size(); ++i) px[i] = uint8_t(i * 13);
    WriteWithOiio<uint8_t>(path, 64, 64, 1, OIIO::TypeDesc::UINT8, px);
    EXPECT_NO_THROW(LoadHeightMap(path, {}));
    fs::resize_file(path, fs::file_size(path) - 100);
    std::string e = ErrorOf([&] { LoadHeightMap(path, {}); });
    EXPECT_NE(e.find("t.tif"), std::string::npos) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}
