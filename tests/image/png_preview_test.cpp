#include "core/image/png_preview.h"

#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace photond {
namespace {

namespace fs = std::filesystem;

struct DecodedPng {
    int width = 0;
    int height = 0;
    std::vector<uint8_t> rgb;
    uint8_t at(int x, int y, int c) const { return rgb[size_t((y * width + x) * 3 + c)]; }
};

/// Decodes with libpng's simplified API (independent of the writer's code path).
DecodedPng decode_png(const std::vector<uint8_t>& bytes) {
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    DecodedPng decoded;
    if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size())) return decoded;
    image.format = PNG_FORMAT_RGB;
    std::vector<uint8_t> rgb(PNG_IMAGE_SIZE(image));
    if (!png_image_finish_read(&image, nullptr, rgb.data(), 0, nullptr)) {
        png_image_free(&image);
        return decoded;
    }
    decoded.width = int(image.width);
    decoded.height = int(image.height);
    decoded.rgb = std::move(rgb);
    return decoded;
}

std::vector<uint8_t> read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class PngPreviewTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("photond_png_test_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path dir_;
};

TEST(LinearToSrgb8Test, KnownValues) {
    EXPECT_EQ(linear_to_srgb8(0.0f), 0);
    EXPECT_EQ(linear_to_srgb8(0.5f), 188);
    EXPECT_EQ(linear_to_srgb8(1.0f), 255);
    EXPECT_EQ(linear_to_srgb8(0.18f), 118);
    EXPECT_EQ(linear_to_srgb8(0.001f), 3);  // linear segment: 12.92 * 0.001 * 255 = 3.29
    EXPECT_EQ(linear_to_srgb8(7.0f), 255);
    EXPECT_EQ(linear_to_srgb8(-1.0f), 0);
    EXPECT_EQ(linear_to_srgb8(std::numeric_limits<float>::quiet_NaN()), 0);
    EXPECT_EQ(linear_to_srgb8(std::numeric_limits<float>::infinity()), 0);
    EXPECT_EQ(linear_to_srgb8(0.25f, 2.0f), 188);
}

TEST_F(PngPreviewTest, WritesSrgbPixelsReadableByLibpng) {
    Image image(5, 3, Color(0.0f));
    image.at(0, 0) = Color(0.5f, 0.0f, 1.0f);
    image.at(4, 2) = Color(2.0f, 0.18f, 0.5f);
    image.at(2, 1) = Color(std::nanf(""), 0.5f, 0.0f);
    const fs::path path = dir_ / "preview.png";
    const Status status = write_png_preview(path, image);
    ASSERT_TRUE(status) << status.error().message;
    EXPECT_FALSE(fs::exists(dir_ / "preview.png.tmp"));

    const DecodedPng png = decode_png(read_bytes(path));
    ASSERT_EQ(png.width, 5);
    ASSERT_EQ(png.height, 3);
    EXPECT_EQ(png.at(0, 0, 0), 188);
    EXPECT_EQ(png.at(0, 0, 1), 0);
    EXPECT_EQ(png.at(0, 0, 2), 255);
    // Row 0 is the top row: (4, 2) is the last pixel of the file.
    EXPECT_EQ(png.at(4, 2, 0), 255);
    EXPECT_EQ(png.at(4, 2, 1), 118);
    EXPECT_EQ(png.at(4, 2, 2), 188);
    EXPECT_EQ(png.at(2, 1, 0), 0);
    EXPECT_EQ(png.at(2, 1, 1), 188);
    EXPECT_EQ(png.at(1, 1, 1), 0);
}

TEST_F(PngPreviewTest, ExposureScalesBeforeEncoding) {
    const Image image(2, 2, Color(0.125f));
    Expected<std::vector<uint8_t>> bytes = encode_png_preview(image, 2.0f);
    ASSERT_TRUE(bytes) << bytes.error().message;
    const DecodedPng png = decode_png(*bytes);
    ASSERT_EQ(png.width, 2);
    EXPECT_EQ(png.at(1, 1, 2), 188);
}

TEST_F(PngPreviewTest, DeterministicBytes) {
    Image image(64, 48);
    for (int y = 0; y < 48; ++y) {
        for (int x = 0; x < 64; ++x) image.at(x, y) = Color(x / 64.0f, y / 48.0f, 0.3f);
    }
    ASSERT_TRUE(write_png_preview(dir_ / "a.png", image));
    ASSERT_TRUE(write_png_preview(dir_ / "b.png", image));
    const std::vector<uint8_t> a = read_bytes(dir_ / "a.png");
    ASSERT_GT(a.size(), 8u);
    EXPECT_EQ(a, read_bytes(dir_ / "b.png"));
    Expected<std::vector<uint8_t>> in_memory = encode_png_preview(image);
    ASSERT_TRUE(in_memory);
    EXPECT_EQ(*in_memory, a);
}

TEST_F(PngPreviewTest, ZeroSizeAndBadPathAreErrors) {
    EXPECT_FALSE(encode_png_preview(Image()));
    const Status empty = write_png_preview(dir_ / "empty.png", Image(0, 4));
    ASSERT_FALSE(empty);
    EXPECT_NE(empty.error().message.find("empty.png"), std::string::npos);
    EXPECT_FALSE(fs::exists(dir_ / "empty.png"));

    const Status bad_path = write_png_preview(dir_ / "missing_dir" / "x.png", Image(2, 2));
    ASSERT_FALSE(bad_path);
    EXPECT_NE(bad_path.error().message.find("x.png"), std::string::npos);
}

}  // namespace
}  // namespace photond
