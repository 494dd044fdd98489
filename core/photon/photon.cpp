#include "core/photon/photon.h"

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>

namespace photond {
namespace {

// constexpr sine and cosine (Taylor series in double, arguments in [-pi, pi]) so that the
// decoding tables are constant-initialised: no static initialisation order to worry about.
constexpr double kPiDouble = 3.14159265358979323846;

constexpr double reduce_angle(double x) {
    while (x > kPiDouble) x -= 2.0 * kPiDouble;
    while (x < -kPiDouble) x += 2.0 * kPiDouble;
    return x;
}

constexpr double constexpr_sin(double x) {
    x = reduce_angle(x);
    double term = x, sum = x;
    for (int n = 1; n < 30; ++n) {
        term *= -x * x / double((2 * n) * (2 * n + 1));
        sum += term;
    }
    return sum;
}

constexpr double constexpr_cos(double x) { return constexpr_sin(x + 0.5 * kPiDouble); }

constexpr PhotonDirectionTables make_direction_tables() {
    PhotonDirectionTables t{};
    for (int i = 0; i < 256; ++i) {
        const double theta = (i + 0.5) * kPiDouble / 256.0;
        const double phi = (i + 0.5) * 2.0 * kPiDouble / 256.0;
        t.cos_theta[i] = float(constexpr_cos(theta));
        t.sin_theta[i] = float(constexpr_sin(theta));
        t.cos_phi[i] = float(constexpr_cos(phi));
        t.sin_phi[i] = float(constexpr_sin(phi));
    }
    return t;
}

// Flux channels as encodable numbers: NaN and negatives -> 0, +inf -> FLT_MAX.
float sanitize_channel(float c) {
    if (!(c > 0.0f)) return 0.0f;
    return std::min(c, FLT_MAX);
}

/// x * 2^k for k in [-126, 127]: exact (as ldexp) unless the product is subnormal, when it may
/// flush to zero, which the callers round to zero anyway.
float times_power_of_two(float x, int k) { return x * std::bit_cast<float>(uint32_t(k + 127) << 23); }

/// lround for 0 <= v < 2^32, without a libm call: v - trunc(v) is exact.
uint32_t round_half_away(float v) {
    const uint32_t r = static_cast<uint32_t>(v);
    return r + (v - static_cast<float>(r) >= 0.5f ? 1u : 0u);
}

// Octahedral normal codes (Meyer et al. 2010): the unit octahedron |x| + |y| + |z| = 1 folded
// onto the square [-1, 1]^2, 16 bits per coordinate (Photon::normal decodes them).
uint16_t normal_code(float c) {
    return uint16_t(round_half_away(std::clamp(c * 0.5f + 0.5f, 0.0f, 1.0f) * Photon::kNormalScale));
}

}  // namespace

constinit const PhotonDirectionTables kPhotonDirectionTables = make_direction_tables();

void Photon::set_flux(const Color& flux) {
    // Shared exponent from the largest channel, mantissas rounded to nearest (the encoded value
    // is the representable one nearest to each channel for that exponent). Float bit arithmetic,
    // exact like frexp, ldexp and lround, which were a tenth of packing a photon.
    flux_mantissas_ = 0;
    flux_exponent_ = 0;
    const float rgb[3] = {sanitize_channel(flux.x), sanitize_channel(flux.y), sanitize_channel(flux.z)};
    const float largest = std::max(rgb[0], std::max(rgb[1], rgb[2]));
    // largest = f * 2^exponent with f in [0.5, 1) (frexp's convention); subnormals fall below the range.
    int exponent = static_cast<int>(std::bit_cast<uint32_t>(largest) >> 23) - 126;
    if (largest > 0.0f && exponent >= kMinFluxExponent) {
        if (round_half_away(times_power_of_two(largest, 10 - exponent)) >= 1024) ++exponent;  // rounds up
        exponent = std::min(exponent, kMaxFluxExponent);
        uint32_t mantissas = 0;
        for (int c = 0; c < 3; ++c) {
            const uint32_t m = std::min(1023u, round_half_away(times_power_of_two(rgb[c], 10 - exponent)));
            mantissas |= m << (10 * c);
        }
        flux_mantissas_ = mantissas;
        flux_exponent_ = uint8_t(exponent - kMinFluxExponent + 1);
    }
}

void Photon::scale_flux(double factor) { set_flux(Color(DVec3(flux()) * factor)); }

Photon make_photon(Vec3 position, Vec3 direction, Color flux, uint8_t user_flags, Vec3 normal) {
    Photon p;
    p.position = position;
    p.flags_ = uint8_t((user_flags << 2) | 3u);

    p.set_flux(flux);

    // Direction: theta = acos(z), phi = atan2(y, x) (Jensen 2001, section 6.3).
    const float length = glm::length(direction);
    Vec3 d = (length > 0.0f && std::isfinite(length)) ? direction / length : Vec3(0, 0, 1);
    if (!is_finite(d)) d = Vec3(0, 0, 1);
    const float theta = std::acos(std::clamp(d.z, -1.0f, 1.0f));
    float phi = std::atan2(d.y, d.x);
    if (phi < 0.0f) phi += 2.0f * kPi;
    p.theta_ = uint8_t(std::min(255, int(theta * (256.0f / kPi))));
    p.phi_ = uint8_t(int(phi * (256.0f / (2.0f * kPi))) & 255);  // phi = 2 pi wraps to bin 0

    // Normal: projected onto the octahedron, the lower half folded over the diagonals.
    const float l1 = std::abs(normal.x) + std::abs(normal.y) + std::abs(normal.z);
    if (l1 > 0.0f && std::isfinite(l1)) {
        float x = normal.x / l1, y = normal.y / l1;
        if (normal.z < 0.0f) {
            const float folded_x = (1.0f - std::abs(y)) * Photon::sign_not_zero(x);
            y = (1.0f - std::abs(x)) * Photon::sign_not_zero(y);
            x = folded_x;
        }
        p.normal_u_ = normal_code(x);
        p.normal_v_ = normal_code(y);
        // (0, 0) is "no normal"; it decodes to -z, as does the opposite corner.
        if (p.normal_u_ == 0 && p.normal_v_ == 0) p.normal_u_ = p.normal_v_ = 65535;
    }
    return p;
}

Photon make_irradiance_site(Vec3 position, Vec3 normal, Color irradiance, float radius) {
    Photon p = make_photon(position, normal, irradiance, 0, normal);
    // 2^(code / 512 - 64): a relative step of 0.14 % from 2^-64 to 2^64, as fine at every scale
    // (a scene scaled by any factor keeps its sites' radii to that step). Code 0 is zero.
    uint32_t code = 0;
    if (std::isfinite(radius) && radius > 0.0f) {
        const double scaled = (std::log2(static_cast<double>(radius)) + Photon::kSiteRadiusLog2Offset) * Photon::kSiteRadiusStepsPerOctave;
        code = static_cast<uint32_t>(std::clamp(std::lround(scaled), 1l, 65535l));
    } else if (radius > 0.0f) {
        code = 65535;  // +infinity: the largest
    }
    p.theta_ = uint8_t(code & 0xffu);
    p.phi_ = uint8_t(code >> 8);
    return p;
}

float Photon::site_radius() const {
    const uint32_t code = theta_ | (uint32_t(phi_) << 8);
    if (code == 0) return 0.0f;
    return static_cast<float>(std::exp2(static_cast<double>(code) / kSiteRadiusStepsPerOctave - kSiteRadiusLog2Offset));
}

}  // namespace photond
