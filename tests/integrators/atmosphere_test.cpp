// The atmosphere (a homogeneous medium filling the scene's bounds) against closed forms: an
// absorbing slab passes exp(-sigma_a d) of an emitter behind it; the light a point light scatters
// once towards a ray equals a quadrature of the single-scattering integral (direct, and path
// limited to one scattering event) for forward, isotropic and backward phase functions; a
// non-absorbing fog around a white sphere under a uniform sky keeps every radiance at the sky's
// (the furnace, which multiple scattering must pass); the AOV parts still sum to the beauty
// image; images are the same for 1, 2 and 7 threads. A smooth glass sphere whose solid
// scatters keeps a uniform sky's radiance, and sends light from above back up (path).
#include <gtest/gtest.h>

#include <cmath>

#include "core/camera/camera.h"
#include "core/integrators/direct.h"
#include "core/integrators/path.h"
#include "core/medium/homogeneous_medium.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;
using test_support::mean_radiance;

/// A tiny triangle at `corner` (material `material`): it stretches the scene's bounds, and with
/// them the atmosphere, without standing in any ray's way.
void add_marker(SceneBuilder& builder, const Vec3& corner, uint32_t material) {
    const Vec3 positions[3] = {corner, corner + Vec3(1e-3f, 0.0f, 0.0f), corner + Vec3(0.0f, 1e-3f, 0.0f)};
    const glm::uvec3 triangle[1] = {{0, 1, 2}};
    ASSERT_TRUE(builder.add_mesh(positions, {}, {}, triangle, material).is_ok());
}

CameraRay ray_from(const Vec3& origin, const Vec3& direction) {
    CameraRay ray;
    ray.origin = origin;
    ray.direction = glm::normalize(direction);
    return ray;
}

TEST(Atmosphere, AnAbsorbingSlabPassesBeerLambert) {
    // An emitter of radiance 1 at z = 0 seen along -z through the box z in [0, 2]: exp(-2 sigma_a).
    SceneBuilder builder("slab");
    Material glow = lambertian(Color(0.0f));
    glow.emission = Color(1.0f);
    const uint32_t emitter = builder.add_material(glow);
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-1, -1, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)), emitter).is_ok());
    add_marker(builder, Vec3(4.0f, 0.0f, 2.0f), builder.add_material(lambertian(Color(0.0f))));
    Scene scene = builder.build().value();
    HomogeneousMedium fog;
    fog.sigma_a = Color(0.1f, 0.5f, 1.0f);
    scene.atmosphere = fog;
    const auto rs = make_render_scene(std::move(scene));
    const CameraRay ray = ray_from(Vec3(0.2f, 0.1f, 5.0f), Vec3(0, 0, -1));
    for (const Integrator* integrator : std::initializer_list<const Integrator*>{
             new PathIntegrator(rs), new DirectIntegrator(rs)}) {
        const Color got = mean_radiance(*integrator, ray, 4);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(got[c], std::exp(-2.0f * fog.sigma_a[c]), 1e-5f) << integrator->name() << " channel " << c;
        delete integrator;
    }
}

/// The single-scattering integral along a ray through the box [-1, 1]^3 from a point light of
/// intensity I at `light` (Simpson's rule in double precision).
Color single_scattering(const HomogeneousMedium& m, const Vec3& origin, const Vec3& direction, const Vec3& light,
                        const Color& intensity) {
    // The ray enters the box at t0 and leaves it at t1 (it is axis-aligned in the test).
    const Bounds3 box{Vec3(-1.0f), Vec3(1.0f)};
    float t0 = 0.0f, t1 = 1e30f;
    for (int a = 0; a < 3; ++a) {
        if (direction[a] == 0.0f) continue;
        float n = (box.lower[a] - origin[a]) / direction[a], f = (box.upper[a] - origin[a]) / direction[a];
        if (n > f) std::swap(n, f);
        t0 = std::max(t0, n);
        t1 = std::min(t1, f);
    }
    const int steps = 20000;
    const double h = (t1 - t0) / steps;
    DVec3 sum(0.0);
    for (int i = 0; i <= steps; ++i) {
        const double t = t0 + i * h;
        const DVec3 x = DVec3(origin) + t * DVec3(direction);
        const DVec3 to_light = DVec3(light) - x;
        const double r = glm::length(to_light);
        // Light travels from the light to x, then back along the ray towards its origin.
        const double cos_theta = glm::dot(-to_light / r, -DVec3(direction));
        const double g = m.g;
        const double phase = (1.0 - g * g) / (4.0 * 3.14159265358979 * std::pow(1.0 + g * g - 2.0 * g * cos_theta, 1.5));
        DVec3 value;
        for (int c = 0; c < 3; ++c) {
            const double st = m.sigma_t()[c];
            value[c] = std::exp(-st * (t - t0)) * m.sigma_s[c] * phase * intensity[c] * std::exp(-st * r) / (r * r);
        }
        const double w = (i == 0 || i == steps) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
        sum += w * value;
    }
    return Color(sum * (h / 3.0));
}

