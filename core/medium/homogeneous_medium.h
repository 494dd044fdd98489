// A homogeneous participating medium (fog, smoke, murky water): absorption and scattering
// coefficients per world unit and a Henyey-Greenstein phase function. What a path through it
// needs: transmittance, free-flight distance sampling, and the phase function's value and
// sampling (docs/ARCHITECTURE.md, "Where each algorithm lives").
#pragma once

#include "core/math/vec.h"

namespace photond {

struct HomogeneousMedium {
    Color sigma_a{0.0f};  // absorption coefficient per world unit, per channel
    Color sigma_s{0.0f};  // scattering coefficient per world unit, per channel
    float g = 0.0f;       // Henyey-Greenstein asymmetry: > 0 forward, < 0 backward, |g| < 1

    Color sigma_t() const { return sigma_a + sigma_s; }
    bool scatters() const { return max_component(sigma_s) > 0.0f; }
    bool empty() const { return !(max_component(sigma_t()) > 0.0f); }
    /// Beer-Lambert: exp(-sigma_t d) per channel; exactly 1 where sigma_t is 0, for any d.
    Color transmittance(float distance) const;
};

/// Where a free flight through a segment of the medium ends: a scattering event `t` along it, or
/// the segment's far end.
struct FreeFlight {
    float t = 0.0f;
    bool scattered = false;
    /// The path throughput's factor: sigma_s T(t) / p(t) at a scattering event, T(length) /
    /// P(passing) at the far end, p and P the hero channel's.
    Color weight{1.0f};
    /// Each channel's density of the same outcome over the hero channel's: sigma_t T(t) / p(t),
    /// or T(length) / P(passing).
    Color pdf_ratio{1.0f};
};

/// Samples a free flight over a segment of `length` (finite) by the extinction of the path's hero
/// channel (Wilkie et al. 2014, "Hero Wavelength Spectral Sampling"): t = -ln(1 - u) /
/// sigma_t[hero]. A path that draws its hero uniformly once and divides what it adds by the
/// average over the channels of the product of its pdf_ratio factors weights its colour channels
/// by the balance heuristic over the whole path (pbrt-v4's r_u): a medium whose coefficients
/// differ by colour stays unbiased with weights that do not grow along the path, as they do when
/// each event picks its own channel. Absorption ends no path: it weights it.
FreeFlight sample_free_flight(const HomogeneousMedium& medium, float length, int hero, float u);

/// A distance in a segment of the medium and its density.
struct SegmentDistance {
    float t = 0.0f;
    float pdf = 0.0f;
};

/// Samples a distance in [0, length) (finite, > 0) with density proportional to the
/// transmittance, truncated to the segment: a channel with probability 1/3 (u_channel), then
/// t = -ln(1 - u (1 - exp(-sigma_t length))) / sigma_t of that channel (uniform where sigma_t is
/// 0). The pdf is the channels' average. For single scattering along a ray, where every ray
/// should find the medium's light whatever its optical depth.
SegmentDistance sample_distance_in_segment(const HomogeneousMedium& medium, float length, float u_channel, float u);

/// The Henyey-Greenstein phase function (1 / 4 pi) (1 - g^2) / (1 + g^2 - 2 g cos)^(3/2) for
/// light that arrives from direction wi (unit, pointing from the scattering point towards where
/// the light comes from) and leaves along wo (unit, pointing away): the scattering angle's cosine
/// is dot(-wi, wo), so g > 0 sends light on roughly the way it travelled.
float henyey_greenstein(float g, const Vec3& wo, const Vec3& wi);

/// A direction wi drawn with density henyey_greenstein(g, wo, wi) (the phase function is
/// normalised, so that is also its pdf).
Vec3 sample_henyey_greenstein(float g, const Vec3& wo, const Vec2& u);

}  // namespace photond
