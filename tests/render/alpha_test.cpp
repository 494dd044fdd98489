// Alpha coverage through Embree's filter functions: a MASK panel shows what is behind it to
// camera rays, shadow rays and photons; a BLEND panel of alpha a stops a fraction a of rays.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/integrators/direct.h"
#include "core/math/rng.h"
#include "core/photon/photon_map.h"
#include "core/photon/photon_tracer.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;

/// A floor z = 0 over [0, 2] x [0, 1] and a panel z = 1 above it whose left half (x < 1) has
/// texture alpha 0 and right half alpha 1 (MASK, cutoff 0.5), or a uniform alpha (BLEND); a
/// directional light shining straight down.
Scene panel_scene(AlphaMode mode, float blend_alpha = 1.0f) {
    SceneBuilder builder("alpha");
    const uint32_t floor = builder.add_material(lambertian(Color(0.5f)));
    Material panel = lambertian(Color(0.5f));
    panel.alpha_mode = mode;
    if (mode == AlphaMode::Mask) {
        Texture t;
        t.width = 2;
        t.height = 1;
        t.texels = {Color(1.0f), Color(1.0f)};
        t.alpha = {0.0f, 1.0f};
        t.nearest = true;
        t.wrap_s = t.wrap_t = TextureWrap::ClampToEdge;
        panel.base_color_texture.texture = static_cast<int>(builder.add_texture(std::move(t)));
    } else {
        panel.base_alpha = blend_alpha;
    }
    const uint32_t panel_material = builder.add_material(panel);
    const MeshData f = make_quad(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 1, 0));
    const MeshData p = make_quad(Vec3(0, 0, 1), Vec3(2, 0, 0), Vec3(0, 1, 0));
    EXPECT_TRUE(builder.add_mesh(f.positions, f.normals, f.uvs, f.triangles, floor).is_ok());
    EXPECT_TRUE(
        builder.add_mesh(p.positions, p.normals, p.uvs, p.triangles, panel_material).is_ok());
    PunctualLight sun;
    sun.type = PunctualLightType::Directional;
    sun.direction = Vec3(0, 0, -1);
    sun.intensity = Color(2.0f);
    builder.add_light(sun);
    return builder.build().value();
}

TEST(AlphaMask, CameraRaysSeeThroughTheMaskedPart) {
    auto rs = make_render_scene(panel_scene(AlphaMode::Mask));
    const Ray left{Vec3(0.5f, 0.5f, 3.0f), Vec3(0, 0, -1)};
    const Ray right{Vec3(1.5f, 0.5f, 3.0f), Vec3(0, 0, -1)};
    const std::optional<Hit> a = rs->tracer->intersect(left), b = rs->tracer->intersect(right);
    ASSERT_TRUE(a && b);
    EXPECT_NEAR(a->t, 3.0f, 1e-4f);  // the floor, through the panel's transparent half
    EXPECT_NEAR(b->t, 2.0f, 1e-4f);  // the panel's opaque half
    EXPECT_EQ(rs->scene->triangle_materials[a->triangle], 0u);
    EXPECT_EQ(rs->scene->triangle_materials[b->triangle], 1u);
}

TEST(AlphaMask, ShadowRaysPassTheMaskedPart) {
    auto rs = make_render_scene(panel_scene(AlphaMode::Mask));
    Ray left{Vec3(0.5f, 0.5f, 0.001f), Vec3(0, 0, 1)};
    Ray right{Vec3(1.5f, 0.5f, 0.001f), Vec3(0, 0, 1)};
    EXPECT_FALSE(rs->tracer->occluded(left));
    EXPECT_TRUE(rs->tracer->occluded(right));
    // Direct light on the floor: lit (rho / pi * E) under the masked half, dark under the rest.
    DirectIntegrator direct(rs);
    Rng rng(1, 2);
    RayCounters counters;
    SampleContext context{rng, counters};
    CameraRay down;
    down.origin = Vec3(0.5f, 0.5f, 3.0f);
    down.direction = Vec3(0, 0, -1);
    EXPECT_NEAR(direct.radiance(down, context).x, 0.5f * kInvPi * 2.0f, 1e-3f);
    down.origin = Vec3(1.5f, 0.5f, 0.5f);  // below the panel, looking at the floor
    EXPECT_EQ(direct.radiance(down, context).x, 0.0f);
}

