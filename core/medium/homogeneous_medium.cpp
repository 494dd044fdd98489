#include "core/medium/homogeneous_medium.h"

#include <algorithm>
#include <cmath>

#include "core/math/frame.h"
#include "core/math/trig.h"

namespace photond {

namespace {

/// exp(-sigma d) that is 1 for sigma = 0 even when d is infinite.
float attenuation(float sigma, float distance) { return sigma > 0.0f ? std::exp(-sigma * distance) : 1.0f; }

/// Below this |g| the phase function is sampled as isotropic: the inversion formula divides by g.
constexpr float kIsotropicG = 1e-3f;

}  // namespace

Color HomogeneousMedium::transmittance(float distance) const {
    const Color s = sigma_t();
    return {attenuation(s.x, distance), attenuation(s.y, distance), attenuation(s.z, distance)};
}

FreeFlight sample_free_flight(const HomogeneousMedium& medium, float length, int hero, float u) {
    const Color sigma_t = medium.sigma_t();
    const float sigma = sigma_t[hero];
    FreeFlight flight;
    // -log1p(-u) keeps u close to 1 finite and u = 0 at t = 0.
    const float t = sigma > 0.0f ? -std::log1p(-std::min(u, 0.99999994f)) / sigma : length;
    if (t < length) {
        const Color tr = medium.transmittance(t);
        const float pdf = sigma * tr[hero];
        flight.t = t;
        flight.scattered = true;
        if (pdf > 0.0f) {
            flight.weight = medium.sigma_s * tr / pdf;
            flight.pdf_ratio = sigma_t * tr / pdf;
        } else {
            flight.weight = flight.pdf_ratio = Color(0.0f);
        }
        return flight;
    }
    const Color tr = medium.transmittance(length);
    flight.t = length;
    if (tr[hero] > 0.0f) {
        flight.weight = flight.pdf_ratio = tr / tr[hero];
    } else {
        flight.weight = flight.pdf_ratio = Color(0.0f);
    }
    return flight;
}

SegmentDistance sample_distance_in_segment(const HomogeneousMedium& medium, float length, float u_channel, float u) {
    const Color sigma_t = medium.sigma_t();
    // Per channel: the probability that a free flight ends inside the segment, and its density.
    const auto captured = [&](float sigma) { return sigma > 0.0f ? -std::expm1(-sigma * length) : 0.0f; };
    const auto density = [&](float sigma, float t) {
        const float inside = captured(sigma);
        return sigma > 0.0f && inside > 0.0f ? sigma * std::exp(-sigma * t) / inside : 1.0f / length;
    };
    const int channel = std::min(2, static_cast<int>(u_channel * 3.0f));
    const float sigma = sigma_t[channel];
    const float inside = captured(sigma);
    float t = sigma > 0.0f && inside > 0.0f ? -std::log1p(-u * inside) / sigma : u * length;
    t = std::clamp(t, 0.0f, std::nextafter(length, 0.0f));
    SegmentDistance sample;
    sample.t = t;
    sample.pdf = (density(sigma_t.x, t) + density(sigma_t.y, t) + density(sigma_t.z, t)) / 3.0f;
    return sample;
}

float henyey_greenstein(float g, const Vec3& wo, const Vec3& wi) {
    if (std::abs(g) < kIsotropicG) return 1.0f / (4.0f * kPi);  // as sample_henyey_greenstein draws it
    const float cos_theta = -glm::dot(wi, wo);
    const float denominator = 1.0f + g * g - 2.0f * g * cos_theta;
    return (1.0f - g * g) / (4.0f * kPi * denominator * std::sqrt(std::max(denominator, 1e-12f)));
}

Vec3 sample_henyey_greenstein(float g, const Vec3& wo, const Vec2& u) {
    float cos_theta;
    if (std::abs(g) < kIsotropicG) {
        cos_theta = 2.0f * u.x - 1.0f;
    } else {
        const float s = (1.0f - g * g) / (1.0f - g + 2.0f * g * u.x);
        cos_theta = (1.0f + g * g - s * s) / (2.0f * g);
    }
    cos_theta = std::clamp(cos_theta, -1.0f, 1.0f);
    const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    const Vec2 cs = cos_sin_turn(u.y);
    // The light's direction of travel, -wi, lies at the scattering angle from wo.
    const Vec3 travel = Frame(wo).to_world(Vec3(sin_theta * cs.x, sin_theta * cs.y, cos_theta));
    return -travel;
}

}  // namespace photond
