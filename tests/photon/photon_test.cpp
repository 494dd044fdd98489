// The packed photon: size, flux, direction and normal quantisation errors, robustness of the
// encoding.
#include "core/photon/photon.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/math/rng.h"
#include "core/math/sampling.h"

namespace photond {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

float angle_degrees(const Vec3& a, const Vec3& b) {
    // atan2 of |a x b| and a . b: accurate for small angles, unlike acos.
    return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)) * 180.0f / kPi;
}

Color decoded_flux(const Color& flux) { return make_photon(Vec3(0), Vec3(0, 0, 1), flux).flux(); }

// Jensen's 20 bytes and a 4-byte surface normal (photon.h).
TEST(Photon, IsTwentyFourBytes) { EXPECT_EQ(sizeof(Photon), 24u); }

TEST(Photon, PositionAndUserFlagsRoundTrip) {
    const Photon p = make_photon(Vec3(1.5f, -2.25f, 1e6f), Vec3(1, 0, 0), Color(1), 0x2a);
    EXPECT_EQ(p.position, Vec3(1.5f, -2.25f, 1e6f));
    EXPECT_EQ(p.user_flags(), 0x2a);
    EXPECT_EQ(p.split_axis(), 3u);
    EXPECT_EQ(make_photon(Vec3(0), Vec3(1, 0, 0), Color(1), 0xff).user_flags(), 0x3f);
}

// Flux within the format's range, every channel >= 1/10 of the largest: < 1% per channel; the
// largest channel <= 0.1%; every channel's absolute error <= max / 1024.
TEST(Photon, FluxRelativeErrorBelowOnePercent) {
    Rng rng(1, 2);
    float worst_relative = 0.0f, worst_largest = 0.0f, worst_absolute = 0.0f;
    for (int i = 0; i < 200000; ++i) {
        const float magnitude = std::exp2(-95.0f + 220.0f * rng.next_float());
        const Color flux =
            magnitude * Color(0.1f + 0.9f * rng.next_float(), 0.1f + 0.9f * rng.next_float(),
                              0.1f + 0.9f * rng.next_float());
        const Color decoded = decoded_flux(flux);
        const float largest = max_component(flux);
        for (int c = 0; c < 3; ++c) {
            ASSERT_TRUE(std::isfinite(decoded[c]));
            const float error = std::abs(decoded[c] - flux[c]);
            worst_relative = std::max(worst_relative, error / flux[c]);
            worst_absolute = std::max(worst_absolute, error / largest);
            if (flux[c] == largest) worst_largest = std::max(worst_largest, error / flux[c]);
        }
    }
    EXPECT_LT(worst_relative, 0.01f);
    EXPECT_LE(worst_largest, 0.5f / 512.0f * 1.0001f);
    EXPECT_LE(worst_absolute, 1.0f / 1024.0f * 1.0001f);
    EXPECT_GT(worst_relative, 0.001f);  // the test measures the quantisation, not an identity
}

TEST(Photon, GreyFluxAcrossMagnitudes) {
    for (float e = -100.0f; e <= 126.0f; e += 0.37f) {
        const float v = std::exp2(e);
        const Color decoded = decoded_flux(Color(v));
        EXPECT_NEAR(decoded.x / v, 1.0f, 0.5f / 512.0f * 1.0001f) << "2^" << e;
        EXPECT_EQ(decoded.x, decoded.y);
        EXPECT_EQ(decoded.x, decoded.z);
    }
}

TEST(Photon, FluxEncodingRoundsToNearest) {
    // 1 = 512 * 2^-9 exactly; the step at this exponent is 2^-9.
    EXPECT_EQ(decoded_flux(Color(1.0f)), Color(1.0f));
    const float step = std::exp2(-9.0f);
    EXPECT_EQ(decoded_flux(Color(1.0f + 0.49f * step)).x, 1.0f);
    EXPECT_EQ(decoded_flux(Color(1.0f + 0.51f * step)).x, 1.0f + step);
    // Largest channel rounding up to the next power of two: 1023.6 * 2^-10 -> 1.
    EXPECT_EQ(decoded_flux(Color(1023.6f / 1024.0f)).x, 1.0f);
    // Smaller channels share the largest one's exponent: 0.1 with max 1 -> 51 * 2^-9 (0.0996).
    EXPECT_FLOAT_EQ(decoded_flux(Color(1.0f, 0.1f, 0.0f)).y, 51.0f / 512.0f);
    EXPECT_EQ(decoded_flux(Color(1.0f, 0.1f, 0.0f)).z, 0.0f);
}

