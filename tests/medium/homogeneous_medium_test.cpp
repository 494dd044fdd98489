// The homogeneous medium's sampling against closed forms: free flights and truncated distances
// are unbiased for chromatic coefficients (their expectations are the transmittance and the
// in-segment integrals), the Henyey-Greenstein phase function is normalised, its sampling follows
// its distribution (chi-square over the scattering angle's cosine) with mean cosine g, and the
// atmosphere's box clips rays as a slab test should.
#include "core/scene/atmosphere.h"
#include "core/medium/homogeneous_medium.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/math/rng.h"
#include "core/math/sampling.h"

namespace photond {
namespace {

HomogeneousMedium chromatic_medium() {
    HomogeneousMedium m;
    m.sigma_a = Color(0.2f, 0.0f, 1.0f);
    m.sigma_s = Color(0.5f, 1.5f, 0.0f);
    m.g = 0.3f;
    return m;
}

TEST(HomogeneousMedium, TransmittanceIsBeerLambertAndOneWithoutCoefficients) {
    const HomogeneousMedium m = chromatic_medium();
    const Color t = m.transmittance(2.0f);
    EXPECT_FLOAT_EQ(t.x, std::exp(-1.4f));
    EXPECT_FLOAT_EQ(t.y, std::exp(-3.0f));
    EXPECT_FLOAT_EQ(t.z, std::exp(-2.0f));
    HomogeneousMedium clear;
    clear.sigma_s = Color(0.0f, 1.0f, 0.0f);
    const Color far = clear.transmittance(std::numeric_limits<float>::infinity());
    EXPECT_EQ(far, Color(1.0f, 0.0f, 1.0f));
    EXPECT_TRUE(HomogeneousMedium{}.empty());
    EXPECT_FALSE(m.empty());
}

TEST(HomogeneousMedium, FreeFlightsAreUnbiasedPerChannel) {
    // With the hero channel drawn uniformly and the weight divided by the average pdf ratio,
    // over a segment of length L: E[weight; passed] = T(L), and E[weight; scattered] =
    // integral of sigma_s T(t) dt = sigma_s / sigma_t (1 - T(L)) (sigma_s L where sigma_t = 0).
    const HomogeneousMedium m = chromatic_medium();
    const float length = 1.3f;
    Rng rng(7, 1);
    const int n = 400000;
    DVec3 passed(0.0), scattered(0.0), scattered_t(0.0);
    for (int i = 0; i < n; ++i) {
        // A hero channel drawn uniformly, the weight divided by the average pdf ratio: one event
        // of a path (sample_free_flight).
        const int hero = std::min(2, static_cast<int>(rng.next_float() * 3.0f));
        const FreeFlight f = sample_free_flight(m, length, hero, rng.next_float());
        const DVec3 weight = DVec3(f.weight) / static_cast<double>(average(f.pdf_ratio));
        if (f.scattered) {
            ASSERT_LT(f.t, length);
            scattered += weight;
            scattered_t += weight * static_cast<double>(f.t);
        } else {
            passed += weight;
        }
    }
    passed /= n;
    scattered /= n;
    scattered_t /= n;
    for (int c = 0; c < 3; ++c) {
        const double st = m.sigma_t()[c], ss = m.sigma_s[c];
        const double t_l = std::exp(-st * length);
        EXPECT_NEAR(passed[c], t_l, 0.005 * t_l) << "channel " << c;
        const double expected = ss / st * (1.0 - t_l);
        EXPECT_NEAR(scattered[c], expected, 0.005 * std::max(expected, 0.05)) << "channel " << c;
        // First moment: integral of t sigma_s e^(-st t) dt over [0, L].
        const double moment = ss * (1.0 - t_l * (1.0 + st * length)) / (st * st);
        EXPECT_NEAR(scattered_t[c], moment, 0.01 * std::max(moment, 0.02)) << "channel " << c;
    }
}

TEST(HomogeneousMedium, SegmentDistancesIntegrateTheTransmittance) {
    // E[T(t) / pdf(t)] = integral of T over [0, L], also where one channel has no extinction.
    HomogeneousMedium m = chromatic_medium();
    m.sigma_a = Color(0.2f, 0.0f, 0.0f);
    m.sigma_s = Color(3.0f, 0.4f, 0.0f);  // optically thick, thin, and clear
    const float length = 2.0f;
    Rng rng(9, 2);
    const int n = 200000;
    DVec3 sum(0.0);
    for (int i = 0; i < n; ++i) {
        const SegmentDistance d = sample_distance_in_segment(m, length, rng.next_float(), rng.next_float());
        ASSERT_GE(d.t, 0.0f);
        ASSERT_LT(d.t, length);
        ASSERT_GT(d.pdf, 0.0f);
        sum += DVec3(m.transmittance(d.t)) / static_cast<double>(d.pdf);
    }
    sum /= n;
    for (int c = 0; c < 3; ++c) {
        const double st = m.sigma_t()[c];
        const double expected = st > 0.0 ? (1.0 - std::exp(-st * length)) / st : length;
        EXPECT_NEAR(sum[c], expected, 0.003 * expected) << "channel " << c;
    }
}

TEST(HenyeyGreenstein, IsNormalisedWithMeanCosineG) {
    Rng rng(3, 4);
    const Vec3 wo = glm::normalize(Vec3(0.3f, -0.5f, 0.8f));
    for (const float g : {-0.7f, 0.0f, 0.4f, 0.9f}) {
        // Normalisation by uniform directions: E[4 pi p] = 1.
        double integral = 0.0;
        const int n = 400000;
        for (int i = 0; i < n; ++i)
            integral += 4.0 * kPi * henyey_greenstein(g, wo, sample_uniform_sphere(rng.next_vec2()));
        EXPECT_NEAR(integral / n, 1.0, g > 0.8f ? 0.05 : 0.01) << "g " << g;
        // Sampled directions: mean cosine of the scattering angle (dot(-wi, wo)) is g.
        double mean_cos = 0.0;
        for (int i = 0; i < n; ++i) mean_cos += -glm::dot(sample_henyey_greenstein(g, wo, rng.next_vec2()), wo);
        EXPECT_NEAR(mean_cos / n, g, 0.005) << "g " << g;
    }
}

TEST(HenyeyGreenstein, SamplesFollowItsDistribution) {
    // Chi-square over 20 bins of the scattering angle's cosine against the closed-form CDF
    // F(mu) = (1 - g^2) / (2 g) ((1 + g^2 - 2 g mu)^(-1/2) - 1 / (1 + g)), and over 8 bins of
    // the azimuth about wo (uniform).
    const Vec3 wo = glm::normalize(Vec3(-0.2f, 0.9f, 0.1f));
    const Frame frame(wo);
    for (const float g : {-0.5f, 0.2f, 0.8f}) {
        const auto cdf = [g](double mu) {
            return (1.0 - g * g) / (2.0 * g) * (1.0 / std::sqrt(1.0 + g * g - 2.0 * g * mu) - 1.0 / (1.0 + g));
        };
        constexpr int kBins = 20, kAzimuthBins = 8;
        const int n = 200000;
        std::vector<int> counts(kBins, 0), azimuth(kAzimuthBins, 0);
        Rng rng(11, static_cast<uint64_t>(g * 100 + 100));
        for (int i = 0; i < n; ++i) {
            const Vec3 travel = -sample_henyey_greenstein(g, wo, rng.next_vec2());
            const float mu = glm::dot(travel, wo);
            ++counts[std::min(kBins - 1, static_cast<int>((mu + 1.0f) * 0.5f * kBins))];
            const Vec3 local = frame.to_local(travel);
            const float phi = std::atan2(local.y, local.x) + kPi;
            ++azimuth[std::min(kAzimuthBins - 1, static_cast<int>(phi / (2.0f * kPi) * kAzimuthBins))];
        }
        double chi2 = 0.0;
        for (int b = 0; b < kBins; ++b) {
            const double expected = n * (cdf(-1.0 + 2.0 * (b + 1) / kBins) - cdf(-1.0 + 2.0 * b / kBins));
            chi2 += (counts[b] - expected) * (counts[b] - expected) / expected;
        }
        // 19 degrees of freedom: 43.8 is the 0.999 quantile.
        EXPECT_LT(chi2, 43.8) << "g " << g;
        double chi2_azimuth = 0.0;
        for (const int count : azimuth) {
            const double expected = static_cast<double>(n) / kAzimuthBins;
            chi2_azimuth += (count - expected) * (count - expected) / expected;
        }
        EXPECT_LT(chi2_azimuth, 24.3) << "g " << g;  // 7 degrees of freedom, 0.999
    }
}

TEST(Atmosphere, SpanInBoundsIsTheSlabIntersection) {
    Bounds3 box;
    box.extend(Vec3(-1.0f, 0.0f, -2.0f));
    box.extend(Vec3(1.0f, 2.0f, 2.0f));
    // From outside, through the box along +x.
    MediumSpan s = span_in_bounds(box, Ray{Vec3(-3.0f, 1.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f)}, 100.0f);
    EXPECT_FLOAT_EQ(s.t0, 2.0f);
    EXPECT_FLOAT_EQ(s.t1, 4.0f);
    // Cut by t_end inside the box; starting inside.
    s = span_in_bounds(box, Ray{Vec3(-3.0f, 1.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f)}, 2.5f);
    EXPECT_FLOAT_EQ(s.t1, 2.5f);
    s = span_in_bounds(box, Ray{Vec3(0.0f, 1.0f, 0.0f), Vec3(0.0f, 0.0f, 1.0f)}, std::numeric_limits<float>::infinity());
    EXPECT_FLOAT_EQ(s.t0, 0.0f);
    EXPECT_FLOAT_EQ(s.t1, 2.0f);
    // Parallel to a face outside it, pointing away, and a non-unit direction (shadow rays).
    EXPECT_TRUE(span_in_bounds(box, Ray{Vec3(0.0f, 3.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f)}, 10.0f).empty());
    EXPECT_TRUE(span_in_bounds(box, Ray{Vec3(-3.0f, 1.0f, 0.0f), Vec3(-1.0f, 0.0f, 0.0f)}, 10.0f).empty());
    s = span_in_bounds(box, Ray{Vec3(-3.0f, 1.0f, 0.0f), Vec3(8.0f, 0.0f, 0.0f), 0.0f, 1.0f}, 1.0f);
    EXPECT_FLOAT_EQ(s.t0, 0.25f);
    EXPECT_FLOAT_EQ(s.t1, 0.5f);
    EXPECT_TRUE(span_in_bounds(Bounds3{}, Ray{}, 1.0f).empty());
}

}  // namespace
}  // namespace photond
