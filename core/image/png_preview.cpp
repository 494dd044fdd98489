#include "core/image/png_preview.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <fstream>
#include <string>
#include <system_error>

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
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, info);
    return true;
}

Status write_file_atomically(const std::filesystem::path& path, const std::vector<uint8_t>& bytes) {
    const std::string name = "PNG '" + path.string() + "': ";
    std::filesystem::path temporary = path;
    temporary += ".tmp";
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) return Error{name + "cannot create '" + temporary.string() + "'"};
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        out.close();
        if (!out) {
            std::error_code ignored;
            std::filesystem::remove(temporary, ignored);
            return Error{name + "cannot write '" + temporary.string() + "'"};
        }
    }
    std::error_code error;
    std::filesystem::rename(temporary, path, error);
    if (error) {
        std::error_code ignored;
        std::filesystem::remove(temporary, ignored);
        return Error{name + "cannot rename '" + temporary.string() + "': " + error.message()};
    }
    return Status::ok();
}

}  // namespace

uint8_t linear_to_srgb8(float linear, float exposure_scale) {
    float value = linear * exposure_scale;
    if (!std::isfinite(value)) return 0;
    value = std::clamp(value, 0.0f, 1.0f);
    // sRGB OETF, IEC 61966-2-1:1999.
    const float encoded =
        value <= 0.0031308f ? 12.92f * value : 1.055f * std::pow(value, 1.0f / 2.4f) - 0.055f;
    return uint8_t(std::lround(std::clamp(encoded, 0.0f, 1.0f) * 255.0f));
}

Expected<std::vector<uint8_t>> encode_png_preview(const Image& image, float exposure_stops) {
    if (image.empty()) return Error{"PNG preview: image has zero size"};
    if (!std::isfinite(exposure_stops)) return Error{"PNG preview: exposure is not finite"};
    const float exposure_scale = std::exp2(exposure_stops);
    const int width = image.width();
    const int height = image.height();
    std::vector<uint8_t> pixels(size_t(width) * size_t(height) * 3);
    for (size_t i = 0; i < image.pixel_count(); ++i) {
        const Color& color = image.pixels()[i];
        pixels[3 * i + 0] = linear_to_srgb8(color.x, exposure_scale);
        pixels[3 * i + 1] = linear_to_srgb8(color.y, exposure_scale);
        pixels[3 * i + 2] = linear_to_srgb8(color.z, exposure_scale);
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

Status write_png_preview(const std::filesystem::path& path, const Image& image,
                         float exposure_stops) {
    Expected<std::vector<uint8_t>> bytes = encode_png_preview(image, exposure_stops);
    if (!bytes) {
        return Error{"PNG '" + path.string() + "': " + bytes.error().message};
    }
    return write_file_atomically(path, *bytes);
}

}  // namespace photond
