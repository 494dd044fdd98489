// KHR_materials_clearcoat: a GGX dielectric layer (F0 0.04) over the base. A smooth coat
// reflects its Fresnel share c (0.04 + 0.96 (1 - mu)^5) as a mirror and dims the base by what
// passes it both ways; a rough coat's sampling, pdf and evaluation agree.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/material/bsdf.h"
#include "core/math/rng.h"
#include "core/math/sampling.h"

namespace photond {
namespace {

Material base(Color colour, float coat, float coat_roughness) {
    Material m;
    m.base_color = colour;
    m.metallic = 0.0f;
    m.roughness = 1.0f;
    m.specular = 0.0f;  // no dielectric layer: the coat is the only specular part
    m.clearcoat = coat;
    m.clearcoat_roughness = coat_roughness;
    return m;
}

float coat_fresnel(float coat, float mu) {
    return coat * (0.04f + 0.96f * std::pow(1.0f - mu, 5.0f));
}

Vec3 direction(float mu) { return Vec3(std::sqrt(1.0f - mu * mu), 0.0f, mu); }

TEST(Clearcoat, SmoothCoatAddsItsFresnelMirrorAndDimsTheBase) {
    const Frame frame(Vec3(0, 0, 1));
    const Vec3 n(0, 0, 1);
    for (float coat : {0.0f, 0.5f, 1.0f}) {
        const BsdfMaterial constants(base(Color(0.8f), coat, 0.0f));
        const Bsdf bsdf(constants, Color(0.8f), frame, n);
        for (float mu : {1.0f, 0.5f, 0.2f}) {
            SCOPED_TRACE(testing::Message() << "coat " << coat << " mu " << mu);
            const Vec3 wo = direction(mu);
            std::array<BsdfSample, 2> lobes;
            const int count = bsdf.delta_lobes(wo, lobes);
            if (coat == 0.0f) {
                EXPECT_EQ(count, 0);
            } else {
                ASSERT_EQ(count, 1);
                EXPECT_NEAR(lobes[0].weight.x, coat_fresnel(coat, mu), 1e-6f);
                EXPECT_NEAR(lobes[0].wi.z, mu, 1e-6f);
            }
            // The Lambertian base, seen through the coat both ways.
            const Vec3 wi = glm::normalize(Vec3(-0.3f, 0.2f, 0.6f));
            const float expected =
                0.8f * kInvPi * (1.0f - coat_fresnel(coat, mu)) * (1.0f - coat_fresnel(coat, wi.z));
            EXPECT_NEAR(bsdf.eval(wo, wi).x, expected, 1e-5f);
        }
    }
}

TEST(Clearcoat, RoughCoatSamplingAgreesWithEvaluation) {
    // int f cos dwi by quadrature of eval() against the mean of sample() weights, and the pdf
    // integrating to 1: a black base leaves the coat alone, a white one the coat plus the base.
    const Frame frame(Vec3(0, 0, 1));
    const Vec3 n(0, 0, 1);
    for (float colour : {0.0f, 1.0f}) {
        const BsdfMaterial constants(base(Color(colour), 1.0f, 0.3f));
        const Bsdf bsdf(constants, Color(colour), frame, n);
        EXPECT_TRUE(bsdf.lobes() & mask_of(LobeKind::Glossy));
        for (float mu : {0.9f, 0.4f}) {
            SCOPED_TRACE(testing::Message() << "base " << colour << " mu " << mu);
            const Vec3 wo = direction(mu);
            Rng rng(11, 3);
            const int n_samples = 400000;
            double sampled = 0.0, quadrature = 0.0, pdf_integral = 0.0;
            for (int i = 0; i < n_samples; ++i) {
                const auto s = bsdf.sample(wo, rng.next_float(), rng.next_vec2());
                if (s) sampled += s->weight.x;
                // Uniform hemisphere directions for the quadrature.
                const Vec3 wi = sample_uniform_cone(rng.next_vec2(), 0.0f);
                quadrature += bsdf.eval(wo, wi).x * wi.z * (2.0 * kPi);
                pdf_integral += bsdf.pdf(wo, wi) * (2.0 * kPi);
            }
            sampled /= n_samples;
            quadrature /= n_samples;
            pdf_integral /= n_samples;
            std::printf(
                "clearcoat 1, roughness 0.3, base %.0f, mu %.1f: albedo %.4f sampled, %.4f by "
                "quadrature, pdf integral %.4f\n",
                colour, mu, sampled, quadrature, pdf_integral);
            EXPECT_NEAR(sampled, quadrature, 0.02 * quadrature + 1e-3);
            EXPECT_NEAR(pdf_integral, 1.0, 0.03);
            // The coat alone reflects about its Fresnel share; nothing reflects more than all.
            if (colour == 0.0f) {
                EXPECT_NEAR(quadrature, coat_fresnel(1.0f, mu), 0.35 * coat_fresnel(1.0f, mu));
            }
            EXPECT_LT(quadrature, 1.01);
        }
    }
}

}  // namespace
}  // namespace photond
