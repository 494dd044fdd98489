#include "core/image/exr_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfThreading.h>
#include <ImfTiledInputFile.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace photond {
namespace {

namespace fs = std::filesystem;

/// A scratch directory removed at the end of each test.
class ExrIoTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("photond_exr_io_test_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path dir_;
};

/// Values in [0.01, 1000], all different, far from half denormals.
Image make_image(int width, int height, float seed) {
    Image image(width, height);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const float t = seed + 0.37f * float(x) + 1.13f * float(y);
            image.at(x, y) = Color(0.01f + 500.0f * (1.0f + std::sin(t)),
                                   0.02f + 3.0f * (1.0f + std::cos(1.7f * t)),
                                   0.5f + 0.001f * float(x * height + y));
        }
    }
    return image;
}

std::vector<uint8_t> read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& path, const std::vector<uint8_t>& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

void expect_images_near(const Image& actual, const Image& expected, float relative_error) {
    ASSERT_EQ(actual.width(), expected.width());
    ASSERT_EQ(actual.height(), expected.height());
    for (int y = 0; y < expected.height(); ++y) {
        for (int x = 0; x < expected.width(); ++x) {
            for (int c = 0; c < 3; ++c) {
                const float want = expected.at(x, y)[c];
                const float got = actual.at(x, y)[c];
                ASSERT_LE(std::abs(got - want), relative_error * std::abs(want))
                    << "pixel (" << x << ", " << y << ") channel " << c;
            }
        }
    }
}

TEST(ImageTest, CopyRectPadsOutsideWithBlackAndPasteClips) {
    Image image = make_image(8, 6, 0.0f);
    const Image copy = image.copy_rect({6, 4, 10, 7});
    ASSERT_EQ(copy.width(), 4);
    ASSERT_EQ(copy.height(), 3);
    EXPECT_EQ(copy.at(0, 0), image.at(6, 4));
    EXPECT_EQ(copy.at(1, 1), image.at(7, 5));
    EXPECT_EQ(copy.at(2, 0), Color(0.0f));
    EXPECT_EQ(copy.at(0, 2), Color(0.0f));

    Image target(8, 6);
    target.paste(copy, 6, 4);
    EXPECT_EQ(target.at(6, 4), image.at(6, 4));
    EXPECT_EQ(target.at(7, 5), image.at(7, 5));
    EXPECT_EQ(target.at(5, 4), Color(0.0f));
    EXPECT_EQ(Image(0, 5).pixel_count(), 0u);
    EXPECT_TRUE(Image(-3, 5).empty());
}

TEST_F(ExrIoTest, HalfRoundTripWithinHalfPrecision) {
    ImageLayers layers;
    layers.beauty = make_image(37, 21, 0.0f);  // not a multiple of the tile size
    const fs::path path = dir_ / "half.exr";
    const Status status = write_exr(path, layers, {ExrPixelType::Half, 16});
    ASSERT_TRUE(status) << status.error().message;
    EXPECT_FALSE(fs::exists(dir_ / "half.exr.tmp"));

    Expected<ImageLayers> read = read_exr(path);
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_TRUE(read->aovs.empty());
    expect_images_near(read->beauty, layers.beauty, 1e-3f);

    // The file really is tiled, ZIP, half.
    Imf::TiledInputFile file(path.c_str());
    EXPECT_EQ(file.tileXSize(), 16u);
    EXPECT_EQ(file.header().compression(), Imf::ZIP_COMPRESSION);
    EXPECT_EQ(file.header().channels().findChannel("G")->type, Imf::HALF);
}

TEST_F(ExrIoTest, HalfClampsValuesBeyondHalfRange) {
    ImageLayers layers;
    layers.beauty = Image(2, 1, Color(1.0e6f, -1.0e6f, 1.0f));
    Expected<std::vector<uint8_t>> bytes = encode_exr(layers);
    ASSERT_TRUE(bytes) << bytes.error().message;
    Expected<ImageLayers> read = decode_exr(*bytes);
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->beauty.at(1, 0), Color(65504.0f, -65504.0f, 1.0f));
}