TEST(AlphaMask, PhotonsPassTheMaskedPart) {
    auto rs = make_render_scene(panel_scene(AlphaMode::Mask));
    PhotonTracingSettings settings;
    settings.global_photons = 20000;
    settings.caustic_photons = 0;
    settings.irradiance_stride = 0;
    const PhotonMaps maps = trace_photons(*rs, settings).value();
    ASSERT_TRUE(maps.global);
    // Floor irradiance from photons: E = 2 under the transparent half; under the opaque half
    // only light the panel's underside cannot send (it faces the floor but receives nothing).
    const Color lit =
        maps.global->estimate_irradiance(Vec3(0.5f, 0.5f, 0.0f), Vec3(0, 0, 1), 200, 0.3f);
    const Color shadowed =
        maps.global->estimate_irradiance(Vec3(1.5f, 0.5f, 0.0f), Vec3(0, 0, 1), 200, 0.3f);
    EXPECT_NEAR(lit.x, 2.0f, 0.2f);
    EXPECT_LT(shadowed.x, 0.3f * lit.x);
}

TEST(AlphaBlend, StopsAFractionAlphaOfRays) {
    const float alpha = 0.3f;
    auto rs = make_render_scene(panel_scene(AlphaMode::Blend, alpha));
    Rng rng(7, 1);
    const int n = 40000;
    int occluded = 0, hit_panel = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2 u = rng.next_vec2();
        const Ray shadow{Vec3(0.05f + 1.9f * u.x, 0.05f + 0.9f * u.y, 0.001f), Vec3(0, 0, 1)};
        if (rs->tracer->occluded(shadow)) ++occluded;
        const Ray camera{Vec3(0.05f + 1.9f * u.x, 0.05f + 0.9f * u.y, 3.0f), Vec3(0, 0, -1)};
        const std::optional<Hit> h = rs->tracer->intersect(camera);
        if (h && rs->scene->triangle_materials[h->triangle] == 1u) ++hit_panel;
    }
    // Binomial: sigma = sqrt(a (1 - a) / n) = 0.0023; 4 sigma.
    const double sigma = std::sqrt(alpha * (1.0 - alpha) / n);
    std::printf(
        "BLEND alpha %.2f: %.4f of shadow rays and %.4f of camera rays stopped (sigma %.4f)\n",
        alpha, double(occluded) / n, double(hit_panel) / n, sigma);
    EXPECT_NEAR(double(occluded) / n, alpha, 4.0 * sigma);
    EXPECT_NEAR(double(hit_panel) / n, alpha, 4.0 * sigma);
    // The same ray decides the same way every time (deterministic for any thread count).
    const Ray ray{Vec3(0.3f, 0.4f, 0.001f), Vec3(0, 0, 1)};
    const bool first = rs->tracer->occluded(ray);
    for (int i = 0; i < 10; ++i) EXPECT_EQ(rs->tracer->occluded(ray), first);
    // Photons: the floor under the panel receives (1 - a) E.
    PhotonTracingSettings settings;
    settings.global_photons = 40000;
    settings.caustic_photons = 0;
    settings.irradiance_stride = 0;
    const PhotonMaps maps = trace_photons(*rs, settings).value();
    const Color e =
        maps.global->estimate_irradiance(Vec3(1.0f, 0.5f, 0.0f), Vec3(0, 0, 1), 400, 0.4f);
    EXPECT_NEAR(e.x, (1.0f - alpha) * 2.0f, 0.1f);
}

}  // namespace
}  // namespace photond
