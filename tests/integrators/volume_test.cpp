// KHR_materials_volume: Beer-Lambert attenuation inside a transmissive solid against the closed
// form exp(-sigma d), for camera paths (direct, path, photon-map) and for photons.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/integrators/direct.h"
#include "core/integrators/path.h"
#include "core/math/rng.h"
#include "core/photon/photon_map.h"
#include "core/photon/photon_tracer.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

const Color kSigma(0.5f, 1.0f, 2.0f);
constexpr float kThickness = 0.6f;

/// A slab [-1, 1]^2 x [0, d] of clear index-1 glass (no refraction, no reflection) with
/// attenuation sigma, between an emitter of radiance 1 at z = -1 facing +z and a camera above;
/// for photons, an emitter at z = 2 facing down and a floor at z = -1.
Scene slab_scene(bool attenuating, bool photons) {
    SceneBuilder builder("volume");
    Material glass = test_support::smooth_glass(1.0f);
    if (attenuating) glass.attenuation = kSigma;
    const uint32_t slab = builder.add_material(glass);
    Material light = test_support::lambertian(Color(0.0f));
    light.emission = Color(1.0f);
    const uint32_t emitter = builder.add_material(light);
    const uint32_t floor = builder.add_material(test_support::lambertian(Color(0.5f)));
    const MeshData box = make_box(Vec3(-1, -1, 0), Vec3(1, 1, kThickness));
    EXPECT_TRUE(builder.add_mesh(box.positions, box.normals, box.uvs, box.triangles, slab).is_ok());
    if (!photons) {
        const MeshData e = make_quad(Vec3(-3, -3, -1), Vec3(6, 0, 0), Vec3(0, 6, 0), Vec3(0, 0, 1));
        EXPECT_TRUE(builder.add_mesh(e.positions, e.normals, e.uvs, e.triangles, emitter).is_ok());
    } else {
        const MeshData e =
            make_quad(Vec3(-0.2f, -0.2f, 2), Vec3(0.4f, 0, 0), Vec3(0, 0.4f, 0), Vec3(0, 0, -1));
        EXPECT_TRUE(builder.add_mesh(e.positions, e.normals, e.uvs, e.triangles, emitter).is_ok());
        const MeshData f = make_quad(Vec3(-3, -3, -1), Vec3(6, 0, 0), Vec3(0, 6, 0), Vec3(0, 0, 1));
        EXPECT_TRUE(builder.add_mesh(f.positions, f.normals, f.uvs, f.triangles, floor).is_ok());
    }
    return builder.build().value();
}

TEST(Volume, CameraPathsFollowBeerLambert) {
    auto rs = test_support::make_render_scene(slab_scene(true, false));
    const Color expected = glm::exp(-kSigma * kThickness);
    CameraRay ray;
    ray.origin = Vec3(0.1f, 0.2f, 3.0f);
    ray.direction = Vec3(0, 0, -1);
    Rng rng(1, 1);
    RayCounters counters;
    SampleContext context{rng, counters};
    const Color direct = DirectIntegrator(rs).radiance(ray, context);
    PathIntegrator path(rs, 16, 8);
    Color sum(0.0f);
    for (int i = 0; i < 64; ++i) sum += path.radiance(ray, context);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(direct[c], expected[c], 1e-4f) << c;
        EXPECT_NEAR(sum[c] / 64.0f, expected[c], 1e-4f) << c;
    }
    // A clear slab passes everything.
    auto clear = test_support::make_render_scene(slab_scene(false, false));
    EXPECT_NEAR(DirectIntegrator(clear).radiance(ray, context).x, 1.0f, 1e-4f);
}

TEST(Volume, PhotonsFollowBeerLambert) {
    PhotonTracingSettings settings;
    settings.global_photons = 30000;
    settings.caustic_photons = 0;
    settings.irradiance_stride = 0;
    const auto estimate = [&](bool attenuating) {
        auto rs = test_support::make_render_scene(slab_scene(attenuating, true));
        const PhotonMaps maps = trace_photons(*rs, settings).value();
        return maps.global->estimate_irradiance(Vec3(0, 0, -1), Vec3(0, 0, 1), 500, 0.5f);
    };
    const Color clear = estimate(false), tinted = estimate(true);
    const Color expected = glm::exp(-kSigma * kThickness);
    // Photons that reach the floor through the slab crossed it straight down or at a slant
    // (d / cos): the ratio lies between exp(-sigma d / cos_max) and exp(-sigma d).
    std::printf("volume: photon irradiance ratio %.4f %.4f %.4f, exp(-sigma d) %.4f %.4f %.4f\n",
                tinted.x / clear.x, tinted.y / clear.y, tinted.z / clear.z, expected.x, expected.y,
                expected.z);
    for (int c = 0; c < 3; ++c) {
        const float ratio = tinted[c] / clear[c];
        EXPECT_LE(ratio, expected[c] * 1.01f) << c;
        EXPECT_GE(ratio, std::pow(expected[c], 1.3f) * 0.99f) << c;
    }
}

}  // namespace
}  // namespace photond