TEST(Photon, EncodingIsIdempotent) {
    Rng rng(3, 4);
    for (int i = 0; i < 10000; ++i) {
        const Color flux(std::exp2(40.0f * rng.next_float() - 20.0f) * rng.next_float(),
                         rng.next_float(), 1e-3f * rng.next_float());
        const Photon once = make_photon(Vec3(0), Vec3(0, 0, 1), flux);
        const Photon twice = make_photon(Vec3(0), Vec3(0, 0, 1), once.flux());
        ASSERT_EQ(once.flux_mantissas(), twice.flux_mantissas());
        ASSERT_EQ(once.flux_exponent(), twice.flux_exponent());
    }
}

// The photon tracer packs a photon before its map's emissions are counted and divides after:
// two roundings, each within max_channel / 1024, and every other field untouched.
TEST(Photon, ScaledFluxStaysWithinTwoRoundings) {
    Rng rng(5, 6);
    float worst_absolute = 0.0f;
    for (int i = 0; i < 100000; ++i) {
        const Color flux = std::exp2(60.0f * rng.next_float() - 10.0f) *
                           Color(0.1f + 0.9f * rng.next_float(), 0.1f + 0.9f * rng.next_float(), rng.next_float());
        const double factor = 1.0 / (1.0 + std::floor(1e7 * double(rng.next_float())));
        const Photon packed = make_photon(Vec3(1, 2, 3), Vec3(0.3f, -0.5f, 0.8f), flux, 17, Vec3(0, 1, 0));
        Photon scaled = packed;
        scaled.scale_flux(factor);
        const DVec3 exact = DVec3(flux) * factor;
        const double largest = std::max(exact.x, std::max(exact.y, exact.z));
        const Color decoded = scaled.flux();
        for (int c = 0; c < 3; ++c)
            worst_absolute = std::max(worst_absolute, float(std::abs(double(decoded[c]) - exact[c]) / largest));
        ASSERT_EQ(scaled.position, packed.position);
        ASSERT_EQ(scaled.theta_bin(), packed.theta_bin());
        ASSERT_EQ(scaled.phi_bin(), packed.phi_bin());
        ASSERT_EQ(scaled.normal_u(), packed.normal_u());
        ASSERT_EQ(scaled.normal_v(), packed.normal_v());
        ASSERT_EQ(scaled.user_flags(), 17);
    }
    EXPECT_LE(worst_absolute, 2.0f / 1024.0f * 1.0001f);
    EXPECT_GT(worst_absolute, 0.5f / 1024.0f);  // it measures rounding, not an identity
}

TEST(Photon, ZeroTinyHugeAndInvalidFlux) {
    EXPECT_EQ(decoded_flux(Color(0.0f)), Color(0.0f));
    EXPECT_EQ(decoded_flux(Color(-0.0f)), Color(0.0f));
    EXPECT_EQ(decoded_flux(Color(1e-35f)), Color(0.0f));                // below 2^-101
    EXPECT_EQ(decoded_flux(Color(FLT_TRUE_MIN)), Color(0.0f));          // denormal
    EXPECT_EQ(decoded_flux(Color(-1.0f, 2.0f, kNaN)), Color(0, 2, 0));  // invalid channels -> 0
    EXPECT_GT(decoded_flux(Color(1e-30f)).x, 0.0f);                     // inside the range

    for (const Color& extreme :
         {Color(FLT_MAX), Color(kInf), Color(kInf, 1.0f, kNaN), Color(3e38f, 1e38f, 0.0f)}) {
        const Color decoded = decoded_flux(extreme);
        EXPECT_TRUE(is_finite(decoded)) << decoded.x;
        EXPECT_GT(decoded.x, 1e38f);
    }
    // Every raw encoding, even one make_photon never writes, decodes to a finite colour.
    for (uint32_t e = 0; e < 256; ++e) {
        for (uint32_t m : {0u, 1u, 1023u, 0xffffffffu}) {
            Photon p = make_photon(Vec3(0), Vec3(0, 0, 1), Color(0));
            unsigned char bytes[sizeof(Photon)];
            std::memcpy(bytes, &p, sizeof(p));
            std::memcpy(bytes + 12, &m, 4);
            bytes[16] = uint8_t(e);
            std::memcpy(&p, bytes, sizeof(p));
            ASSERT_EQ(p.flux_exponent(), e);  // the offsets above are the fields'
            ASSERT_EQ(p.flux_mantissas(), m);
            ASSERT_TRUE(is_finite(p.flux())) << e << " " << m;
        }
    }
}

