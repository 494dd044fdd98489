// An emitter seen through rough glass: light sampling cannot reach it (the pane blocks its shadow
// rays), so the photon-map integrator's glossy rays must add the emission they hit, weighted by
// multiple importance sampling against light sampling; the image then agrees with `path`.
#include <gtest/gtest.h>

#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/render/tile_renderer.h"
#include "core/scene/shapes.h"

#include "tests/support/photon_fixtures.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;

double mean_luminance(const Image& image) {
    double sum = 0.0;
    for (const Color& c : image.pixels()) {
        EXPECT_TRUE(is_finite(c));
        sum += luminance(c);
    }
    return sum / static_cast<double>(image.pixel_count());
}

TEST(GlossyEmitter, EmitterBehindRoughGlassAgreesWithPath) {
    SceneBuilder builder("rough pane");
    const uint32_t floor = builder.add_material(lambertian(Color(0.7f)));
    Material pane;
    pane.base_color = Color(1.0f);
    pane.roughness = 0.3f;  // glossy transmission, not delta
    pane.transmission = 1.0f;
    const uint32_t glass = builder.add_material(pane);
    Material lamp = lambertian(Color(0.0f));
    lamp.emission = Color(8.0f, 6.0f, 4.0f);
    const uint32_t emitter = builder.add_material(lamp);
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-5, 0, -5), Vec3(10, 0, 0), Vec3(0, 0, 10), Vec3(0, 1, 0)), floor).is_ok());
    // A pane of rough glass (one interface: the photon-map integrator's glossy rays take one
    // rough bounce) between the camera and the lamp, the lamp facing the camera.
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-1.2f, 0.2f, 0.0f), Vec3(2.4f, 0, 0), Vec3(0, 2.0f, 0), Vec3(0, 0, 1)),
                         glass).is_ok());
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-0.5f, 0.7f, -1.0f), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)),
                         emitter).is_ok());
    CameraDesc view;
    view.position = Vec3(0.0f, 1.2f, 3.0f);
    view.look_at = Vec3(0.0f, 1.2f, 0.0f);
    view.vfov_deg = 40.0f;
    builder.add_camera(view);
    auto rs = make_render_scene(builder.build().value());
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 32, 32).value();

    TileSettings path_tiles;
    path_tiles.samples_per_pixel = 1024;
    const double reference = mean_luminance(render_tiles(PathIntegrator(rs), camera, path_tiles).layers.beauty);

    const auto photon_map = test_support::uncached_photon_map(rs, 100000, 20000, 128);
    ASSERT_TRUE(photon_map);
    TileSettings tiles;
    tiles.samples_per_pixel = 64;
    const double estimate = mean_luminance(render_tiles(*photon_map, camera, tiles).layers.beauty);
    std::printf("emitter behind rough glass, 32x32: path %.4f, photon-map %.4f\n", reference, estimate);
    EXPECT_NEAR(estimate / reference, 1.0, 0.03);
}

}  // namespace
}  // namespace photond
