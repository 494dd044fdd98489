#include "core/image/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace photond {

Image downsample(const Image& image, int factor) {
    factor = std::max(factor, 1);
    const int w = (image.width() + factor - 1) / factor, h = (image.height() + factor - 1) / factor;
    Image out(w, h);
    for (int by = 0; by < h; ++by) {
        for (int bx = 0; bx < w; ++bx) {
            DVec3 sum(0.0);
            int count = 0;
            for (int y = by * factor; y < std::min((by + 1) * factor, image.height()); ++y) {
                for (int x = bx * factor; x < std::min((bx + 1) * factor, image.width()); ++x) {
                    sum += DVec3(image.at(x, y));
                    ++count;
                }
            }
            out.at(bx, by) = Color(sum / static_cast<double>(std::max(count, 1)));
        }
    }
    return out;
}

double relative_squared_error(const Color& value, const Color& reference, double epsilon) {
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) {
        const double d = static_cast<double>(value[c]) - static_cast<double>(reference[c]);
        sum += d * d / (static_cast<double>(reference[c]) * reference[c] + epsilon);
    }
    return sum / 3.0;
}

Expected<ImageError> compare_images(const Image& image, const Image& reference,
                                    std::optional<PixelRect> region, double epsilon, size_t worst_count) {
    if (image.width() != reference.width() || image.height() != reference.height()) {
        return Error{"compare: image is " + std::to_string(image.width()) + "x" + std::to_string(image.height()) +
                     " but the reference is " + std::to_string(reference.width()) + "x" +
                     std::to_string(reference.height())};
    }
    const PixelRect area = region ? region->intersect(image.bounds()) : image.bounds();
    if (area.empty()) return Error{"compare: the region holds no pixel"};
    ImageError e;
    double sum_rel = 0.0, sum_sq = 0.0, sum = 0.0, sum_ref = 0.0;
    std::vector<double> abs_errors;
    abs_errors.reserve(static_cast<size_t>(area.area()));
    std::vector<PixelError> pixel_errors;
    if (worst_count > 0) pixel_errors.reserve(static_cast<size_t>(area.area()));
    for (int y = area.y0; y < area.y1; ++y) {
        for (int x = area.x0; x < area.x1; ++x) {
            const Color a = image.at(x, y), r = reference.at(x, y);
            const double pixel_rel = relative_squared_error(a, r, epsilon);
            double pixel_abs = 0.0;
            for (int c = 0; c < 3; ++c) {
                const double d = static_cast<double>(a[c]) - static_cast<double>(r[c]);
                sum_sq += d * d;
                pixel_abs += std::abs(d) / 3.0;
                sum += a[c];
                sum_ref += r[c];
            }
            abs_errors.push_back(pixel_abs);
            sum_rel += pixel_rel;
            if (worst_count > 0) pixel_errors.push_back({x, y, pixel_rel, 0.0, a, r});
        }
    }
    if (worst_count > 0) {
        const size_t count = std::min(worst_count, pixel_errors.size());
        // Largest first, ties by row and column: the listing is the same on every run.
        std::partial_sort(pixel_errors.begin(), pixel_errors.begin() + static_cast<ptrdiff_t>(count),
                          pixel_errors.end(), [](const PixelError& a, const PixelError& b) {
                              if (a.relative_squared_error != b.relative_squared_error)
                                  return a.relative_squared_error > b.relative_squared_error;
                              return a.y != b.y ? a.y < b.y : a.x < b.x;
                          });
        pixel_errors.resize(count);
        for (PixelError& p : pixel_errors) p.share = sum_rel > 0.0 ? p.relative_squared_error / sum_rel : 0.0;
        e.worst = std::move(pixel_errors);
    }
    const double n = static_cast<double>(area.area());
    e.pixels = static_cast<size_t>(area.area());
    e.relative_mse = sum_rel / n;
    e.rmse = std::sqrt(sum_sq / (3.0 * n));
    const size_t p99 = std::min(abs_errors.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(abs_errors.size())));
    std::nth_element(abs_errors.begin(), abs_errors.begin() + static_cast<ptrdiff_t>(p99), abs_errors.end());
    e.p99_abs_error = abs_errors[p99];
    e.mean = sum / (3.0 * n);
    e.reference_mean = sum_ref / (3.0 * n);
    e.mean_bias = e.reference_mean != 0.0 ? (e.mean - e.reference_mean) / e.reference_mean : 0.0;
    return e;
}

}  // namespace photond
