// Solids that scatter light inside (Material::interior_scatters, a job's material_media) under
// the photon-map integrator, whose volume map then holds their photons (photon_flags::kInterior):
// the furnace (a smooth glass sphere whose inside scatters and absorbs nothing, under a uniform
// sky of radiance 1, passes the sky on unchanged along every ray, which the estimate's cut at the
// solid's surface must keep near the surface), the light such a sphere sends back up from a sky
// that is white above and black below against path tracing, an absorbing and scattering solid on
// a floor under a sky against path tracing (image means), and the same image for any thread count.
#include <gtest/gtest.h>

#include <cmath>

#include "core/camera/camera.h"
#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"
#include "core/render/tile_renderer.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;
using test_support::mean_radiance;

CameraRay ray_from(const Vec3& origin, const Vec3& direction) {
    CameraRay ray;
    ray.origin = origin;
    ray.direction = glm::normalize(direction);
    return ray;
}

/// Smooth glass of index `ior` whose solid scatters (sigma_s per unit, g 0.5) and absorbs
/// sigma_a.
Material scattering_glass(float ior, const Color& sigma_s, const Color& sigma_a = Color(0.0f)) {
    Material glass = test_support::smooth_glass(ior);
    glass.name = "glass";
    glass.scattering = sigma_s;
    glass.attenuation = sigma_a;
    glass.phase_g = 0.5f;
    return glass;
}

/// A sphere of radius 0.5 at the origin of that glass (optical depths 1, 2.5 and 6 across), alone
/// under `sky`.
std::shared_ptr<const RenderScene> glass_sphere_under(float ior, const Environment& sky) {
    SceneBuilder builder("scattering-solid");
    EXPECT_TRUE(add_mesh(builder, make_icosphere(Vec3(0.0f), 0.5f, 4),
                         builder.add_material(scattering_glass(ior, Color(1.0f, 2.5f, 6.0f))))
                    .is_ok());
    Scene scene = builder.build().value();
    scene.environment = sky;
    return make_render_scene(std::move(scene));
}

/// The photon-map integrator with a volume map of `volume_photons` (and the global map of a
/// scene with diffuse surfaces), set up as the pipeline does.
std::unique_ptr<PhotonMapIntegrator> photon_map(const std::shared_ptr<const RenderScene>& rs, uint32_t global_photons,
                                                uint32_t volume_photons, int threads = 2) {
    PhotonTracingSettings tracing;
    tracing.global_photons = global_photons;
    tracing.caustic_photons = 0;
    tracing.volume_photons = volume_photons;
    tracing.threads = threads;
    auto maps = trace_photons(*rs, tracing);
    EXPECT_TRUE(maps) << maps.error().message;
    EXPECT_TRUE(maps->volume);
    EXPECT_EQ(maps->statistics.stored_volume, volume_photons);
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = 128;
    settings.use_irradiance_cache = false;
    return std::make_unique<PhotonMapIntegrator>(rs, std::make_shared<const PhotonMaps>(std::move(maps).value()),
                                                 settings);
}

Environment uniform_sky() { return Environment{}; }

/// White above the horizon, black below.
Environment half_sky() {
    Environment sky;
    sky.name = "half";
    sky.width = 4;
    sky.height = 2;
    sky.texels = {Color(1.0f), Color(1.0f), Color(1.0f), Color(1.0f), Color(0.0f), Color(0.0f), Color(0.0f), Color(0.0f)};
    return sky;
}

/// The mean radiance of rays along `direction` (an axis) through a grid of points over the
/// sphere's disc seen that way (radius 0.48 of its 0.5: every ray crosses the solid), `samples`
/// each. One ray's mean carries the noise of the few photon estimates along it (a few percent);
/// the disc's averages that out and keeps what is systematic.
Color disc_mean(const Integrator& integrator, const Vec3& direction, int samples) {
    const Vec3 u = std::abs(direction.y) > 0.5f ? Vec3(1.0f, 0.0f, 0.0f) : Vec3(0.0f, 1.0f, 0.0f);
    const Vec3 v = glm::cross(direction, u);
    constexpr int kGrid = 13;
    DVec3 sum(0.0);
    int rays = 0;
    for (int i = 0; i < kGrid; ++i) {
        for (int j = 0; j < kGrid; ++j) {
            const float a = 0.48f * (2.0f * (i + 0.5f) / kGrid - 1.0f), b = 0.48f * (2.0f * (j + 0.5f) / kGrid - 1.0f);
            if (a * a + b * b > 0.48f * 0.48f) continue;
            const Vec3 origin = a * u + b * v - 3.0f * direction;
            sum += DVec3(mean_radiance(integrator, ray_from(origin, direction), samples, uint64_t(rays + 1)));
            ++rays;
        }
    }
    return Color(sum / double(rays));
}

