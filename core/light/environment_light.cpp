#include "core/light/environment_light.h"

#include <cmath>

namespace photond {

EnvironmentLight::EnvironmentLight(const Environment& environment) : environment_(&environment) {
    cos_rotation_ = std::cos(environment.rotation);
    sin_rotation_ = std::sin(environment.rotation);
    if (!environment.has_image()) {
        integral_ = 4.0f * kPi * environment.intensity * environment.color;
        return;
    }
    const int w = environment.width, h = environment.height;
    std::vector<float> row_weights(static_cast<size_t>(h));
    std::vector<float> weights(static_cast<size_t>(w));
    columns_.reserve(static_cast<size_t>(h));
    // Each texel spans (2 pi / w) x (pi / h) in (phi, theta): its solid angle is that area times
    // sin(theta) (integrated over the row exactly: cos(theta0) - cos(theta1)).
    DVec3 integral(0.0);
    for (int y = 0; y < h; ++y) {
        const double theta0 = 3.14159265358979323846 * y / h;
        const double theta1 = 3.14159265358979323846 * (y + 1) / h;
        const double row_solid_angle = 2.0 * 3.14159265358979323846 * (std::cos(theta0) - std::cos(theta1));
        const double texel_solid_angle = row_solid_angle / w;
        double row_sum = 0.0;
        for (int x = 0; x < w; ++x) {
            const Color c = texel(x, y);
            weights[static_cast<size_t>(x)] = std::max(luminance(c), 0.0f);
            row_sum += weights[static_cast<size_t>(x)];
            integral += DVec3(c) * texel_solid_angle;
        }
        columns_.emplace_back(weights);
        row_weights[static_cast<size_t>(y)] = static_cast<float>(row_sum * (std::cos(theta0) - std::cos(theta1)));
    }
    rows_ = DiscreteDistribution(row_weights);
    integral_ = Color(integral);
}

EnvironmentSplit split_environment_peaks(const Environment& environment, float peak_factor) {
    EnvironmentSplit split;
    const EnvironmentLight light(environment);
    const float threshold = peak_factor * luminance(light.radiance_integral()) * kInv4Pi;
    if (!environment.has_image() || !(threshold > 0.0f)) {
        split.diffuse = environment;
        return split;
    }
    Environment peaks = environment, diffuse = environment;
    peaks.name = environment.name + " (peaks)";
    bool any_peak = false, any_diffuse = false;
    for (size_t i = 0; i < environment.texels.size(); ++i) {
        const bool peak = environment.intensity * luminance(environment.texels[i]) > threshold;
        (peak ? diffuse : peaks).texels[i] = Color(0.0f);
        any_peak |= peak;
        any_diffuse |= !peak && max_component(environment.texels[i]) > 0.0f;
    }
    if (any_peak) split.peaks = std::move(peaks);
    if (any_diffuse) split.diffuse = std::move(diffuse);
    return split;
}

Color EnvironmentLight::texel(int x, int y) const {
    const Environment& e = *environment_;
    return e.intensity * e.texels[static_cast<size_t>(y) * static_cast<size_t>(e.width) + static_cast<size_t>(x)];
}

Vec2 EnvironmentLight::direction_to_uv(const Vec3& d) const {
    // Into the image's frame: turn by -rotation about +Y.
    return equirectangular_uv({cos_rotation_ * d.x - sin_rotation_ * d.z, d.y, sin_rotation_ * d.x + cos_rotation_ * d.z});
}

Vec3 EnvironmentLight::uv_to_direction(const Vec2& uv) const {
    const Vec3 d = equirectangular_direction(uv);
    // Out of the image's frame: turn by +rotation about +Y.
    return {cos_rotation_ * d.x + sin_rotation_ * d.z, d.y, -sin_rotation_ * d.x + cos_rotation_ * d.z};
}

glm::ivec2 EnvironmentLight::texel_at(const Vec2& uv) const {
    const Environment& e = *environment_;
    return {std::min(static_cast<int>(uv.x * static_cast<float>(e.width)), e.width - 1),
            std::min(static_cast<int>(uv.y * static_cast<float>(e.height)), e.height - 1)};
}

Color EnvironmentLight::radiance(const Vec3& d) const {
    const Environment& e = *environment_;
    if (!e.has_image()) return e.intensity * e.color;
    // Nearest texel: the same piecewise-constant function that sample() and pdf() describe, so
    // that light samples and BSDF samples of the sky agree exactly.
    const glm::ivec2 t = texel_at(direction_to_uv(d));
    return texel(t.x, t.y);
}

Vec3 EnvironmentLight::sample(Vec2 u, float* pdf) const {
    const Environment& e = *environment_;
    if (is_black()) {
        *pdf = 0.0f;
        return Vec3(0.0f, 1.0f, 0.0f);
    }
    if (!e.has_image()) {
        *pdf = kInv4Pi;
        return sample_uniform_sphere(u);
    }
    float row_probability = 0.0f, column_probability = 0.0f, v_in_row = 0.0f, u_in_column = 0.0f;
    const uint32_t row = rows_.sample(u.y, &row_probability, &v_in_row);
    const uint32_t column = columns_[row].sample(u.x, &column_probability, &u_in_column);
    // Off the poles, where sin(theta) = 0 would make the density infinite (a set of measure 0).
    const Vec2 uv((static_cast<float>(column) + u_in_column) / static_cast<float>(e.width),
                  std::clamp((static_cast<float>(row) + v_in_row) / static_cast<float>(e.height), 0x1p-20f,
                             1.0f - 0x1p-20f));
    const float sin_theta = std::sin(kPi * uv.y);
    // pdf(u, v) = p_row p_column w h; domega = 2 pi^2 sin(theta) du dv.
    const float pdf_uv = row_probability * column_probability * static_cast<float>(e.width) *
                         static_cast<float>(e.height);
    *pdf = sin_theta > 0.0f ? pdf_uv / (2.0f * kPi * kPi * sin_theta) : 0.0f;
    return uv_to_direction(uv);
}

float EnvironmentLight::pdf(const Vec3& d) const {
    const Environment& e = *environment_;
    if (is_black()) return 0.0f;
    if (!e.has_image()) return kInv4Pi;
    const Vec2 uv = direction_to_uv(d);
    const glm::ivec2 t = texel_at(uv);
    const uint32_t x = static_cast<uint32_t>(t.x), y = static_cast<uint32_t>(t.y);
    const float sin_theta = std::sin(kPi * uv.y);
    if (!(sin_theta > 0.0f)) return 0.0f;
    const float pdf_uv = rows_.probability(y) * columns_[y].probability(x) * static_cast<float>(e.width) *
                         static_cast<float>(e.height);
    return pdf_uv / (2.0f * kPi * kPi * sin_theta);
}

}  // namespace photond
