#include "core/image/environment_image.h"

#include <stb_image.h>

#include <cctype>
#include <memory>

#include "core/image/exr_io.h"

namespace photond {
namespace {

std::string lowercase_extension(const std::filesystem::path& path) {
    std::string extension = path.extension().string();
    for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return extension;
}

Expected<Environment> read_radiance_hdr(const std::filesystem::path& path, Environment environment) {
    int width = 0, height = 0, channels = 0;
    if (!stbi_is_hdr(path.c_str()))
        return Error{"environment image '" + path.filename().string() + "': not a Radiance RGBE (.hdr) file"};
    if (!stbi_info(path.c_str(), &width, &height, &channels))
        return Error{"environment image '" + path.filename().string() + "': " + stbi_failure_reason()};
    if (width > kMaxEnvironmentWidth || height > kMaxEnvironmentHeight)
        return Error{"environment image '" + path.filename().string() + "': " + std::to_string(width) + " x " +
                     std::to_string(height) + " texels is larger than " + std::to_string(kMaxEnvironmentWidth) +
                     " x " + std::to_string(kMaxEnvironmentHeight)};
    std::unique_ptr<float, void (*)(void*)> data(stbi_loadf(path.c_str(), &width, &height, &channels, 3),
                                                  stbi_image_free);
    if (!data)
        return Error{"environment image '" + path.filename().string() + "': " + stbi_failure_reason()};
    environment.width = width;
    environment.height = height;
    environment.texels.resize(static_cast<size_t>(width) * static_cast<size_t>(height));
    for (size_t i = 0; i < environment.texels.size(); ++i)
        environment.texels[i] = Color(data.get()[3 * i], data.get()[3 * i + 1], data.get()[3 * i + 2]);
    return environment;
}

Expected<Environment> read_exr_environment(const std::filesystem::path& path, Environment environment) {
    auto layers = read_exr(path);
    if (!layers) return Error{"environment image: " + layers.error().message};
    const Image& image = layers->beauty;
    if (image.width() > kMaxEnvironmentWidth || image.height() > kMaxEnvironmentHeight)
        return Error{"environment image '" + path.filename().string() + "': " + std::to_string(image.width()) +
                     " x " + std::to_string(image.height()) + " texels is larger than " +
                     std::to_string(kMaxEnvironmentWidth) + " x " + std::to_string(kMaxEnvironmentHeight)};
    environment.width = image.width();
    environment.height = image.height();
    environment.texels.resize(static_cast<size_t>(image.width()) * static_cast<size_t>(image.height()));
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x)
            environment.texels[static_cast<size_t>(y) * static_cast<size_t>(image.width()) + static_cast<size_t>(x)] =
                image.at(x, y);
    return environment;
}

}  // namespace

Expected<Environment> read_environment_image(const std::filesystem::path& path) {
    Environment environment;
    environment.name = path.filename().string();
    const std::string extension = lowercase_extension(path);
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error))
        return Error{"environment image '" + environment.name + "': no such file"};
    Expected<Environment> read = extension == ".hdr" ? read_radiance_hdr(path, std::move(environment))
                                 : extension == ".exr"
                                     ? read_exr_environment(path, std::move(environment))
                                     : Expected<Environment>(Error{"environment image '" + path.filename().string() +
                                                                   "': not an .exr or .hdr file"});
    if (!read) return read;
    if (read->width < 2 || read->height < 1)
        return Error{"environment image '" + read->name + "': needs at least 2 x 1 texels"};
    for (size_t i = 0; i < read->texels.size(); ++i) {
        const Color& c = read->texels[i];
        if (!is_finite(c) || min_component(c) < 0.0f) {
            const size_t w = static_cast<size_t>(read->width);
            return Error{"environment image '" + read->name + "': texel (" + std::to_string(i % w) + ", " +
                         std::to_string(i / w) + ") is negative or not finite"};
        }
    }
    return read;
}

}  // namespace photond
