// Environment images from files: equirectangular latitude-longitude maps of linear radiance in
// OpenEXR (core/image/exr_io.h) or Radiance RGBE (.hdr, read by Debian's stb_image).
#pragma once

#include <filesystem>

#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

/// Reads an environment image into an Environment (intensity 1, no rotation). The beauty layer
/// (R, G, B) of an EXR is taken; negative and non-finite texels are refused with their position,
/// as is an image smaller than 2 x 1 or larger than limits allow. Errors name the file.
Expected<Environment> read_environment_image(const std::filesystem::path& path);

/// The largest environment image accepted: 16384 x 8192 texels (1.5 GiB as floats).
inline constexpr int kMaxEnvironmentWidth = 16384;
inline constexpr int kMaxEnvironmentHeight = 8192;

}  // namespace photond
