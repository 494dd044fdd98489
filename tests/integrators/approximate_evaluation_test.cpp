// Visible points of small importance read the photon maps at once (kApproximateImportance,
// core/integrators/integrator.h): a glass sphere shows the wall behind the camera in its Fresnel
// reflection (0.04 of the light head-on), and those points neither get irradiance records nor
// trace light samples and glossy rays. The image must stay what the accurate evaluation makes of
// it, within the noise of the accurate evaluation itself (another seed); and the approximate
// evaluation made at every visible point must agree with the accurate one in 8 x 8 blocks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/integrators/photon_mapping.h"
#include "core/render/tile_renderer.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

constexpr int kSize = 96;

/// A room open at its sides under a square ceiling light: a glass sphere on a white floor in
/// front of a white back wall, seen from between it and a green front wall that the camera sees
/// only in the sphere.
Scene glass_sphere_room() {
    SceneBuilder builder("a glass sphere reflecting the wall behind the camera");
    const uint32_t white = builder.add_material(test_support::lambertian(Color(0.75f)));
    const uint32_t green = builder.add_material(test_support::lambertian(Color(0.2f, 0.75f, 0.2f)));
    Material light = test_support::lambertian(Color(0.0f));
    light.emission = Color(20.0f);
    const uint32_t lamp = builder.add_material(light);
    Material glass;
    glass.base_color = Color(1.0f);
    glass.metallic = 0.0f;
    glass.roughness = 0.0f;
    glass.transmission = 1.0f;
    glass.ior = 1.5f;
    const uint32_t crystal = builder.add_material(glass);
    const auto add = [&](const MeshData& mesh, uint32_t material) {
        EXPECT_TRUE(builder.add_mesh(mesh.positions, mesh.normals, mesh.uvs, mesh.triangles, material).is_ok());
    };
    add(make_quad(Vec3(-3, 0, -3), Vec3(6, 0, 0), Vec3(0, 0, 16), Vec3(0, 1, 0)), white);       // floor
    add(make_quad(Vec3(-3, 0, -3), Vec3(6, 0, 0), Vec3(0, 6, 0), Vec3(0, 0, 1)), white);        // back wall
    add(make_quad(Vec3(-3, 0, 13), Vec3(6, 0, 0), Vec3(0, 6, 0), Vec3(0, 0, -1)), green);       // front wall
    add(make_quad(Vec3(-1, 5.9f, 4), Vec3(2, 0, 0), Vec3(0, 0, 2), Vec3(0, -1, 0)), lamp);      // light
    add(make_icosphere(Vec3(0, 1, 0), 1.0f, 5), crystal);
    CameraDesc camera;
    camera.position = Vec3(0.0f, 2.0f, 10.0f);
    camera.look_at = Vec3(0.0f, 1.0f, 0.0f);
    camera.up = Vec3(0.0f, 1.0f, 0.0f);
    camera.vfov_deg = 20.0f;
    builder.add_camera(camera);
    return builder.build().value();
}

struct Rendered {
    TileRenderResult result;
    CacheBuildStatistics cache;
};

Rendered render(const std::shared_ptr<const RenderScene>& rs, const std::shared_ptr<const PhotonMaps>& maps,
                const Camera& camera, float approximate_importance, uint64_t seed) {
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = 64;
    settings.approximate_importance = approximate_importance;
    settings.irradiance_cache.seed = seed;
    PhotonMapIntegrator integrator(rs, maps, settings);
    Rendered rendered;
    integrator.build_cache(camera, &rendered.cache);
    TileSettings tiles;
    tiles.samples_per_pixel = 8;
    tiles.seed = seed;
    rendered.result = render_tiles(integrator, camera, tiles);
    return rendered;
}

/// Mean squared difference of a's and b's luminance over the pixels where `changed` differs from
/// `base`, relative to base's squared luminance there (+0.01), and the count of those pixels.
double relative_mse(const Image& a, const Image& b, const Image& base, const Image& changed, int* pixels) {
    double sum = 0.0;
    *pixels = 0;
    for (size_t p = 0; p < a.pixel_count(); ++p) {
        if (changed.pixels()[p] == base.pixels()[p]) continue;
        const double va = luminance(a.pixels()[p]), vb = luminance(b.pixels()[p]), vr = luminance(base.pixels()[p]);
        sum += (va - vb) * (va - vb) / (vr * vr + 0.01);
        ++*pixels;
    }
    return *pixels > 0 ? sum / *pixels : 0.0;
}

