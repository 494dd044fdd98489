// Small math vocabulary shared by the whole renderer: GLM vectors plus a few helpers.
#pragma once

#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>

namespace photond {

using Vec2 = glm::vec2;
using Vec3 = glm::vec3;
using Vec4 = glm::vec4;
using Mat3 = glm::mat3;
using Mat4 = glm::mat4;
using DVec3 = glm::dvec3;
/// Linear RGB radiance, irradiance, flux or reflectance.
using Color = glm::vec3;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 1.0f / kPi;
inline constexpr float kInv2Pi = 1.0f / (2.0f * kPi);
inline constexpr float kInv4Pi = 1.0f / (4.0f * kPi);

inline float max_component(const Vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }
inline float min_component(const Vec3& v) { return std::min(v.x, std::min(v.y, v.z)); }
inline float max_abs_component(const Vec3& v) {
    return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z)));
}
/// Rec. 709 luminance of a linear RGB colour.
inline float luminance(const Color& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
inline float average(const Color& c) { return (c.x + c.y + c.z) * (1.0f / 3.0f); }
inline bool is_black(const Color& c) { return c.x <= 0.0f && c.y <= 0.0f && c.z <= 0.0f; }
inline bool is_finite(const Vec3& v) {
    // x - x is 0 for every finite x and NaN for infinities and NaN: one branch-free test where
    // three isfinite calls with their short-circuit branches cost four times the instructions.
    return (v.x - v.x) + (v.y - v.y) + (v.z - v.z) == 0.0f;
}
inline float safe_sqrt(float x) { return std::sqrt(std::max(0.0f, x)); }
inline float sqr(float x) { return x * x; }

/// Reflects w (pointing away from the surface) about the normal n.
inline Vec3 reflect(const Vec3& w, const Vec3& n) { return 2.0f * glm::dot(w, n) * n - w; }

}  // namespace photond