TEST_F(ExrIoTest, FloatRoundTripIsExact) {
    ImageLayers layers;
    layers.beauty = make_image(64, 33, 1.0f);
    layers.beauty.at(3, 4) = Color(1.0e-30f, 3.0e38f, -7.25f);
    const fs::path path = dir_ / "float.exr";
    const Status status = write_exr(path, layers, {ExrPixelType::Float, 32});
    ASSERT_TRUE(status) << status.error().message;
    Expected<ImageLayers> read = read_exr(path);
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->beauty, layers.beauty);
}

TEST_F(ExrIoTest, AovLayersRoundTripWithNames) {
    ImageLayers layers;
    layers.beauty = make_image(20, 10, 0.0f);
    layers.aovs.emplace_back("direct", make_image(20, 10, 1.0f));
    layers.aovs.emplace_back("indirect", make_image(20, 10, 2.0f));
    layers.aovs.emplace_back("depth", Image(20, 10, Color(12.5f)));
    const fs::path path = dir_ / "aovs.exr";
    const Status status = write_exr(path, layers, {ExrPixelType::Float, 8});
    ASSERT_TRUE(status) << status.error().message;

    Imf::InputFile file(path.c_str());
    EXPECT_NE(file.header().channels().findChannel("indirect.G"), nullptr);
    EXPECT_NE(file.header().channels().findChannel("B"), nullptr);

    Expected<ImageLayers> read = read_exr(path);
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->beauty, layers.beauty);
    ASSERT_EQ(read->aovs.size(), 3u);
    // EXR sorts channels, so AOVs come back in alphabetical order.
    EXPECT_EQ(read->aovs[0].first, "depth");
    EXPECT_EQ(read->aovs[1].first, "direct");
    EXPECT_EQ(read->aovs[2].first, "indirect");
    for (const auto& [name, image] : layers.aovs) {
        const Image* found = read->find_aov(name);
        ASSERT_NE(found, nullptr) << name;
        EXPECT_EQ(*found, image) << name;
    }
}

TEST_F(ExrIoTest, RejectsInvalidLayers) {
    ImageLayers empty;
    EXPECT_FALSE(encode_exr(empty));
    EXPECT_FALSE(write_exr(dir_ / "empty.exr", empty));
    EXPECT_FALSE(fs::exists(dir_ / "empty.exr"));

    ImageLayers layers;
    layers.beauty = make_image(4, 4, 0.0f);
    layers.aovs.emplace_back("albedo", Image(4, 3));
    Expected<std::vector<uint8_t>> wrong_size = encode_exr(layers);
    ASSERT_FALSE(wrong_size);
    EXPECT_NE(wrong_size.error().message.find("albedo"), std::string::npos);

    layers.aovs = {{"a.b", Image(4, 4)}};
    EXPECT_FALSE(encode_exr(layers));
    layers.aovs = {{"normal", Image(4, 4)}, {"normal", Image(4, 4)}};
    EXPECT_FALSE(encode_exr(layers));
    layers.aovs.clear();
    EXPECT_FALSE(encode_exr(layers, {ExrPixelType::Half, 0}));

    const Status missing_dir = write_exr(dir_ / "no_such_dir" / "x.exr", layers);
    ASSERT_FALSE(missing_dir);
    EXPECT_NE(missing_dir.error().message.find("x.exr"), std::string::npos);
}

