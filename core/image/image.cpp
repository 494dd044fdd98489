#include "core/image/image.h"

#include <algorithm>

namespace photond {

PixelRect PixelRect::intersect(const PixelRect& other) const {
    PixelRect result{std::max(x0, other.x0), std::max(y0, other.y0), std::min(x1, other.x1),
                     std::min(y1, other.y1)};
    if (result.empty()) return {};
    return result;
}

Image::Image(int width, int height, Color fill)
    : width_(std::max(width, 0)), height_(std::max(height, 0)) {
    if (width_ == 0 || height_ == 0) {
        width_ = 0;
        height_ = 0;
    }
    pixels_.assign(size_t(width_) * size_t(height_), fill);
}

void Image::fill(Color value) { std::fill(pixels_.begin(), pixels_.end(), value); }

Image Image::copy_rect(const PixelRect& rect) const {
    Image result(rect.width(), rect.height());
    if (result.empty()) return result;
    const PixelRect inside = rect.intersect(bounds());
    for (int y = inside.y0; y < inside.y1; ++y) {
        const Color* source = &at(inside.x0, y);
        std::copy(source, source + inside.width(), &result.at(inside.x0 - rect.x0, y - rect.y0));
    }
    return result;
}

void Image::paste(const Image& tile, int x0, int y0) {
    if (tile.empty() || empty()) return;
    const PixelRect target =
        PixelRect{x0, y0, x0 + tile.width(), y0 + tile.height()}.intersect(bounds());
    for (int y = target.y0; y < target.y1; ++y) {
        const Color* source = &tile.at(target.x0 - x0, y - y0);
        std::copy(source, source + target.width(), &at(target.x0, y));
    }
}

Image* ImageLayers::find_aov(std::string_view name) {
    for (auto& [aov_name, image] : aovs) {
        if (aov_name == name) return &image;
    }
    return nullptr;
}

const Image* ImageLayers::find_aov(std::string_view name) const {
    for (const auto& [aov_name, image] : aovs) {
        if (aov_name == name) return &image;
    }
    return nullptr;
}

ImageLayers copy_rect(const ImageLayers& layers, const PixelRect& rect) {
    ImageLayers result;
    result.beauty = layers.beauty.copy_rect(rect);
    result.aovs.reserve(layers.aovs.size());
    for (const auto& [name, image] : layers.aovs) {
        result.aovs.emplace_back(name, image.copy_rect(rect));
    }
    return result;
}

void paste(ImageLayers& target, const ImageLayers& tile, int x0, int y0) {
    target.beauty.paste(tile.beauty, x0, y0);
    for (const auto& [name, image] : tile.aovs) {
        Image* destination = target.find_aov(name);
        if (destination == nullptr) {
            target.aovs.emplace_back(name, Image(target.beauty.width(), target.beauty.height()));
            destination = &target.aovs.back().second;
        }
        destination->paste(image, x0, y0);
    }
}

}  // namespace photond
