// Float RGB images, pixel rectangles and named AOV layers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/math/vec.h"

namespace photond {

/// A half-open pixel rectangle [x0, x1) x [y0, y1); y grows downwards (row 0 is the top row).
struct PixelRect {
    int x0 = 0;
    int y0 = 0;
    int x1 = 0;
    int y1 = 0;

    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    bool empty() const { return x1 <= x0 || y1 <= y0; }
    int64_t area() const { return empty() ? 0 : int64_t(width()) * int64_t(height()); }
    bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
    /// True when `inner` lies completely inside this rectangle (an empty one always does).
    bool contains(const PixelRect& inner) const {
        return inner.empty() ||
               (inner.x0 >= x0 && inner.x1 <= x1 && inner.y0 >= y0 && inner.y1 <= y1);
    }
    PixelRect intersect(const PixelRect& other) const;
    bool operator==(const PixelRect&) const = default;
};

/// A linear RGB float image, stored row-major with row 0 at the top.
class Image {
public:
    Image() = default;
    /// A width x height image filled with `fill`; negative sizes are treated as 0.
    Image(int width, int height, Color fill = Color(0.0f));

    int width() const { return width_; }
    int height() const { return height_; }
    bool empty() const { return width_ <= 0 || height_ <= 0; }
    PixelRect bounds() const { return {0, 0, width_, height_}; }
    size_t pixel_count() const { return pixels_.size(); }

    /// The pixel in column x, row y; (x, y) must lie inside the image.
    Color& at(int x, int y) { return pixels_[index(x, y)]; }
    const Color& at(int x, int y) const { return pixels_[index(x, y)]; }

    std::vector<Color>& pixels() { return pixels_; }
    const std::vector<Color>& pixels() const { return pixels_; }

    void fill(Color value);

    /// A copy of `rect` with the rectangle's size; pixels of `rect` outside this image are black.
    Image copy_rect(const PixelRect& rect) const;

    /// Copies `tile` so that its pixel (0, 0) lands on (x0, y0); parts outside this image are
    /// dropped.
    void paste(const Image& tile, int x0, int y0);

    bool operator==(const Image&) const = default;

private:
    size_t index(int x, int y) const { return size_t(y) * size_t(width_) + size_t(x); }

    int width_ = 0;
    int height_ = 0;
    std::vector<Color> pixels_;
};

/// The beauty image plus optional named AOV images of the same size. AOV names in use:
/// "direct", "indirect", "caustic", "albedo", "normal", "depth" (depth repeats its value in
/// R, G and B). Names must be non-empty, unique and contain no '.', since they become EXR
/// layer names ("<name>.R").
struct ImageLayers {
    Image beauty;
    std::vector<std::pair<std::string, Image>> aovs;

    /// The AOV called `name`, or nullptr.
    Image* find_aov(std::string_view name);
    const Image* find_aov(std::string_view name) const;
};

/// The same rectangle copied out of the beauty and every AOV (see Image::copy_rect).
ImageLayers copy_rect(const ImageLayers& layers, const PixelRect& rect);

/// Pastes the beauty and every AOV of `tile` at (x0, y0) into `target`; an AOV of `tile` that
/// `target` lacks is added first as a black image of the target's size.
void paste(ImageLayers& target, const ImageLayers& tile, int x0, int y0);

}  // namespace photond