TEST(Atmosphere, SingleScatteringFromAPointLightMatchesTheIntegral) {
    SceneBuilder builder("point-in-fog");
    const uint32_t black = builder.add_material(lambertian(Color(0.0f)));
    add_marker(builder, Vec3(-1.0f), black);
    add_marker(builder, Vec3(1.0f - 1e-3f), black);
    PunctualLight light;
    light.position = Vec3(0.3f, 0.2f, -0.1f);
    light.intensity = Color(10.0f, 6.0f, 3.0f);
    builder.add_light(light);
    const Scene base = builder.build().value();
    const Vec3 origin(-0.2f, -0.1f, 3.0f), direction(0.0f, 0.0f, -1.0f);
    for (const float g : {0.6f, 0.0f, -0.4f}) {
        Scene scene = base;
        HomogeneousMedium fog;
        fog.sigma_a = Color(0.1f, 0.05f, 0.0f);
        fog.sigma_s = Color(0.2f, 0.4f, 0.8f);
        fog.g = g;
        scene.atmosphere = fog;
        const auto rs = make_render_scene(std::move(scene));
        const Color expected = single_scattering(fog, origin, direction, light.position, light.intensity);
        const DirectIntegrator direct(rs);
        const PathIntegrator single(rs, 1);  // one vertex: the scattering event and its light sample
        const Color by_direct = mean_radiance(direct, ray_from(origin, direction), 100000);
        const Color by_path = mean_radiance(single, ray_from(origin, direction), 200000);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(by_direct[c], expected[c], 0.01f * expected[c]) << "direct, g " << g << " channel " << c;
            EXPECT_NEAR(by_path[c], expected[c], 0.015f * expected[c]) << "path, g " << g << " channel " << c;
        }
    }
}

TEST(Atmosphere, NonAbsorbingFogUnderAUniformSkyKeepsItsRadiance) {
    // The furnace with a medium: a white Lambertian sphere in a fog that absorbs nothing, under a
    // sky of radiance 1, leaves radiance 1 everywhere, however often light scatters (optical
    // depths up to 8 across the box, a colour-dependent coefficient, a forward phase function).
    SceneBuilder builder("foggy-furnace");
    const uint32_t white = builder.add_material(lambertian(Color(1.0f)));
    ASSERT_TRUE(add_mesh(builder, make_icosphere(Vec3(0.0f), 0.5f, 3), white).is_ok());
    add_marker(builder, Vec3(-1.0f), white);
    add_marker(builder, Vec3(1.0f - 1e-3f), white);
    Scene scene = builder.build().value();
    scene.environment = Environment{};
    HomogeneousMedium fog;
    fog.sigma_s = Color(0.5f, 1.5f, 4.0f);
    fog.g = 0.6f;
    scene.atmosphere = fog;
    const auto rs = make_render_scene(std::move(scene));
    const PathIntegrator path(rs);
    // From outside towards the sphere, from inside the fog, and past the sphere.
    for (const auto& [origin, target] : {std::pair{Vec3(0.0f, 0.0f, 3.0f), Vec3(0.0f)},
                                         std::pair{Vec3(0.7f, 0.6f, 0.5f), Vec3(-1.0f, 0.2f, -0.3f)},
                                         std::pair{Vec3(-3.0f, 0.8f, 0.1f), Vec3(0.0f, 0.8f, 0.0f)}}) {
        const Color got = mean_radiance(path, ray_from(origin, target - origin), 40000);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], 1.0f, 0.02f) << "from " << origin.x << " channel " << c;
    }
}

/// A smooth glass sphere of radius 0.5 at the origin whose solid scatters (optical depths 1, 2.5
/// and 6 across, g 0.5) and absorbs nothing, in a scene of its own.
Scene scattering_glass_sphere(float ior) {
    SceneBuilder builder("scattering-solid");
    Material glass = test_support::smooth_glass(ior);
    glass.scattering = Color(1.0f, 2.5f, 6.0f);
    glass.phase_g = 0.5f;
    EXPECT_TRUE(add_mesh(builder, make_icosphere(Vec3(0.0f), 0.5f, 4), builder.add_material(glass)).is_ok());
    return builder.build().value();
}