TEST(Photon, DirectionErrorBelowOneDegree) {
    Rng rng(5, 6);
    float worst = 0.0f;
    for (int i = 0; i < 200000; ++i) {
        const Vec3 d = sample_uniform_sphere(rng.next_vec2());
        const Vec3 decoded = make_photon(Vec3(0), d, Color(1)).direction();
        ASSERT_NEAR(glm::length(decoded), 1.0f, 1e-5f);
        worst = std::max(worst, angle_degrees(d, decoded));
    }
    EXPECT_LT(worst, 0.8f);
    EXPECT_GT(worst, 0.5f);  // the bins are as coarse as documented, no finer
}

TEST(Photon, DirectionSpecialCases) {
    const Vec3 axes[] = {
        Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0),      Vec3(0, -1, 0),
        Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, -1e-7f, 0),
    };
    for (const Vec3& d : axes) {
        EXPECT_LT(angle_degrees(d, make_photon(Vec3(0), d, Color(1)).direction()), 0.8f)
            << d.x << " " << d.y << " " << d.z;
    }
    // Not normalised: normalised first.
    EXPECT_LT(angle_degrees(Vec3(0, 3, 4) / 5.0f,
                            make_photon(Vec3(0), Vec3(0, 30, 40), Color(1)).direction()),
              0.8f);
    // Degenerate: +z.
    for (const Vec3& d : {Vec3(0), Vec3(kNaN, 0, 1), Vec3(kInf, 0, 0)}) {
        EXPECT_LT(angle_degrees(Vec3(0, 0, 1), make_photon(Vec3(0), d, Color(1)).direction()),
                  0.8f);
    }
}

TEST(Photon, NormalErrorBelowOneHundredthOfADegree) {
    Rng rng(7, 8);
    float worst = 0.0f;
    for (int i = 0; i < 200000; ++i) {
        const Vec3 n = sample_uniform_sphere(rng.next_vec2());
        // Not unit: the encoding normalises.
        const float length = 0.5f + rng.next_float();
        const Photon p = make_photon(Vec3(0), Vec3(0, 0, 1), Color(1), 0, n * length);
        ASSERT_TRUE(p.has_normal());
        const Vec3 decoded = p.normal();
        ASSERT_NEAR(glm::length(decoded), 1.0f, 1e-6f);
        worst = std::max(worst, angle_degrees(n, decoded));
    }
    EXPECT_LT(worst, 0.01f);
    EXPECT_GT(worst, 0.0005f);  // quantised to 16 bits per coordinate, not stored exactly
}

TEST(Photon, NormalSpecialCases) {
    // Axes, the folded corner (-z) and normals next to it on every side, near-axis normals.
    const Vec3 normals[] = {
        Vec3(1, 0, 0),           Vec3(-1, 0, 0),           Vec3(0, 1, 0),
        Vec3(0, -1, 0),          Vec3(0, 0, 1),            Vec3(0, 0, -1),
        Vec3(-1e-7f, -1e-7f, -1), Vec3(1e-7f, -1e-7f, -1), Vec3(-1e-7f, 1e-7f, -1),
        Vec3(-0.0f, -0.0f, -1),  Vec3(1, -1e-7f, 0),       Vec3(0, 0, -1e-30f),
    };
    for (const Vec3& n : normals) {
        const Photon p = make_photon(Vec3(0), Vec3(0, 0, 1), Color(1), 0, n);
        EXPECT_TRUE(p.has_normal()) << n.x << " " << n.y << " " << n.z;
        EXPECT_LT(angle_degrees(n, p.normal()), 0.01f) << n.x << " " << n.y << " " << n.z;
    }
    // No normal given, or none to give: the photon has none, and normal() is zero.
    EXPECT_FALSE(make_photon(Vec3(0), Vec3(0, 0, 1), Color(1)).has_normal());
    EXPECT_EQ(make_photon(Vec3(0), Vec3(0, 0, 1), Color(1)).normal(), Vec3(0.0f));
    for (const Vec3& n : {Vec3(0), Vec3(kNaN, 0, 1), Vec3(kInf, 0, 0), Vec3(-kInf, 1, 1)}) {
        const Photon p = make_photon(Vec3(0), Vec3(0, 0, 1), Color(1), 0, n);
        EXPECT_FALSE(p.has_normal()) << n.x << " " << n.y << " " << n.z;
        EXPECT_EQ(p.normal(), Vec3(0.0f));
    }
    // The normal leaves the other fields alone.
    const Photon with = make_photon(Vec3(1, 2, 3), Vec3(0, 1, 0), Color(0.5f), 0x15, Vec3(1, 0, 0));
    const Photon without = make_photon(Vec3(1, 2, 3), Vec3(0, 1, 0), Color(0.5f), 0x15);
    EXPECT_EQ(with.position, without.position);
    EXPECT_EQ(with.flux(), without.flux());
    EXPECT_EQ(with.direction(), without.direction());
    EXPECT_EQ(with.user_flags(), without.user_flags());
}

