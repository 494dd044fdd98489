// A compact photon for photon maps: 24 bytes. Jensen's 20 ("Realistic Image Synthesis Using
// Photon Mapping" (2001), section 6.3: position (3 floats), flux in a shared-exponent format,
// direction as two bytes (theta, phi) decoded through tables, one byte of flags) and the surface
// normal in 4 bytes, which Jensen suggests storing so that an estimate can refuse photons of
// other surfaces (section 7.2): photons on the inside of a thin closed object otherwise light its
// outside near the edges.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "core/math/vec.h"

namespace photond {

/// Decoding tables for the photon direction bytes: bin centres, theta = (i + 0.5) pi / 256 and
/// phi = (j + 0.5) 2 pi / 256 (Jensen 2001, section 6.3, with centred bins).
struct PhotonDirectionTables {
    std::array<float, 256> cos_theta, sin_theta, cos_phi, sin_phi;
};
/// Constant-initialised in photon.cpp, so usable from any static initialiser.
extern const PhotonDirectionTables kPhotonDirectionTables;

/// One stored photon. Trivially copyable, no padding: arrays of them may be compared bytewise.
///
/// Quantisation (both measured in tests/photon/photon_test.cpp):
/// - Flux: "RGB10E8", Ward's RGBE idea (Graphics Gems II, 1991) with 10-bit instead of 8-bit
///   mantissas: one shared exponent byte and three 10-bit mantissas, rounded to nearest. The
///   absolute error of every channel is at most max_channel / 1024, so the relative error is
///   <= 0.1% on the largest channel and < 1% on every channel >= max_channel / 10 (Ward's 8-bit
///   RGBE: 0.4% and only channels >= 0.4 max_channel). Range: max channel in [2^-101, 1.7e38];
///   smaller flux decodes as 0, larger saturates. Negative and NaN channels encode as 0, +inf
///   saturates; decoding never yields NaN or Inf.
/// - Direction: theta and phi in 256 bins each, decoded at the bin centre: angular error
///   <= 0.8 degrees (half a theta bin, 0.35 deg, combined with half a phi bin, 0.70 deg).
/// - Normal: octahedral map (Meyer et al. 2010, "On floating-point normal vectors"), 16 bits per
///   coordinate, rounded to nearest: angular error < 0.01 degrees. The code (0, 0) means "no
///   normal" (the encoder never writes it: that corner and (65535, 65535) both decode to -z).
struct Photon {
    Vec3 position{0.0f};

    /// The flux (power) the photon carries, decoded: mantissa * 2^(exponent - 10).
    Color flux() const {
        // Bytes above the largest exponent's (only from corrupt data) saturate.
        const int byte = std::min(int(flux_exponent_), kMaxFluxExponent - kMinFluxExponent + 1);
        const int exponent = byte + kMinFluxExponent - 1;
        // 2^(exponent - 10) built from its bits; the biased exponent stays in [16, 244].
        const float scale = std::bit_cast<float>(uint32_t(exponent - 10 + 127) << 23);
        return Color(float(flux_mantissas_ & 1023u), float((flux_mantissas_ >> 10) & 1023u),
                     float((flux_mantissas_ >> 20) & 1023u)) *
               scale;
    }

    /// The unit direction the photon travelled (towards the surface where it is stored).
    Vec3 direction() const {
        const PhotonDirectionTables& t = kPhotonDirectionTables;
        return {t.sin_theta[theta_] * t.cos_phi[phi_], t.sin_theta[theta_] * t.sin_phi[phi_],
                t.cos_theta[theta_]};
    }

    /// The unit surface normal on the side the photon arrived from, or zero when the photon was
    /// made without one. Inline: every photon a search meets may be asked for it.
    Vec3 normal() const {
        if (!has_normal()) return Vec3(0.0f);
        const float x = float(normal_u_) * (2.0f / kNormalScale) - 1.0f;
        const float y = float(normal_v_) * (2.0f / kNormalScale) - 1.0f;
        Vec3 n(x, y, 1.0f - std::abs(x) - std::abs(y));
        if (n.z < 0.0f) {  // the lower half, folded out of the square's corners
            n.x = (1.0f - std::abs(y)) * sign_not_zero(x);
            n.y = (1.0f - std::abs(x)) * sign_not_zero(y);
        }
        return glm::normalize(n);  // |n| >= 1 / sqrt(3): never zero
    }
    /// The largest octahedral normal code (16 bits a coordinate).
    static constexpr float kNormalScale = 65535.0f;
    /// The octahedral fold's sign: +1 for zero.
    static float sign_not_zero(float v) { return v >= 0.0f ? 1.0f : -1.0f; }
    bool has_normal() const { return normal_u_ != 0 || normal_v_ != 0; }

