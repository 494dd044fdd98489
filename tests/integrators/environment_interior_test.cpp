// Where photon maps must earn their place: "sunlit-room", a textured room lit only by a sky image
// and its sun through a window. The photon-map integrator (final gathering of the diffuse sky,
// light-sampled sun, global map) agrees with the path tracer on the image's mean and on its
// lit and unlit halves.
#include <gtest/gtest.h>

#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"
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

TEST(EnvironmentInterior, PhotonMapAgreesWithPathInTheSunlitRoom) {
    auto rs = make_render_scene(make_builtin_scene("sunlit-room").value());
    ASSERT_TRUE(rs->lights_with_sky_peaks) << "the room's sky must split into its sun and the rest";
    ASSERT_TRUE(rs->sky_peaks && rs->diffuse_sky);
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 48, 48).value();

    TileSettings path_tiles;
    path_tiles.samples_per_pixel = 1024;
    const PathIntegrator path(rs);
    const std::array<double, 3> reference = half_means(render_tiles(path, camera, path_tiles).image);

    PhotonTracingSettings tracing;
    tracing.global_photons = 200000;
    tracing.caustic_photons = 0;
    auto maps = trace_photons(*rs, tracing);
    ASSERT_TRUE(maps) << maps.error().message;
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = 256;
    settings.cache.cache.accuracy = 0.3f;
    PhotonMapIntegrator photon_map(rs, std::make_shared<const PhotonMaps>(std::move(maps).value()), settings);
    photon_map.prepare(camera, nullptr);
    TileSettings tiles;
    tiles.samples_per_pixel = 16;
    const std::array<double, 3> estimate = half_means(render_tiles(photon_map, camera, tiles).image);

    std::printf("sunlit-room 48x48: path means %.4f %.4f %.4f, photon-map %.4f %.4f %.4f\n", reference[0],
                reference[1], reference[2], estimate[0], estimate[1], estimate[2]);
    EXPECT_NEAR(estimate[2] / reference[2], 1.0, 0.02);      // the whole image
    for (int h = 0; h < 2; ++h) EXPECT_NEAR(estimate[h] / reference[h], 1.0, 0.04) << "half " << h;
}

}  // namespace
}  // namespace photond