/// The mean radiance of rays along -z that graze the sphere's rim at 0.46 of its 0.5 radius, where
/// most of an estimate's sphere lies outside the solid: `rays` of them around the rim, `samples`
/// each. The rays' estimates draw on different photons, so their mean keeps what is systematic;
/// one ray's mean is as far off as its few photon neighbourhoods happen to be (up to 10.4 % at
/// k = 200 for some photon seeds).
Color rim_mean(const Integrator& integrator, int rays, int samples) {
    DVec3 sum(0.0);
    for (int i = 0; i < rays; ++i) {
        const float angle = 2.0f * kPi * (float(i) + 0.5f) / float(rays);
        const Vec3 origin(0.46f * std::cos(angle), 0.46f * std::sin(angle), 3.0f);
        sum += DVec3(mean_radiance(integrator, ray_from(origin, Vec3(0.0f, 0.0f, -1.0f)), samples, uint64_t(i + 1)));
    }
    return Color(sum / double(rays));
}

TEST(ScatteringSolid, PhotonMapKeepsAUniformSkysRadianceInsideGlass) {
    for (const float ior : {1.0f, 1.5f}) {
        const auto rs = glass_sphere_under(ior, uniform_sky());
        ASSERT_TRUE(rs->scattering_interiors);
        const auto integrator = photon_map(rs, 0, 400000);
        // Measured: within 2 % but for the densest channel behind refraction (-3.1 %): its light
        // comes from close to the surface, whose curvature the cut, a plane at the nearest
        // point, leaves out (without the cut -9 %).
        const Color got = disc_mean(*integrator, Vec3(0.0f, 0.0f, -1.0f), 64);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], 1.0f, 0.04f) << "ior " << ior << " channel " << c;
        // Rays that graze the rim, where most of an estimate's sphere lies outside the solid.
        // Measured over photon seeds 1 to 4: within 2.5 % (k = 100) and 3.5 % (k = 200).
        const Color rim = rim_mean(*integrator, 16, 125);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(rim[c], 1.0f, 0.05f) << "ior " << ior << " rim, channel " << c;
    }
}

TEST(ScatteringSolid, PhotonMapSendsBackWhatPathTracingDoes) {
    // Seen from above, the sphere (ior 1.5) sends back up some of the light from above: all of it
    // scattered inside, which the volume map alone carries.
    const auto rs = glass_sphere_under(1.5f, half_sky());
    const auto integrator = photon_map(rs, 0, 400000);
    const Vec3 down(0.0f, -1.0f, 0.0f);
    const Color expected = disc_mean(PathIntegrator(rs), down, 1500);
    const Color got = disc_mean(*integrator, down, 64);
    EXPECT_GT(expected.z, expected.x + 0.05f);  // the densest channel sends back the most
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 0.03f * expected[c]) << "channel " << c;
}

/// A cube of absorbing, scattering glass just above a white floor (a face on the floor's plane
/// would be hit by either) under the half sky, seen from above at an angle.
std::shared_ptr<const RenderScene> cube_on_a_floor() {
    SceneBuilder builder("scattering-cube");
    const uint32_t floor = builder.add_material(lambertian(Color(0.8f)));
    const uint32_t glass = builder.add_material(scattering_glass(1.5f, Color(3.0f, 2.0f, 1.0f), Color(0.2f, 0.4f, 0.8f)));
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-3.0f, 0.0f, -3.0f), Vec3(6.0f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 6.0f), Vec3(0.0f, 1.0f, 0.0f)), floor)
                    .is_ok());
    EXPECT_TRUE(add_mesh(builder, make_box(Vec3(-0.6f, 0.01f, -0.6f), Vec3(0.6f, 1.21f, 0.6f)), glass).is_ok());
    Scene scene = builder.build().value();
    scene.environment = half_sky();
    return make_render_scene(std::move(scene));
}

Camera cube_camera() {
    CameraDesc view;
    view.position = Vec3(2.2f, 2.4f, 2.6f);
    view.look_at = Vec3(0.0f, 0.5f, 0.0f);
    view.vfov_deg = 40.0f;
    return Camera::create(view, 32, 32).value();
}

double image_mean(const Image& image) {
    double sum = 0.0;
    for (const Color& c : image.pixels()) {
        EXPECT_TRUE(is_finite(c));
        sum += luminance(c);
    }
    return sum / static_cast<double>(image.pixel_count());
}

TEST(ScatteringSolid, ACubeOnAFloorAgreesWithPathTracingForAnyThreadCount) {
    const auto rs = cube_on_a_floor();
    const Camera camera = cube_camera();
    TileSettings tiles;
    tiles.samples_per_pixel = 512;
    const double path_mean = image_mean(render_tiles(PathIntegrator(rs), camera, tiles).layers.beauty);
    const auto integrator = photon_map(rs, 200000, 400000);
    tiles.samples_per_pixel = 16;
    tiles.threads = 1;
    const Image one = render_tiles(*integrator, camera, tiles).layers.beauty;
    EXPECT_NEAR(image_mean(one), path_mean, 0.03 * path_mean);
    for (const int threads : {2, 7}) {
        tiles.threads = threads;
        EXPECT_TRUE(render_tiles(*integrator, camera, tiles).layers.beauty == one) << threads << " threads";
    }
    // The photons too: traced on 1 thread they make the same image.
    const auto traced_alone = photon_map(rs, 200000, 400000, 1);
    tiles.threads = 2;
    EXPECT_TRUE(render_tiles(*traced_alone, camera, tiles).layers.beauty == one);
}

}  // namespace
}  // namespace photond