TEST_F(ExrIoTest, TileExrKeepsWindowsAndPixels) {
    const PixelRect rect{32, 16, 61, 40};
    ImageLayers tile;
    tile.beauty = make_image(rect.width(), rect.height(), 3.0f);
    tile.aovs.emplace_back("caustic", make_image(rect.width(), rect.height(), 4.0f));
    Expected<std::vector<uint8_t>> bytes =
        encode_tile_exr(tile, rect, 100, 60, ExrPixelType::Float);
    ASSERT_TRUE(bytes) << bytes.error().message;

    // The header, checked with OpenEXR itself.
    const fs::path path = dir_ / "tile.exr";
    write_bytes(path, *bytes);
    {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i data = file.header().dataWindow();
        const Imath::Box2i display = file.header().displayWindow();
        EXPECT_EQ(data.min, Imath::V2i(32, 16));
        EXPECT_EQ(data.max, Imath::V2i(60, 39));
        EXPECT_EQ(display.min, Imath::V2i(0, 0));
        EXPECT_EQ(display.max, Imath::V2i(99, 59));
        EXPECT_FALSE(file.header().hasTileDescription());
    }

    Expected<DecodedExrTile> decoded = decode_tile_exr(*bytes);
    ASSERT_TRUE(decoded) << decoded.error().message;
    EXPECT_EQ(decoded->rect, rect);
    EXPECT_EQ(decoded->frame_width, 100);
    EXPECT_EQ(decoded->frame_height, 60);
    EXPECT_EQ(decoded->tile.beauty, tile.beauty);
    ASSERT_NE(decoded->tile.find_aov("caustic"), nullptr);
    EXPECT_EQ(*decoded->tile.find_aov("caustic"), tile.aovs[0].second);

    // As a whole frame: the tile in place, zeros around it.
    Expected<ImageLayers> frame = read_exr(path);
    ASSERT_TRUE(frame) << frame.error().message;
    ASSERT_EQ(frame->beauty.width(), 100);
    ASSERT_EQ(frame->beauty.height(), 60);
    EXPECT_EQ(frame->beauty.at(32, 16), tile.beauty.at(0, 0));
    EXPECT_EQ(frame->beauty.at(60, 39), tile.beauty.at(28, 23));
    EXPECT_EQ(frame->beauty.at(31, 16), Color(0.0f));
    EXPECT_EQ(frame->beauty.at(32, 40), Color(0.0f));
    EXPECT_EQ(frame->beauty.copy_rect(rect), tile.beauty);
}

TEST_F(ExrIoTest, TileExrHalfAndInvalidTiles) {
    const PixelRect rect{0, 0, 16, 8};
    ImageLayers tile;
    tile.beauty = make_image(16, 8, 5.0f);
    Expected<std::vector<uint8_t>> bytes = encode_tile_exr(tile, rect, 16, 8, ExrPixelType::Half);
    ASSERT_TRUE(bytes) << bytes.error().message;
    Expected<DecodedExrTile> decoded = decode_tile_exr(*bytes);
    ASSERT_TRUE(decoded) << decoded.error().message;
    expect_images_near(decoded->tile.beauty, tile.beauty, 1e-3f);

    EXPECT_FALSE(encode_tile_exr(tile, {8, 0, 24, 8}, 20, 8, ExrPixelType::Half));  // outside
    EXPECT_FALSE(encode_tile_exr(tile, {0, 0, 8, 8}, 16, 8, ExrPixelType::Half));   // size
    EXPECT_FALSE(encode_tile_exr(tile, {0, 0, 0, 0}, 16, 8, ExrPixelType::Half));   // empty
}

TEST_F(ExrIoTest, ReadsForeignScanlineGreyFileInDisplayWindow) {
    // A scanline float file with a single Y channel, data window offset inside the frame.
    const fs::path path = dir_ / "grey.exr";
    const Imath::Box2i display(Imath::V2i(0, 0), Imath::V2i(9, 7));
    const Imath::Box2i data(Imath::V2i(2, 3), Imath::V2i(5, 4));
    std::vector<float> values(4 * 2);
    for (size_t i = 0; i < values.size(); ++i) values[i] = 0.25f * float(i + 1);
    {
        Imf::Header header(display, data);
        header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
        Imf::OutputFile file(path.c_str(), header);
        Imf::FrameBuffer frame_buffer;
        frame_buffer.insert("Y", Imf::Slice::Make(Imf::FLOAT, values.data(), data));
        file.setFrameBuffer(frame_buffer);
        file.writePixels(2);
    }
    Expected<ImageLayers> read = read_exr(path);
    ASSERT_TRUE(read) << read.error().message;
    ASSERT_EQ(read->beauty.width(), 10);
    ASSERT_EQ(read->beauty.height(), 8);
    EXPECT_EQ(read->beauty.at(2, 3), Color(0.25f));
    EXPECT_EQ(read->beauty.at(5, 4), Color(2.0f));
    EXPECT_EQ(read->beauty.at(1, 3), Color(0.0f));
    EXPECT_EQ(read->beauty.at(2, 5), Color(0.0f));
}

