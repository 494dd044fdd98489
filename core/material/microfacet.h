// The isotropic GGX (Trowbridge-Reitz) microfacet distribution with the height-correlated Smith
// masking-shadowing function and visible-normal sampling. Local frame: the macro normal is +z;
// callers pass directions on the +z side (wo.z > 0) and microfacet normals with h.z > 0.
#pragma once

#include <limits>

#include "core/math/trig.h"
#include "core/math/vec.h"

namespace photond {

class GgxDistribution {
public:
    explicit GgxDistribution(float alpha) : alpha_(alpha) {}

    float alpha() const { return alpha_; }

    /// Normal distribution D(h) (Walter et al. 2007, eq. 33).
    float d(const Vec3& h) const {
        if (h.z <= 0.0f) return 0.0f;
        const float a2 = alpha_ * alpha_;
        const float t = h.z * h.z * (a2 - 1.0f) + 1.0f;
        return a2 / (kPi * t * t);
    }

    /// Smith's Lambda for GGX (Heitz 2014, "Understanding the Masking-Shadowing Function",
    /// eq. 72), symmetric in the sign of w.z.
    float lambda(const Vec3& w) const {
        const float cos2 = w.z * w.z;
        if (cos2 <= 0.0f) return std::numeric_limits<float>::infinity();
        const float tan2 = std::max(0.0f, 1.0f - cos2) / cos2;
        return 0.5f * (std::sqrt(1.0f + alpha_ * alpha_ * tan2) - 1.0f);
    }

    /// Masking G1(w) = 1 / (1 + Lambda(w)).
    float g1(const Vec3& w) const { return 1.0f / (1.0f + lambda(w)); }

    /// Height-correlated masking-shadowing G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) (Heitz 2014,
    /// eq. 99), used for reflection and, as in pbrt, for transmission. G2 <= G1(wo), which keeps
    /// every lobe's albedo at or below one under visible-normal sampling.
    float g2(const Vec3& wo, const Vec3& wi) const {
        return 1.0f / (1.0f + lambda(wo) + lambda(wi));
    }

    /// Samples a visible normal for wo (wo.z > 0) (Heitz 2018, "Sampling the GGX Distribution of
    /// Visible Normals", JCGT 7(4), listing 1). Density: visible_normal_pdf(wo, h).
    Vec3 sample_visible_normal(const Vec3& wo, const Vec2& u) const {
        // Stretch wo to the hemisphere configuration.
        const Vec3 vh = glm::normalize(Vec3(alpha_ * wo.x, alpha_ * wo.y, wo.z));
        const float len2 = vh.x * vh.x + vh.y * vh.y;
        const Vec3 t1 = len2 > 0.0f ? Vec3(-vh.y, vh.x, 0.0f) / std::sqrt(len2) : Vec3(1, 0, 0);
        const Vec3 t2 = glm::cross(vh, t1);
        // Uniform point on the disc, warped to the projected visible hemisphere.
        const float r = std::sqrt(u.x);
        const Vec2 cs = cos_sin_turn(u.y);  // phi = 2 pi u.y
        const float p1 = r * cs.x;
        float p2 = r * cs.y;
        const float s = 0.5f * (1.0f + vh.z);
        p2 = (1.0f - s) * safe_sqrt(1.0f - p1 * p1) + s * p2;
        const Vec3 nh = p1 * t1 + p2 * t2 + safe_sqrt(1.0f - p1 * p1 - p2 * p2) * vh;
        // Unstretch.
        return glm::normalize(Vec3(alpha_ * nh.x, alpha_ * nh.y, std::max(1e-7f, nh.z)));
    }

    /// Density of sample_visible_normal: D_wo(h) = G1(wo) max(0, wo.h) D(h) / wo.z
    /// (Heitz 2018, eq. 3).
    float visible_normal_pdf(const Vec3& wo, const Vec3& h) const {
        if (wo.z <= 0.0f) return 0.0f;
        return g1(wo) * std::max(0.0f, glm::dot(wo, h)) * d(h) / wo.z;
    }

private:
    float alpha_;
};

}  // namespace photond
