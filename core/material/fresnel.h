// Fresnel reflectance (exact dielectric and Schlick's approximation) and Snell refraction.
// All vectors are in a local frame; cosines are taken on the incident side (cos_i >= 0).
#pragma once

#include "core/math/vec.h"

namespace photond {

/// (1 - cos)^5, the angular term of Schlick's approximation.
inline float schlick_weight(float cos_theta) {
    const float m = std::clamp(1.0f - cos_theta, 0.0f, 1.0f);
    const float m2 = m * m;
    return m2 * m2 * m;
}

/// Schlick's approximation generalised to F90 (glTF 2.0 Appendix B, KHR_materials_specular):
/// F = F0 + (F90 - F0) (1 - cos)^5.
inline Color fresnel_schlick(const Color& f0, const Color& f90, float cos_theta) {
    return f0 + (f90 - f0) * schlick_weight(cos_theta);
}

/// Exact unpolarised Fresnel reflectance of a smooth dielectric interface for light arriving
/// with cosine cos_i (>= 0) on the side of index n_i; eta = n_t / n_i. Returns 1 under total
/// internal reflection (pbrt-v4 FrDielectric; Born & Wolf 1999, Sec. 1.5.2).
inline float fresnel_dielectric(float cos_i, float eta) {
    cos_i = std::clamp(cos_i, 0.0f, 1.0f);
    const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return 1.0f;
    const float cos_t = safe_sqrt(1.0f - sin2_t);
    const float r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const float r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5f * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
}

/// Refracts w (pointing away from the surface, on the side n points to: dot(w, n) > 0) through
/// an interface with relative index eta = n_t / n_i. Writes the transmitted direction (pointing
/// away on the other side) and returns false under total internal reflection (Snell's law in
/// vector form, pbrt-v4 Refract).
inline bool refract(const Vec3& w, const Vec3& n, float eta, Vec3* transmitted) {
    const float cos_i = glm::dot(w, n);
    const float sin2_t = std::max(0.0f, 1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return false;
    const float cos_t = safe_sqrt(1.0f - sin2_t);
    *transmitted = -w / eta + (cos_i / eta - cos_t) * n;
    return true;
}

}  // namespace photond
