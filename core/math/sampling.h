// Warping of uniform random numbers to the distributions the renderer samples, with their pdfs.
#pragma once

#include <algorithm>
#include <span>
#include <vector>

#include "core/math/trig.h"
#include "core/math/vec.h"

namespace photond {

/// Concentric map of the unit square onto the unit disc (Shirley & Chiu 1997).
inline Vec2 sample_concentric_disk(const Vec2& u) {
    const Vec2 o = 2.0f * u - Vec2(1.0f);
    if (o.x == 0.0f && o.y == 0.0f) return {0.0f, 0.0f};
    // theta = pi/4 (y/x) or pi/2 - pi/4 (x/y): within an eighth of a turn of 0, or of pi/2, where
    // cosine and sine are those of the small angle, swapped.
    if (std::abs(o.x) > std::abs(o.y)) return o.x * cos_sin_eighth((kPi / 4.0f) * (o.y / o.x));
    const Vec2 cs = cos_sin_eighth((kPi / 4.0f) * (o.x / o.y));
    return o.y * Vec2(cs.y, cs.x);
}

/// Cosine-weighted direction on the +z hemisphere; pdf = cos(theta) / pi.
inline Vec3 sample_cosine_hemisphere(const Vec2& u) {
    const Vec2 d = sample_concentric_disk(u);
    const float z = safe_sqrt(1.0f - d.x * d.x - d.y * d.y);
    return {d.x, d.y, z};
}
inline float cosine_hemisphere_pdf(float cos_theta) { return std::max(cos_theta, 0.0f) * kInvPi; }

/// Uniform direction on the unit sphere; pdf = 1 / (4 pi).
inline Vec3 sample_uniform_sphere(const Vec2& u) {
    const float z = 1.0f - 2.0f * u.x;
    const float r = safe_sqrt(1.0f - z * z);
    const Vec2 cs = cos_sin_turn(u.y);  // phi = 2 pi u.y
    return {r * cs.x, r * cs.y, z};
}

/// Uniform direction in the cone around +z with cos(half angle) = cos_max;
/// pdf = 1 / (2 pi (1 - cos_max)).
inline Vec3 sample_uniform_cone(const Vec2& u, float cos_max) {
    // Through 1 - cos(theta), exact for narrow cones where cos(theta) itself has few float steps.
    const float one_minus_cos = u.x * (1.0f - cos_max);
    const float cos_theta = 1.0f - one_minus_cos;
    const float sin_theta = safe_sqrt(one_minus_cos * (2.0f - one_minus_cos));
    const Vec2 cs = cos_sin_turn(u.y);  // phi = 2 pi u.y
    return {sin_theta * cs.x, sin_theta * cs.y, cos_theta};
}
inline float uniform_cone_pdf(float cos_max) { return 1.0f / (2.0f * kPi * (1.0f - cos_max)); }

/// Uniform barycentrics (b0, b1) on a triangle (Heitz 2019, low-distortion map); b2 = 1-b0-b1.
inline Vec2 sample_uniform_triangle(const Vec2& u) {
    float b0, b1;
    if (u.x < u.y) {
        b0 = u.x / 2.0f;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0f;
        b0 = u.x - b1;
    }
    return {b0, b1};
}

/// Veach's power heuristic with beta = 2, for multiple importance sampling.
inline float power_heuristic(float pdf_a, float pdf_b) {
    const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    if (a == 0.0f) return 0.0f;
    if (!std::isfinite(a)) return 1.0f;
    return a / (a + b);
}

/// A discrete distribution proportional to non-negative weights (built once, then read-only).
class DiscreteDistribution {
public:
    DiscreteDistribution() = default;
    explicit DiscreteDistribution(std::span<const float> weights);

    /// Picks an index for u in [0,1); returns the index and writes its probability.
    /// u_remapped (optional) receives u rescaled to [0,1) within the chosen bin.
    uint32_t sample(float u, float* probability, float* u_remapped = nullptr) const;
    float probability(uint32_t index) const;
    size_t size() const { return cdf_.empty() ? 0 : cdf_.size() - 1; }
    double total() const { return total_; }
    bool empty() const { return total_ <= 0.0; }

private:
    std::vector<double> cdf_;  // size n + 1, cdf_[0] = 0, cdf_[n] = 1
    double total_ = 0.0;
};

// Inline: every photon and every light sample picks a light with it.
inline uint32_t DiscreteDistribution::sample(float u, float* probability, float* u_remapped) const {
    // First bin whose upper cdf bound exceeds u; empty bins (zero width) are never chosen.
    const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), static_cast<double>(u));
    uint32_t index = static_cast<uint32_t>(std::min<ptrdiff_t>(it - cdf_.begin() - 1,
                                                               static_cast<ptrdiff_t>(size()) - 1));
    while (index > 0 && cdf_[index + 1] - cdf_[index] <= 0.0) --index;
    const double width = cdf_[index + 1] - cdf_[index];
    if (probability) *probability = static_cast<float>(width);
    if (u_remapped) {
        const double r = width > 0.0 ? (u - cdf_[index]) / width : 0.0;
        *u_remapped = static_cast<float>(std::clamp(r, 0.0, 0x1.fffffep-1));
    }
    return index;
}

}  // namespace photond
