// PNGs decoded with libpng's simplified API (independent of photond's writer), for the tests of
// previews and of the daemon's PNG tiles.
#pragma once

#include <png.h>

#include <cstdint>
#include <vector>

namespace photond::test_support {

struct DecodedPng {
    int width = 0;
    int height = 0;
    std::vector<uint8_t> rgb;
    uint8_t at(int x, int y, int c) const { return rgb[size_t((y * width + x) * 3 + c)]; }
};

/// 8-bit RGB; width 0 when the bytes are not a readable PNG.
inline DecodedPng decode_png(const uint8_t* bytes, size_t size) {
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    DecodedPng decoded;
    if (!png_image_begin_read_from_memory(&image, bytes, size)) return decoded;
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

inline DecodedPng decode_png(const std::vector<uint8_t>& bytes) {
    return decode_png(bytes.data(), bytes.size());
}

}  // namespace photond::test_support