TEST(ApproximateEvaluation, AGlassSpheresReflectionReadsThePhotonMapsWithinTheAccurateEvaluationsNoise) {
    const auto rs = test_support::make_render_scene(glass_sphere_room());
    PhotonTracingSettings photons;
    photons.global_photons = 100000;
    photons.caustic_photons = 20000;
    const auto maps = std::make_shared<const PhotonMaps>(trace_photons(*rs, photons).value());
    const Camera camera = Camera::create(rs->scene->cameras.at(0), kSize, kSize).value();

    const Rendered approximate = render(rs, maps, camera, kApproximateImportance, 1);
    const Rendered accurate = render(rs, maps, camera, 0.0f, 1);
    const Rendered accurate_other_seed = render(rs, maps, camera, 0.0f, 2);

    // The prepass does not look for records at the weak points, and the render pass traces no
    // light sample there.
    EXPECT_LT(approximate.cache.candidates, accurate.cache.candidates);
    EXPECT_LT(approximate.result.counters.shadow_rays, accurate.result.counters.shadow_rays);

    // Where the approximation changed the image, it differs from the accurate one by less than
    // the accurate one differs from itself at another seed.
    const Image& a = approximate.result.layers.beauty;
    const Image& b = accurate.result.layers.beauty;
    const Image& c = accurate_other_seed.result.layers.beauty;
    int changed = 0, compared = 0;
    const double change = relative_mse(a, b, b, a, &changed);
    const double noise = relative_mse(c, b, b, a, &compared);
    double sum_a = 0.0, sum_b = 0.0, sum_c = 0.0;
    for (size_t p = 0; p < a.pixel_count(); ++p) {
        sum_a += luminance(a.pixels()[p]);
        sum_b += luminance(b.pixels()[p]);
        sum_c += luminance(c.pixels()[p]);
    }
    std::printf("points examined for records %llu (accurate %llu), records %llu (%llu); shadow rays %llu (%llu); "
                "%d pixels changed, relMSE %.6f there (another seed: %.6f); image mean %+.3f %% (another seed: "
                "%+.3f %%)\n",
                static_cast<unsigned long long>(approximate.cache.candidates),
                static_cast<unsigned long long>(accurate.cache.candidates),
                static_cast<unsigned long long>(approximate.cache.records),
                static_cast<unsigned long long>(accurate.cache.records),
                static_cast<unsigned long long>(approximate.result.counters.shadow_rays),
                static_cast<unsigned long long>(accurate.result.counters.shadow_rays), changed, change, noise,
                100.0 * (sum_a / sum_b - 1.0), 100.0 * (sum_c / sum_b - 1.0));
    ASSERT_GT(changed, 0);
    EXPECT_LT(change, noise);
    EXPECT_LT(std::abs(sum_a / sum_b - 1.0), std::abs(sum_c / sum_b - 1.0));

    // The approximate evaluation itself, at every visible point (an importance above 1): the
    // room as its photon maps' irradiance sites see it, within a few percent of the accurate
    // evaluation in 8 x 8 pixel blocks.
    const Rendered everywhere = render(rs, maps, camera, 2.0f, 1);
    EXPECT_EQ(everywhere.cache.records, 0u);
    const Image& e = everywhere.result.layers.beauty;
    double sum_e = 0.0, block_error = 0.0;
    int blocks = 0;
    for (int by = 0; by < kSize; by += 8) {
        for (int bx = 0; bx < kSize; bx += 8) {
            double be = 0.0, bb = 0.0;
            for (int y = by; y < by + 8; ++y)
                for (int x = bx; x < bx + 8; ++x) {
                    be += luminance(e.at(x, y));
                    bb += luminance(b.at(x, y));
                }
            block_error += (be - bb) * (be - bb) / (bb * bb + 1e-6);
            ++blocks;
            sum_e += be;
        }
    }
    std::printf("everywhere approximate: image mean %+.3f %%, 8 x 8 blocks' relMSE %.6f\n",
                100.0 * (sum_e / sum_b - 1.0), block_error / blocks);
    EXPECT_LT(std::abs(sum_e / sum_b - 1.0), 0.03);
    EXPECT_LT(block_error / blocks, 0.02);
}

}  // namespace
}  // namespace photond
