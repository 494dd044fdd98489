// 8-bit sRGB PNG previews of linear renders.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/image/image.h"
#include "core/util/expected.h"

namespace photond {

/// The 8-bit sRGB code of a linear value after scaling by 2^exposure_stops: clamped to [0, 1],
/// sRGB OETF (IEC 61966-2-1), rounded to nearest; non-finite values give 0.
uint8_t linear_to_srgb8(float linear, float exposure_scale = 1.0f);

/// A PNG (8-bit RGB, sRGB chunk, no timestamp) of `image` in memory; Error for an empty image.
Expected<std::vector<uint8_t>> encode_png_preview(const Image& image, float exposure_stops = 0.0f);

/// encode_png_preview written to `path` + ".tmp", then renamed onto `path`.
Status write_png_preview(const std::filesystem::path& path, const Image& image,
                         float exposure_stops = 0.0f);

}  // namespace photond
