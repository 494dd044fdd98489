// Environment light through the photon-map integrator's split (the diffuse sky to final
// gathering, also through specular surfaces; its peaks and other lights to light sampling and
// the caustic map) against the path tracer: "sunlit-room", a textured room lit only by a sky
// image and its sun through a window, and a glass sphere on a floor under a uniform sky (no
// caustic map needed) and under a sky with a sun (a caustic map of the sun alone).
#include <gtest/gtest.h>

#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"
#include "core/render/render_plan.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"

#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::make_render_scene;

/// The mean of each of the image's left and right halves, and of the whole.
std::array<double, 3> half_means(const Image& image) {
    double left = 0.0, right = 0.0;
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            EXPECT_TRUE(is_finite(image.at(x, y)));
            (x < image.width() / 2 ? left : right) += luminance(image.at(x, y));
        }
    }
    const double half = 0.5 * image.width() * image.height();
    return {left / half, right / half, 0.5 * (left + right) / half};
}

/// The photon-map integrator as the pipeline sets it up: planned passes, final photon counts.
Image render_photon_map(const std::shared_ptr<const RenderScene>& rs, const Camera& camera, RenderPlan* plan) {
    *plan = plan_photon_passes(*rs->scene, *rs->lights, {200000, 50000}, rs->lights_with_sky_peaks.get());
    PhotonTracingSettings tracing;
    tracing.global_photons = plan->global_map ? 200000 : 0;
    tracing.caustic_photons = plan->caustic_map ? 50000 : 0;
    auto maps = trace_photons(*rs, tracing);
    EXPECT_TRUE(maps) << maps.error().message;
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = 256;
    settings.cache.cache.accuracy = 0.3f;
    PhotonMapIntegrator photon_map(rs, std::make_shared<const PhotonMaps>(std::move(maps).value()), settings);
    photon_map.prepare(camera, nullptr);
    TileSettings tiles;
    tiles.samples_per_pixel = 16;
    return render_tiles(photon_map, camera, tiles).image;
}

/// The image means of a converged path render (1024 spp).
std::array<double, 3> path_means(const std::shared_ptr<const RenderScene>& rs, const Camera& camera) {
    TileSettings tiles;
    tiles.samples_per_pixel = 1024;
    return half_means(render_tiles(PathIntegrator(rs), camera, tiles).image);
}

TEST(EnvironmentInterior, PhotonMapAgreesWithPathInTheSunlitRoom) {
    auto rs = make_render_scene(make_builtin_scene("sunlit-room").value());
    ASSERT_TRUE(rs->lights_with_sky_peaks) << "the room's sky must split into its sun and the rest";
    ASSERT_TRUE(rs->sky_peaks && rs->diffuse_sky);
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 48, 48).value();

    const std::array<double, 3> reference = path_means(rs, camera);
    RenderPlan plan;
    const std::array<double, 3> estimate = half_means(render_photon_map(rs, camera, &plan));
    EXPECT_FALSE(plan.caustic_map);  // nothing in the room is specular

    std::printf("sunlit-room 48x48: path means %.4f %.4f %.4f, photon-map %.4f %.4f %.4f\n", reference[0],
                reference[1], reference[2], estimate[0], estimate[1], estimate[2]);
    EXPECT_NEAR(estimate[2] / reference[2], 1.0, 0.02);      // the whole image
    for (int h = 0; h < 2; ++h) EXPECT_NEAR(estimate[h] / reference[h], 1.0, 0.04) << "half " << h;
}

TEST(EnvironmentTransport, GlassOnAFloorUnderUniformAndSunnySkiesAgreesWithPath) {
    for (const bool sunny : {false, true}) {
        Scene scene = make_builtin_scene("caustic").value();
        scene.lights.clear();  // the sky alone
        Environment sky;
        if (sunny) {
            // A small, bright sun above and behind the sphere, so that its caustic lies in view.
            sky.name = "sunny";
            sky.width = 64;
            sky.height = 32;
            sky.texels.assign(64 * 32, Color(0.3f, 0.4f, 0.6f));
            sky.texels[6 * 64 + 16] = Color(2000.0f, 1900.0f, 1700.0f);
        }
        scene.environment = sky;
        auto rs = make_render_scene(std::move(scene));
        const Camera camera = Camera::create(rs->scene->cameras.at(0), 48, 36).value();
        RenderPlan plan;
        const Image image = render_photon_map(rs, camera, &plan);
        const PassDecision* caustic = plan.find("caustic_map");
        ASSERT_TRUE(caustic);
        EXPECT_EQ(caustic->enabled, sunny) << caustic->reason;

        const std::array<double, 3> reference = path_means(rs, camera);
        const std::array<double, 3> estimate = half_means(image);
        std::printf("glass under a %s sky 48x36: path %.4f, photon-map %.4f\n", sunny ? "sunny" : "uniform",
                    reference[2], estimate[2]);
        EXPECT_NEAR(estimate[2] / reference[2], 1.0, 0.02) << (sunny ? "sunny" : "uniform");
    }
}

}  // namespace
}  // namespace photond