    /// An irradiance site's estimate radius (make_irradiance_site): the radius of the disc
    /// whose photons gave its irradiance. A site has no direction of travel; its two direction
    /// bytes hold the radius on a logarithmic scale, 2^(code / 512 - 64): within 0.07 % (half a
    /// step) of the radius from 2^-64 to 2^64, the same at every scale. Meaningless for photons.
    float site_radius() const;
    static constexpr double kSiteRadiusStepsPerOctave = 512.0;
    static constexpr double kSiteRadiusLog2Offset = 64.0;

    /// Six bits for the caller (e.g. which map, caustic or not), given to make_photon.
    uint8_t user_flags() const { return flags_ >> 2; }
    /// The kd-tree split axis (0, 1, 2) of a photon that is an inner node of a PhotonKdTree;
    /// 3 otherwise. Written by PhotonKdTree only.
    uint32_t split_axis() const { return flags_ & 3u; }

    /// Multiplies the flux by `factor` (>= 0) and encodes it anew: the photon tracer stores
    /// photons before it knows how many were emitted for their map, and divides once it does.
    /// Each rounding is within max_channel / 1024 (see above), the two within max_channel / 512.
    void scale_flux(double factor);

    // Raw encoded fields, for tests and serialisation.
    uint32_t flux_mantissas() const { return flux_mantissas_; }
    uint8_t flux_exponent() const { return flux_exponent_; }
    uint8_t theta_bin() const { return theta_; }
    uint8_t phi_bin() const { return phi_; }
    uint16_t normal_u() const { return normal_u_; }
    uint16_t normal_v() const { return normal_v_; }

    static constexpr int kMinFluxExponent = -100;  // smallest shared exponent (byte value 1)
    static constexpr int kMaxFluxExponent = 127;   // largest; byte value 0 means zero flux

private:
    friend Photon make_photon(Vec3 position, Vec3 direction, Color flux, uint8_t user_flags,
                              Vec3 normal);
    friend Photon make_irradiance_site(Vec3 position, Vec3 normal, Color irradiance, float radius);
    friend class PhotonKdTree;

    void set_split_axis(uint32_t axis) { flags_ = uint8_t((flags_ & ~3u) | (axis & 3u)); }
    void set_flux(const Color& flux);

    uint32_t flux_mantissas_ = 0;  // red bits 0-9, green 10-19, blue 20-29, bits 30-31 zero
    uint8_t flux_exponent_ = 0;    // shared exponent - kMinFluxExponent + 1; 0 = black
    uint8_t theta_ = 0;            // floor(theta * 256 / pi), theta = acos(direction.z)
    uint8_t phi_ = 0;              // floor(phi * 256 / (2 pi)), phi = atan2(y, x) in [0, 2 pi)
    uint8_t flags_ = 3;            // bits 0-1 split axis, bits 2-7 user flags
    uint16_t normal_u_ = 0;        // octahedral normal, both 0 = none
    uint16_t normal_v_ = 0;
};

// 24 = 12 + 4 + 4 x 1 + 2 x 2: the fields fill it, no padding.
static_assert(sizeof(Photon) == 24, "Photon must stay 24 bytes (Jensen's 20 and a normal)");
static_assert(std::is_trivially_copyable_v<Photon>);

/// Packs a photon. direction need not be unit (it is normalised; a zero or non-finite one
/// becomes +z); user_flags keeps its low 6 bits; normal need not be unit either (zero or
/// non-finite: the photon has none).
Photon make_photon(Vec3 position, Vec3 direction, Color flux, uint8_t user_flags = 0,
                   Vec3 normal = Vec3(0.0f));

/// Packs a precomputed irradiance site (PhotonMap::nearest_irradiance): its position, surface
/// normal (which the site must have: a zero or non-finite one gives a site no lookup accepts),
/// irradiance as its flux and its estimate's radius (Photon::site_radius; negative and NaN are
/// stored as 0, a positive radius below 2^-64 as that, beyond about 2^64 and +infinity as the
/// largest code, 2^(65535 / 512 - 64)).
Photon make_irradiance_site(Vec3 position, Vec3 normal, Color irradiance, float radius);

}  // namespace photond
