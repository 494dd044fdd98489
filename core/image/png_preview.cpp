#include "core/image/png_preview.h"

#include <png.h>

#include "core/util/file_io.h"

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstddef>
#include <cstdio>
#include <string>

namespace photond {
namespace {

// libpng reports errors by longjmp; everything it may jump over is plain C data, and the
// jump target (encode_rows) owns no objects with destructors.
struct PngWriteState {
    std::vector<uint8_t>* bytes = nullptr;
    char message[256] = "unknown libpng error";
};

void write_callback(png_structp png, png_bytep data, png_size_t length) {
    auto* state = static_cast<PngWriteState*>(png_get_io_ptr(png));
    bool appended = true;
    try {
        state->bytes->insert(state->bytes->end(), data, data + length);
    } catch (...) {
        appended = false;
    }
    // png_error longjmps, so it must not be called from inside the catch block.
    if (!appended) png_error(png, "out of memory");
}

void flush_callback(png_structp) {}

[[noreturn]] void error_callback(png_structp png, png_const_charp message) {
    auto* state = static_cast<PngWriteState*>(png_get_error_ptr(png));
    std::snprintf(state->message, sizeof(state->message), "%s", message);
    png_longjmp(png, 1);
}

void warning_callback(png_structp, png_const_charp) {}  // the core never prints

bool encode_rows(png_structp png, png_infop info, int width, int height, png_bytepp rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    // zlib's fastest level: a 512 x 512 preview encodes in 26 ms instead of 102 (level 6), and
    // previews are made while a job renders, on its first image's path (README.md,
    // "Progressive previews"); the files are somewhat larger.
    png_set_compression_level(png, 1);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, info);
    return true;
}

/// sRGB OETF, IEC 61966-2-1:1999, of a value in [0, 1], as an 8-bit code rounded to nearest.
uint8_t srgb8_of_unit(float value) {
    const float encoded =
        value <= 0.0031308f ? 12.92f * value : 1.055f * std::pow(value, 1.0f / 2.4f) - 0.055f;
    return uint8_t(std::lround(std::clamp(encoded, 0.0f, 1.0f) * 255.0f));
}

using ChannelEncoder = uint8_t (*)(float linear, float exposure_scale);

/// The PNG of `image` with each channel encoded by `encode(channel, exposure_scale)`.
Expected<std::vector<uint8_t>> encode_png(const Image& image, ChannelEncoder encode,
                                          float exposure_scale) {
    const int width = image.width();
    const int height = image.height();
    std::vector<uint8_t> pixels(size_t(width) * size_t(height) * 3);
    for (size_t i = 0; i < image.pixel_count(); ++i) {
        const Color& color = image.pixels()[i];
        pixels[3 * i + 0] = encode(color.x, exposure_scale);
        pixels[3 * i + 1] = encode(color.y, exposure_scale);
        pixels[3 * i + 2] = encode(color.z, exposure_scale);
    }
    std::vector<png_bytep> rows(static_cast<size_t>(height));
    for (int y = 0; y < height; ++y) rows[size_t(y)] = &pixels[size_t(y) * size_t(width) * 3];

    std::vector<uint8_t> bytes;
    PngWriteState state;
    state.bytes = &bytes;
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, error_callback, warning_callback);
    if (png == nullptr) return Error{"PNG preview: cannot create libpng writer"};
    png_infop info = png_create_info_struct(png);
    if (info == nullptr) {
        png_destroy_write_struct(&png, nullptr);
        return Error{"PNG preview: cannot create libpng info"};
    }
    png_set_write_fn(png, &state, write_callback, flush_callback);
    const bool encoded = encode_rows(png, info, width, height, rows.data());
    png_destroy_write_struct(&png, &info);
    if (!encoded) return Error{std::string("PNG preview: ") + state.message};
    return bytes;
}

Status write_png_file(const std::filesystem::path& path,
                      const Expected<std::vector<uint8_t>>& bytes) {
    if (!bytes) return Error{"PNG '" + path.string() + "': " + bytes.error().message};
    if (Status written = write_file_atomically(path, *bytes); !written)
        return Error{"PNG " + written.error().message};
    return Status::ok();
}

}  // namespace