TEST_F(ExrIoTest, MissingGarbageAndTruncatedFilesAreErrors) {
    const fs::path missing = dir_ / "missing.exr";
    Expected<ImageLayers> not_there = read_exr(missing);
    ASSERT_FALSE(not_there);
    EXPECT_NE(not_there.error().message.find("missing.exr"), std::string::npos);

    const fs::path garbage = dir_ / "garbage.exr";
    std::vector<uint8_t> noise(4096);
    for (size_t i = 0; i < noise.size(); ++i) noise[i] = uint8_t((i * 2654435761u) >> 13);
    write_bytes(garbage, noise);
    Expected<ImageLayers> bad = read_exr(garbage);
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().message.find("garbage.exr"), std::string::npos);

    EXPECT_FALSE(decode_exr({}));
    EXPECT_FALSE(decode_tile_exr({}));

    // A valid file cut short, and one with its magic number kept but the rest scrambled.
    ImageLayers layers;
    layers.beauty = make_image(40, 40, 0.0f);
    Expected<std::vector<uint8_t>> bytes = encode_exr(layers);
    ASSERT_TRUE(bytes) << bytes.error().message;
    for (size_t cut : {size_t(3), size_t(100), bytes->size() / 2, bytes->size() - 1}) {
        std::vector<uint8_t> truncated(bytes->begin(), bytes->begin() + std::ptrdiff_t(cut));
        EXPECT_FALSE(decode_exr(truncated)) << "cut at " << cut;
    }
    std::vector<uint8_t> scrambled = *bytes;
    for (size_t i = 8; i < scrambled.size(); i += 7) scrambled[i] ^= 0x5a;
    EXPECT_FALSE(decode_exr(scrambled));
}

TEST_F(ExrIoTest, OutputIsByteIdenticalAcrossWritesAndThreadCounts) {
    ImageLayers layers;
    layers.beauty = make_image(130, 70, 0.0f);
    layers.aovs.emplace_back("albedo", make_image(130, 70, 1.0f));
    const fs::path first = dir_ / "first.exr";
    const fs::path second = dir_ / "second.exr";
    ASSERT_TRUE(write_exr(first, layers));
    ASSERT_TRUE(write_exr(second, layers));
    const std::vector<uint8_t> first_bytes = read_bytes(first);
    ASSERT_FALSE(first_bytes.empty());
    EXPECT_EQ(first_bytes, read_bytes(second));

    const int previous_threads = Imf::globalThreadCount();
    Imf::setGlobalThreadCount(4);
    Expected<std::vector<uint8_t>> threaded = encode_exr(layers);
    Expected<std::vector<uint8_t>> threaded_tile =
        encode_tile_exr(layers, {0, 0, 130, 70}, 130, 70, ExrPixelType::Float);
    Imf::setGlobalThreadCount(previous_threads);
    ASSERT_TRUE(threaded) << threaded.error().message;
    EXPECT_EQ(*threaded, first_bytes);
    Expected<std::vector<uint8_t>> single_tile =
        encode_tile_exr(layers, {0, 0, 130, 70}, 130, 70, ExrPixelType::Float);
    ASSERT_TRUE(threaded_tile);
    ASSERT_TRUE(single_tile);
    EXPECT_EQ(*threaded_tile, *single_tile);

    // Overwriting an existing file works (the rename replaces it).
    layers.beauty.at(0, 0) = Color(9.0f);
    ASSERT_TRUE(write_exr(first, layers));
    Expected<ImageLayers> read = read_exr(first);
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->beauty.at(0, 0), Color(9.0f));
}

}  // namespace
}  // namespace photond