TEST(Photon, EveryNormalCodeDecodesToAUnitVector) {
    for (uint32_t u = 0; u < 65536; u += 257) {
        for (uint32_t v = 0; v < 65536; v += 255) {
            if (u == 0 && v == 0) continue;  // "no normal"
            Photon p = make_photon(Vec3(0), Vec3(0, 0, 1), Color(1));
            unsigned char bytes[sizeof(Photon)];
            std::memcpy(bytes, &p, sizeof(p));
            const uint16_t codes[2] = {uint16_t(u), uint16_t(v)};
            std::memcpy(bytes + 20, codes, sizeof(codes));
            std::memcpy(&p, bytes, sizeof(p));
            ASSERT_EQ(p.normal_u(), u);  // the offsets above are the fields'
            ASSERT_EQ(p.normal_v(), v);
            ASSERT_NEAR(glm::length(p.normal()), 1.0f, 1e-6f) << u << " " << v;
            // Re-encoding the decoded normal keeps it (the code may change: the square's border
            // folds onto itself, (0, v) and (0, 65535 - v) are the same normal).
            const Photon again = make_photon(Vec3(0), Vec3(0, 0, 1), Color(1), 0, p.normal());
            ASSERT_LT(angle_degrees(again.normal(), p.normal()), 0.005f) << u << " " << v;
        }
    }
}

TEST(Photon, IrradianceSiteKeepsItsRadiusWithinAStepAtEveryScale) {
    // A site's estimate radius lives in the direction bytes (make_irradiance_site), on a log
    // scale: within half a step, 2^(1/1024) - 1 = 0.068 %, from the tiniest scene to the largest.
    const Vec3 normal = glm::normalize(Vec3(0.3f, 0.9f, -0.2f));
    const float half_step = std::exp2(1.0f / 1024.0f) - 1.0f;
    for (const float radius : {1e-15f, 1e-4f, 0.0123f, 0.11f, 1.0f, 3.7f, 250.0f, 6e4f, 9.6e4f, 1e15f}) {
        const Photon site = make_irradiance_site(Vec3(1, 2, 3), normal, Color(0.5f, 1.0f, 2.0f), radius);
        EXPECT_NEAR(site.site_radius(), radius, radius * half_step * 1.001f) << radius;
        EXPECT_LT(angle_degrees(site.normal(), normal), 0.01f);
        EXPECT_NEAR(site.flux().y, 1.0f, 1e-3f);
    }
    EXPECT_EQ(make_irradiance_site(Vec3(0), normal, Color(1.0f), 0.0f).site_radius(), 0.0f);
    EXPECT_EQ(make_irradiance_site(Vec3(0), normal, Color(1.0f), -1.0f).site_radius(), 0.0f);
    EXPECT_EQ(make_irradiance_site(Vec3(0), normal, Color(1.0f), kNaN).site_radius(), 0.0f);
    EXPECT_GT(make_irradiance_site(Vec3(0), normal, Color(1.0f), kInf).site_radius(), 1e19f);
    EXPECT_GT(make_irradiance_site(Vec3(0), normal, Color(1.0f), 1e-30f).site_radius(), 0.0f);
}

}  // namespace
}  // namespace photond