float filmic_tone_curve(float x) {
    if (!(x > 0.0f)) return 0.0f;  // also NaN
    if (x >= 8.0f) return 1.0f;    // past the curve's white point (7.24); also keeps inf out
    // Narkowicz 2015, the ACES fit.
    constexpr float a = 2.51f, b = 0.03f, c = 2.43f, d = 0.59f, e = 0.14f;
    return std::clamp(x * (a * x + b) / (x * (c * x + d) + e), 0.0f, 1.0f);
}

float automatic_exposure_ev(const Image& image) {
    std::vector<float> log_luminance;
    log_luminance.reserve(image.pixel_count());
    for (const Color& color : image.pixels()) {
        // Rec. 709 / sRGB luminance weights.
        const float y = 0.2126f * color.x + 0.7152f * color.y + 0.0722f * color.z;
        if (y > 0.0f && std::isfinite(y)) log_luminance.push_back(std::log2(y));
    }
    if (log_luminance.empty()) return 0.0f;
    // The mean of the values between the 1st and the 99th percentile, in linear time: after the
    // two partitions, [trim, n - trim) holds exactly the values of those ranks.
    const size_t n = log_luminance.size();
    const size_t trim = n / 100;
    const auto first = log_luminance.begin() + std::ptrdiff_t(trim);
    const auto last = log_luminance.end() - std::ptrdiff_t(trim);
    if (trim > 0) {
        std::nth_element(log_luminance.begin(), first, log_luminance.end());
        std::nth_element(first, last - 1, log_luminance.end());
    }
    double sum = 0.0;
    for (auto it = first; it != last; ++it) sum += *it;
    const double mean = sum / double(last - first);
    const double average_ev = std::log2(double(kPreviewMiddleGrey)) - mean;
    // Highlight protection (png_preview.h): the percentile's rank among all the positive finite
    // values, the 1 % trimmed at either end included.
    const auto highlight = log_luminance.begin() + std::ptrdiff_t(kHighlightPercentile * double(n - 1));
    std::nth_element(log_luminance.begin(), highlight, log_luminance.end());
    const double highlight_ev = std::log2(double(kHighlightCeiling)) - double(*highlight);
    const double ev = std::max(average_ev - double(kMaxHighlightProtectionEv), std::min(average_ev, highlight_ev));
    return float(std::clamp(ev, -double(kMaxAutomaticExposureEv), double(kMaxAutomaticExposureEv)));
}

uint8_t preview_srgb8(float linear, float exposure_scale) {
    return srgb8_of_unit(filmic_tone_curve(linear * exposure_scale));
}

Expected<std::vector<uint8_t>> encode_render_preview(const Image& image,
                                                     std::optional<float> exposure_ev) {
    if (image.empty()) return Error{"PNG preview: image has zero size"};
    const float ev = exposure_ev ? *exposure_ev : automatic_exposure_ev(image);
    if (!std::isfinite(ev)) return Error{"PNG preview: exposure is not finite"};
    return encode_png(image, preview_srgb8, std::exp2(ev));
}

Status write_render_preview(const std::filesystem::path& path, const Image& image,
                            std::optional<float> exposure_ev) {
    return write_png_file(path, encode_render_preview(image, exposure_ev));
}

uint8_t linear_to_srgb8(float linear, float exposure_scale) {
    const float value = linear * exposure_scale;
    if (!std::isfinite(value)) return 0;
    return srgb8_of_unit(std::clamp(value, 0.0f, 1.0f));
}

Expected<std::vector<uint8_t>> encode_png_preview(const Image& image, float exposure_stops) {
    if (image.empty()) return Error{"PNG preview: image has zero size"};
    if (!std::isfinite(exposure_stops)) return Error{"PNG preview: exposure is not finite"};
    return encode_png(image, linear_to_srgb8, std::exp2(exposure_stops));
}

Status write_png_preview(const std::filesystem::path& path, const Image& image,
                         float exposure_stops) {
    return write_png_file(path, encode_png_preview(image, exposure_stops));
}

}  // namespace photond
