#include "core/image/png_preview.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "tests/support/decoded_png.h"

namespace photond {
namespace {

namespace fs = std::filesystem;

using test_support::DecodedPng;
using test_support::decode_png;

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

// ------------------------------------------------------------------------- render previews

/// The one grey code of a PNG whose pixels all share it, or -1.
int uniform_code(const DecodedPng& png) {
    if (png.rgb.empty()) return -1;
    for (uint8_t code : png.rgb)
        if (code != png.rgb[0]) return -1;
    return png.rgb[0];
}

TEST(FilmicToneCurveTest, MonotonicFromZeroAndBelowOne) {
    EXPECT_EQ(filmic_tone_curve(0.0f), 0.0f);
    EXPECT_EQ(filmic_tone_curve(-1.0f), 0.0f);
    EXPECT_EQ(filmic_tone_curve(std::numeric_limits<float>::quiet_NaN()), 0.0f);
    // Narkowicz's ACES fit at middle grey and at 1.
    EXPECT_NEAR(filmic_tone_curve(0.18f), 0.2669f, 1e-4f);
    EXPECT_NEAR(filmic_tone_curve(1.0f), 0.8038f, 1e-4f);
    float previous = 0.0f;
    for (float x = 1e-4f; x < 1e6f; x *= 1.01f) {
        const float y = filmic_tone_curve(x);
        ASSERT_GE(y, previous) << x;  // monotonic
        ASSERT_LE(y, 1.0f) << x;      // large values stay displayable
        if (x < 7.0f) {
            ASSERT_GT(y, previous) << x;  // strictly, below the white point
        }
        previous = y;
    }
    EXPECT_LT(filmic_tone_curve(4.0f), 1.0f);
    EXPECT_EQ(filmic_tone_curve(1e30f), 1.0f);
    EXPECT_EQ(filmic_tone_curve(std::numeric_limits<float>::infinity()), 1.0f);
    // The curve compresses highlights: 1 maps well below the clamp of a linear preview.
    EXPECT_LT(preview_srgb8(1.0f, 1.0f), linear_to_srgb8(1.0f));
}

TEST(AutomaticExposureTest, UniformImagesOfAnyRadianceGiveTheSameGrey) {
    // log2(0.18 / L): the image's luminance lands on middle grey.
    EXPECT_NEAR(automatic_exposure_ev(Image(8, 8, Color(1.0f))), std::log2(0.18f), 1e-5f);
    int expected = -1;
    for (float radiance : {1e-3f, 1.0f, 1e4f}) {
        Expected<std::vector<uint8_t>> bytes = encode_render_preview(Image(16, 8, Color(radiance)));
        ASSERT_TRUE(bytes) << bytes.error().message;
        const int code = uniform_code(decode_png(*bytes));
        // Middle grey through the curve: sRGB(f(0.18)) = sRGB(0.267) = 141.
        EXPECT_EQ(code, 141) << radiance;
        if (expected < 0) expected = code;
        EXPECT_EQ(code, expected) << radiance;
    }
}

TEST(AutomaticExposureTest, RobustToHotPixelsNonFiniteValuesAndBlack) {
    Image image(64, 64, Color(0.5f));
    for (int i = 0; i < 5; ++i) image.at(7 * i, 3) = Color(1e30f);  // fireflies
    image.at(1, 1) = Color(std::nanf(""));
    image.at(2, 1) = Color(std::numeric_limits<float>::infinity());
    image.at(3, 1) = Color(0.0f);  // black (e.g. a tile not rendered yet) is left out too
    const float uniform = automatic_exposure_ev(Image(64, 64, Color(0.5f)));
    EXPECT_FLOAT_EQ(automatic_exposure_ev(image), uniform);
    Expected<std::vector<uint8_t>> bytes = encode_render_preview(image);
    ASSERT_TRUE(bytes);
    const DecodedPng png = decode_png(*bytes);
    EXPECT_EQ(png.at(10, 10, 1), 141);
    EXPECT_EQ(png.at(0, 3, 0), 255);  // a firefly is white
    EXPECT_EQ(png.at(1, 1, 0), 0);    // NaN is black

    // All black: exposure 0, a black PNG, no NaN anywhere.
    EXPECT_EQ(automatic_exposure_ev(Image(4, 4)), 0.0f);
    Expected<std::vector<uint8_t>> black = encode_render_preview(Image(4, 4));
    ASSERT_TRUE(black) << black.error().message;
    EXPECT_EQ(uniform_code(decode_png(*black)), 0);
    // Far beyond the job field's range, still finite.
    EXPECT_EQ(automatic_exposure_ev(Image(2, 2, Color(1e-40f))), kMaxAutomaticExposureEv);
}

/// An image with 15 of its 100 rows at radiance `bright`, the rest at `shade`.
Image sunlit_over_shade(float bright, float shade) {
    Image image(20, 100, Color(shade));
    for (int y = 0; y < 15; ++y)
        for (int x = 0; x < 20; ++x) image.at(x, y) = Color(bright);
    return image;
}

/// automatic_exposure_ev's log-average exposure of sunlit_over_shade: its darkest and brightest
/// 1 % (20 of each) left out, 280 bright and 1,680 shaded pixels remain.
double average_ev_of(float bright, float shade) {
    const double mean = (280.0 * std::log2(double(bright)) + 1680.0 * std::log2(double(shade))) / 1960.0;
    return std::log2(double(kPreviewMiddleGrey)) - mean;
}

TEST(AutomaticExposureTest, ASunlitSubjectOverShadeKeepsItsShading) {
    // 15 % in sunlight at 0.5, the rest in shade 100 times darker: the log-average alone exposes
    // the sunlit part at 0.5 x 2^4.3 = 10, white; the brightest tenth is held at 2.0 instead.
    const Image image = sunlit_over_shade(0.5f, 0.005f);
    const double average_ev = average_ev_of(0.5f, 0.005f);
    const float ev = automatic_exposure_ev(image);
    EXPECT_NEAR(ev, std::log2(kHighlightCeiling / 0.5f), 1e-4f);
    EXPECT_LT(ev, average_ev - 1.0);
    Expected<std::vector<uint8_t>> bytes = encode_render_preview(image);
    ASSERT_TRUE(bytes) << bytes.error().message;
    const DecodedPng png = decode_png(*bytes);
    EXPECT_EQ(png.at(5, 5, 0), preview_srgb8(kHighlightCeiling, 1.0f));
    EXPECT_LT(png.at(5, 5, 0), 250);  // not white: the curve's 0.91
    EXPECT_EQ(preview_srgb8(0.5f, float(std::exp2(average_ev))), 255);  // as it was

    // A subject 2^20 times brighter than the rest: protection stops 3 stops under the average,
    // so that a visible emitter does not blacken the rest of the picture.
    EXPECT_NEAR(automatic_exposure_ev(sunlit_over_shade(1.0f, 1e-6f)),
                average_ev_of(1.0f, 1e-6f) - kMaxHighlightProtectionEv, 1e-4);
    // Where the brightest tenth is under the ceiling, the log-average alone decides.
    EXPECT_NEAR(automatic_exposure_ev(sunlit_over_shade(0.3f, 0.1f)), average_ev_of(0.3f, 0.1f), 1e-4);
}

TEST(RenderPreviewTest, ExposureDoublesTheLinearValueBeforeTheCurve) {
    Image image(3, 1);
    image.at(0, 0) = Color(0.05f, 0.2f, 0.7f);
    image.at(1, 0) = Color(0.01f, 1.5f, 3.0f);
    image.at(2, 0) = Color(0.3f);
    Image doubled = image;
    for (Color& c : doubled.pixels()) c = c * 2.0f;
    Expected<std::vector<uint8_t>> plus_one = encode_render_preview(image, 1.0f);
    Expected<std::vector<uint8_t>> twice = encode_render_preview(doubled, 0.0f);
    ASSERT_TRUE(plus_one && twice);
    EXPECT_EQ(*plus_one, *twice);
    const DecodedPng png = decode_png(*plus_one);
    EXPECT_EQ(png.at(2, 0, 0), preview_srgb8(0.6f, 1.0f));
    EXPECT_EQ(png.at(1, 0, 2), preview_srgb8(6.0f, 1.0f));
    // Another exposure gives another picture; an explicit exposure is not the automatic one.
    EXPECT_NE(*encode_render_preview(image, 0.0f), *plus_one);
    EXPECT_NE(*encode_render_preview(image), *encode_render_preview(image, 0.0f));
    EXPECT_FALSE(encode_render_preview(image, std::numeric_limits<float>::infinity()));
    EXPECT_FALSE(encode_render_preview(Image()));
}

TEST_F(PngPreviewTest, RenderPreviewIsWrittenAtomically) {
    const Image image(4, 4, Color(2.0f));
    const Status status = write_render_preview(dir_ / "render.png", image, -3.0f);
    ASSERT_TRUE(status) << status.error().message;
    EXPECT_FALSE(fs::exists(dir_ / "render.png.tmp"));
    EXPECT_EQ(uniform_code(decode_png(read_bytes(dir_ / "render.png"))),
              preview_srgb8(2.0f, 0.125f));
    EXPECT_FALSE(write_render_preview(dir_ / "missing_dir" / "x.png", image));
}

}  // namespace
}  // namespace photond
