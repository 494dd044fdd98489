// The environment as a light: radiance by direction, and directions importance-sampled by a
// piecewise-constant 2D distribution over the equirectangular image in proportion to luminance
// times sin(theta) (pbrt-v3, section 14.2.4 "Infinite Area Lights"), so that bright parts of the
// sky (the sun in an HDR image) get the samples. A uniform environment samples the sphere
// uniformly. Immutable after construction; safe to share between threads.
#pragma once

#include <optional>
#include <vector>

#include "core/math/equirectangular.h"
#include "core/math/sampling.h"
#include "core/scene/scene.h"

namespace photond {

/// An environment as the sum of its peaks (texels far brighter than its average, such as the
/// sun in a sky image) and the rest, the diffuse sky. Final gathering collects the diffuse sky
/// smoothly through the irradiance cache while light sampling takes the peaks, whose sharp
/// shadows a cache would blur. A uniform environment has no peaks.
struct EnvironmentSplit {
    std::optional<Environment> peaks;    // absent when no texel is a peak
    std::optional<Environment> diffuse;  // absent when every lit texel is a peak
};

/// A texel is a peak when its luminance exceeds this many times the environment's average
/// luminance over the sphere.
inline constexpr float kEnvironmentPeakFactor = 16.0f;

EnvironmentSplit split_environment_peaks(const Environment& environment,
                                         float peak_factor = kEnvironmentPeakFactor);

class EnvironmentLight {
public:
    explicit EnvironmentLight(const Environment& environment);

    /// Radiance arriving from direction `d` (unit, pointing away from the scene towards the sky).
    Color radiance(const Vec3& d) const;
    /// A direction towards the sky and its solid-angle pdf (0 when the environment is black).
    Vec3 sample(Vec2 u, float* pdf) const;
    /// The solid-angle pdf with which sample() returns `d`.
    float pdf(const Vec3& d) const;
    /// The integral of the radiance over the sphere of directions (W m^-2): the power the
    /// environment sends through a disc of area A facing each direction is A times this.
    Color radiance_integral() const { return integral_; }
    bool is_black() const { return !(max_component(integral_) > 0.0f); }

    /// The image coordinates (u, v) in [0, 1)^2 of a world direction, and back.
    Vec2 direction_to_uv(const Vec3& d) const;
    Vec3 uv_to_direction(const Vec2& uv) const;

private:
    Color texel(int x, int y) const;
    /// The texel holding image coordinates uv (nearest: radiance, sample and pdf agree on it).
    glm::ivec2 texel_at(const Vec2& uv) const;

    const Environment* environment_;
    float cos_rotation_ = 1.0f, sin_rotation_ = 0.0f;
    Color integral_{0.0f};
    // Image environments: rows chosen by `rows_`, then a column within the row by its own
    // distribution (uniform in (u, v) inside a texel).
    DiscreteDistribution rows_;
    std::vector<DiscreteDistribution> columns_;
};

}  // namespace photond
