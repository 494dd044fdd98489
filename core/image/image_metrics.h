// Error of an image against a reference: the figures the benchmark and the tests report.
#pragma once

#include <optional>
#include <vector>

#include "core/image/image.h"
#include "core/util/expected.h"

namespace photond {

/// One pixel's share of an ImageError: where an error comes from.
struct PixelError {
    int x = 0, y = 0;
    double relative_squared_error = 0.0;  // relative_squared_error(value, reference, epsilon)
    double share = 0.0;                    // of the compared area's relMSE sum (0 to 1)
    Color value{0.0f}, reference{0.0f};
};

struct ImageError {
    double relative_mse = 0.0;    // mean over pixels and channels of (x - r)^2 / (r^2 + epsilon)
    double rmse = 0.0;            // sqrt of the mean squared difference
    double p99_abs_error = 0.0;   // 99th percentile of the per-pixel mean absolute difference
    double mean = 0.0;            // mean of the image (all channels)
    double reference_mean = 0.0;  // mean of the reference
    double mean_bias = 0.0;       // (mean - reference_mean) / reference_mean
    size_t pixels = 0;
    /// The pixels of largest relative squared error, largest first (ties: row, then column),
    /// as many as compare_images was asked for.
    std::vector<PixelError> worst;
};

/// A pixel's relative squared error against its reference, the mean over channels of
/// (x - r)^2 / (r^2 + epsilon): what relMSE averages over pixels.
double relative_squared_error(const Color& value, const Color& reference, double epsilon);

/// The image averaged over factor x factor blocks (a box filter), for comparisons where pixel
/// noise of the reference must not dominate. Edge blocks average what they hold.
Image downsample(const Image& image, int factor);

/// Compares `image` with `reference` over `region` (the whole frame by default). epsilon keeps
/// the relative error finite where the reference is black (0.01, as in the literature).
/// `worst_count` pixels of largest error are listed in ImageError::worst.
Expected<ImageError> compare_images(const Image& image, const Image& reference,
                                    std::optional<PixelRect> region = std::nullopt,
                                    double epsilon = 0.01, size_t worst_count = 0);

}  // namespace photond
