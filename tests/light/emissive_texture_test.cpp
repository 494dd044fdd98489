// Emissive textures in emitted radiance, light sampling and photon emission: a textured quad's
// power and its photons' flux equal the texture's integral, and next-event estimation agrees
// with BSDF-sampled rays that read the emitted radiance where they land.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/light/light_set.h"
#include "core/math/rng.h"
#include "core/math/sampling.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

/// A 2 x 1 emitter in the plane z = 1 facing down (-z), emissive factor 3 times a 4 x 4 texture
/// with texels (x + 4 y) / 15 * (1, 0.5, 0.25), repeat wrapping, bilinear.
Scene textured_emitter_scene(bool masked = false) {
    SceneBuilder builder("emissive-texture");
    Texture t;
    t.width = 4;
    t.height = 4;
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
            t.texels.push_back(float(x + 4 * y) / 15.0f * Color(1.0f, 0.5f, 0.25f));
    Material m = test_support::lambertian(Color(0.0f));
    m.emission = Color(3.0f);
    m.emissive_texture.texture = static_cast<int>(builder.add_texture(std::move(t)));
    if (masked) {
        // MASK: the quad's left half (u < 0.5) is absent, for every kind of ray.
        Texture coverage;
        coverage.width = 2;
        coverage.height = 1;
        coverage.texels = {Color(1.0f), Color(1.0f)};
        coverage.alpha = {0.0f, 1.0f};
        coverage.nearest = true;
        coverage.wrap_s = coverage.wrap_t = TextureWrap::ClampToEdge;
        m.base_color_texture.texture = static_cast<int>(builder.add_texture(std::move(coverage)));
        m.alpha_mode = AlphaMode::Mask;
    }
    const uint32_t emitter = builder.add_material(m);
    const MeshData quad = make_quad(Vec3(0, 0, 1), Vec3(2, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, -1));
    EXPECT_TRUE(
        builder.add_mesh(quad.positions, quad.normals, quad.uvs, quad.triangles, emitter).is_ok());
    return builder.build().value();
}

// Bilinear interpolation with repeat wrapping keeps the texels' mean over a whole period, so
// the exact integral is pi * area * factor * mean = pi * 2 * 3 * 0.5 * (1, 0.5, 0.25).
const Color kExactPower = kPi * 2.0f * 3.0f * 0.5f * Color(1.0f, 0.5f, 0.25f);

TEST(EmissiveTexture, PowerIsTheTexturesIntegral) {
    const Scene scene = textured_emitter_scene();
    const LightSet lights(scene);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(lights.total_power()[c], kExactPower[c], 0.01f * kExactPower[c]);
    std::printf("emissive texture: power %.4f, exact %.4f (red)\n", lights.total_power().x,
                kExactPower.x);
}

TEST(EmissiveTexture, PhotonFluxIsTheTexturesIntegral) {
    const Scene scene = textured_emitter_scene();
    const LightSet lights(scene);
    Rng rng(3, 4);
    const int n = 400000;
    DVec3 flux(0.0);
    DVec3 left(0.0);  // flux from photons leaving the quad's dark half (texel rows 0, 1: v < 0.5)
    for (int i = 0; i < n; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2());
        ASSERT_TRUE(e.has_value());
        flux += DVec3(e->flux_weight);
        if (e->origin.y < 0.5f) left += DVec3(e->flux_weight);
    }
    flux /= double(n);
    left /= double(n);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(flux[c], kExactPower[c], 0.01 * kExactPower[c]);
    std::printf("emissive texture: mean photon flux %.4f, exact %.4f (red)\n", flux.x,
                kExactPower.x);
    // The texture decides where the flux leaves: rows 0-1 hold 28 of the 120 parts of the sum,
    // with bilinear blending across the v = 0.5 line and the repeat seam at v = 0 (exact: the
    // mean of the blended field over v in [0, 0.5]).
    EXPECT_LT(left.x, 0.45 * flux.x);
}

TEST(EmissiveTexture, LightSamplingAgreesWithBsdfSampling) {
    for (bool masked : {false, true}) {
        SCOPED_TRACE(masked ? "masked" : "opaque");
        auto rs = test_support::make_render_scene(textured_emitter_scene(masked));
        const LightSet& lights = *rs->lights;
        const Vec3 p(0.6f, 0.3f, 0.2f), n(0, 0, 1);
        Rng rng(5, 6);
        const int samples = 400000;
        DVec3 by_light(0.0), by_bsdf(0.0);
        const Frame frame(n);
        for (int i = 0; i < samples; ++i) {
            const auto ls = lights.sample_incident(p, rng.next_float(), rng.next_vec2());
            if (ls && ls->pdf > 0.0f)
                by_light += DVec3(ls->radiance * (glm::dot(ls->wi, n) / ls->pdf));
            // Cosine-weighted directions: E = pi * mean L.
            const Vec3 d = frame.to_world(sample_cosine_hemisphere(rng.next_vec2()));
            const Ray ray{p, d};
            const std::optional<Hit> hit = rs->tracer->intersect(ray);
            if (!hit) continue;
            const SurfaceInteraction si = make_interaction(*rs->scene, *hit, d);
            by_bsdf += DVec3(lights.emitted_radiance(si, -d) * kPi);
        }
        by_light /= double(samples);
        by_bsdf /= double(samples);
        ASSERT_GT(by_bsdf.x, 0.1);
        std::printf(
            "emissive texture (%s): irradiance by light sampling %.4f, by BSDF sampling %.4f\n",
            masked ? "masked" : "opaque", by_light.x, by_bsdf.x);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(by_light[c], by_bsdf[c], 0.02 * by_bsdf[c]) << c;
    }
}

}  // namespace
}  // namespace photond