TEST(Atmosphere, AScatteringSolidUnderAUniformSkyKeepsItsRadiance) {
    // The furnace inside glass: a smooth transmissive sphere whose solid scatters and absorbs
    // nothing (Material::scattering, a job's material_media), under a sky of radiance 1, passes
    // the sky on unchanged along every ray, whether its surface refracts (ior 1.5, with
    // reflection and total internal reflection) or not (ior 1). Its inside is reached by light
    // only through the surface (light samples from inside are blocked by it).
    for (const float ior : {1.0f, 1.5f}) {
        Scene scene = scattering_glass_sphere(ior);
        scene.environment = Environment{};
        const auto rs = make_render_scene(std::move(scene));
        ASSERT_TRUE(rs->scattering_interiors);
        const PathIntegrator path(rs);
        for (const Vec3& origin : {Vec3(0.0f, 0.0f, 3.0f), Vec3(0.3f, 0.35f, 2.0f)}) {
            const Color got = mean_radiance(path, ray_from(origin, -origin), 40000);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c], 1.0f, 0.02f) << "ior " << ior << " from y " << origin.y << " channel " << c;
        }
    }
    // Under a sky that is white above the horizon and black below, the same sphere (ior 1, its
    // surface invisible) seen from straight above would show the black below if its inside did
    // not scatter: it sends back some of the light from above, the densest channel (blue,
    // optical depth 6 across) the most.
    Scene scene = scattering_glass_sphere(1.0f);
    Environment half_sky;
    half_sky.name = "half";
    half_sky.width = 4;
    half_sky.height = 2;
    half_sky.texels = {Color(1.0f), Color(1.0f), Color(1.0f), Color(1.0f), Color(0.0f), Color(0.0f), Color(0.0f), Color(0.0f)};
    scene.environment = half_sky;
    const auto rs = make_render_scene(std::move(scene));
    const Color back = mean_radiance(PathIntegrator(rs), ray_from(Vec3(0.0f, 3.0f, 0.0f), Vec3(0.0f, -1.0f, 0.0f)), 40000);
    EXPECT_GT(back.x, 0.02f);
    EXPECT_GT(back.z, back.x + 0.05f);
    EXPECT_LT(back.z, 1.0f);
}

TEST(Atmosphere, PartsSumToTheImageAndThreadCountsAgree) {
    Scene scene = make_builtin_scene("cornell-box-diffuse").value();
    HomogeneousMedium fog;
    fog.sigma_a = Color(0.05f);
    fog.sigma_s = Color(0.3f, 0.4f, 0.5f);
    fog.g = 0.3f;
    scene.atmosphere = fog;
    const CameraDesc view = scene.cameras.at(0);
    const auto rs = make_render_scene(std::move(scene));
    const Camera camera = Camera::create(view, 32, 32).value();
    for (const Integrator* integrator : std::initializer_list<const Integrator*>{
             new PathIntegrator(rs), new DirectIntegrator(rs)}) {
        TileSettings settings;
        settings.tile_size = 8;
        settings.samples_per_pixel = 4;
        settings.seed = 3;
        settings.aovs = {Aov::Emission, Aov::Direct, Aov::Indirect, Aov::Caustic};
        settings.threads = 1;
        const TileRenderResult one = render_tiles(*integrator, camera, settings);
        for (const int threads : {2, 7}) {
            settings.threads = threads;
            const TileRenderResult other = render_tiles(*integrator, camera, settings);
            EXPECT_TRUE(one.layers.beauty == other.layers.beauty) << integrator->name() << ", " << threads << " threads";
        }
        double image_sum = 0.0, parts_sum = 0.0;
        for (size_t i = 0; i < one.layers.beauty.pixel_count(); ++i) {
            const Color beauty = one.layers.beauty.pixels()[i];
            ASSERT_TRUE(is_finite(beauty));
            image_sum += luminance(beauty);
            for (const auto& layer : one.layers.aovs) parts_sum += luminance(layer.second.pixels()[i]);
        }
        EXPECT_GT(image_sum, 0.0);
        EXPECT_NEAR(parts_sum, image_sum, 1e-4 * image_sum) << integrator->name();
        delete integrator;
    }
}

}  // namespace
}  // namespace photond
