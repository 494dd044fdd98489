// KHR_lights_punctual intensities are photometric (cd, lx) and emission is not: a scene written as
// Blender's glTF exporter writes it (tests/data/gltf/blender_lights.gltf: a 1000 W point lamp as
// 1000 / (4 pi) * 683 cd, a 3 W/m^2 sun as 3 * 683 lx, a quad of emission strength 2) renders its
// lamps and its emitter in the ratio Blender shows them.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "core/camera/camera.h"
#include "core/integrators/direct.h"
#include "core/render/tile_renderer.h"
#include "core/scene/gltf_loader.h"

namespace photond {
namespace {

/// The mean radiance a narrow camera sees from `from` towards `at`.
double mean_radiance(const std::shared_ptr<const RenderScene>& rs, Vec3 from, Vec3 at, Vec3 up) {
    CameraDesc desc;
    desc.position = from;
    desc.look_at = at;
    desc.up = up;
    desc.vfov_deg = 1.0f;
    const Camera camera = Camera::create(desc, 8, 8).value();
    const DirectIntegrator integrator(rs);
    TileSettings settings;
    settings.samples_per_pixel = 256;  // each sample picks one of the three lights at random
    const Image image = render_tiles(integrator, camera, settings).layers.beauty;
    double sum = 0.0;
    for (const Color& c : image.pixels()) sum += c.x;
    return sum / double(image.pixel_count());
}

TEST(GltfLightUnits, BlenderExportRendersLampsAgainstEmissionInBlendersRatio) {
    const auto path = std::filesystem::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "blender_lights.gltf";
    auto scene = load_gltf_file(path);
    ASSERT_TRUE(scene.has_value()) << scene.error().message;
    auto device = EmbreeDevice::create().value();
    auto rs = RenderScene::create(device, std::make_shared<const Scene>(std::move(scene).value()));
    ASSERT_TRUE(rs.has_value());

    // The floor 2 below the point lamp, looked at straight down: Lambert's rho / pi times the
    // irradiance of the lamp (P / (4 pi) / d^2) and of the sun (3 W/m^2). The emitter's plane
    // contains the point, so it adds nothing there.
    const double rho = 0.8, watts = 1000.0, d = 2.0, sun = 3.0;
    const double floor_expected = rho / kPi * (watts / (4.0 * kPi) / (d * d) + sun);
    const double floor = mean_radiance(*rs, {-1, 0.5, 0}, {-1, 0, 0}, {0, 0, -1});
    EXPECT_NEAR(floor / floor_expected, 1.0, 0.01) << floor << " vs " << floor_expected;
    // The emitter seen head-on: its strength, 2, unconverted.
    const double emitter = mean_radiance(*rs, {1.5, 1, 3}, {1.5, 1, 0}, {0, 1, 0});
    std::printf("  floor %.4f (expected %.4f), emitter %.4f, ratio %.4f\n", floor, floor_expected,
                emitter, floor / emitter);
    EXPECT_NEAR(emitter, 2.0, 0.02);
    // The ratio a user compares with Blender's render: 2.92 (683 times that if the lamps were
    // taken as W/sr and W/m^2).
    EXPECT_NEAR(floor / emitter, floor_expected / 2.0, 0.02 * floor_expected / 2.0);
}

}  // namespace
}  // namespace photond
