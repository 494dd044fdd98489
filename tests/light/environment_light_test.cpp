// The environment light and soft suns: image mapping, importance sampling against its density
// (chi-square), emitted photon flux against the map's integral, and every integrator against
// closed forms (a convex Lambertian object under a uniform sky has radiance rho L; a plane under
// an image sky reflects rho / pi times the image's cosine-weighted integral).
#include <gtest/gtest.h>

#include "core/integrators/direct.h"
#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/light/environment_light.h"
#include "core/light/light_set.h"
#include "core/math/rng.h"
#include "core/scene/shapes.h"
#include "tests/support/chi_square.h"
#include "tests/support/photon_fixtures.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::chi_square_p_value;
using test_support::lambertian;
using test_support::make_render_scene;
using test_support::mean_radiance;

constexpr double kPiD = 3.14159265358979323846;

/// A sky of w x h texels: a gradient from the horizon up, a dim ground and one hot "sun" texel
/// (a thousand times the sky), so that importance sampling matters.
Environment test_sky(int w = 32, int h = 16) {
    Environment e;
    e.name = "test sky";
    e.width = w;
    e.height = h;
    e.texels.resize(static_cast<size_t>(w * h));
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const float up = 1.0f - (static_cast<float>(y) + 0.5f) / static_cast<float>(h);
            Color c = y < h / 2 ? Color(0.2f + 0.6f * up, 0.3f + 0.6f * up, 1.0f) : Color(0.05f, 0.04f, 0.03f);
            c *= 1.0f + 0.5f * std::sin(0.7f * static_cast<float>(x));
            e.texels[static_cast<size_t>(y * w + x)] = c;
        }
    }
    e.texels[static_cast<size_t>((h / 4) * w + w / 3)] = Color(900.0f, 800.0f, 700.0f);
    return e;
}

int texel_of(const EnvironmentLight& light, const Environment& e, const Vec3& d) {
    const Vec2 uv = light.direction_to_uv(d);
    const int x = std::min(static_cast<int>(uv.x * static_cast<float>(e.width)), e.width - 1);
    const int y = std::min(static_cast<int>(uv.y * static_cast<float>(e.height)), e.height - 1);
    return y * e.width + x;
}

TEST(EnvironmentLight, MapsDirectionsAsBlenderAndThreeJsDo) {
    Environment e = test_sky();
    const EnvironmentLight light(e);
    EXPECT_NEAR(light.direction_to_uv({0, 1, 0}).y, 0.0f, 1e-6f);   // up: the top row
    EXPECT_NEAR(light.direction_to_uv({0, -1, 0}).y, 1.0f, 1e-6f);  // down: the bottom row
    EXPECT_NEAR(light.direction_to_uv({1, 0, 0}).x, 0.5f, 1e-6f);   // +X: the centre column
    EXPECT_NEAR(light.direction_to_uv({0, 0, 1}).x, 0.75f, 1e-6f);
    EXPECT_NEAR(light.direction_to_uv({0, 0, -1}).x, 0.25f, 1e-6f);
    EXPECT_NEAR(light.direction_to_uv({1, 0, 0}).y, 0.5f, 1e-6f);
    Rng rng(3, 4);
    for (int i = 0; i < 1000; ++i) {
        const Vec3 d = sample_uniform_sphere(rng.next_vec2());
        const Vec3 back = light.uv_to_direction(light.direction_to_uv(d));
        EXPECT_LT(glm::length(back - d), 1e-4f) << i;
    }
    // A quarter turn counter-clockwise seen from above brings what lay at +X to -Z.
    e.rotation = 0.5f * kPi;
    const EnvironmentLight turned(e);
    EXPECT_NEAR(turned.direction_to_uv({0, 0, -1}).x, 0.5f, 1e-5f);
    Environment unturned = test_sky();
    const EnvironmentLight reference(unturned);
    int differing = 0;  // only directions within rounding of a texel edge may differ
    for (int i = 0; i < 1000; ++i) {
        const Vec3 d = sample_uniform_sphere(rng.next_vec2());
        const Vec3 turned_d(d.z, d.y, -d.x);  // d turned a quarter counter-clockwise about +Y
        if (turned.radiance(turned_d) != reference.radiance(d)) ++differing;
    }
    EXPECT_LE(differing, 2);
}

TEST(EnvironmentLight, SamplesFollowLuminanceTimesSolidAngle) {
    const Environment e = test_sky();
    const EnvironmentLight light(e);
    // Expected share of each texel, computed here independently: luminance times its exact solid
    // angle (the texel's row spans cos(theta0) - cos(theta1)).
    std::vector<double> expected(e.texels.size());
    double total = 0.0;
    for (int y = 0; y < e.height; ++y) {
        const double band = std::cos(kPiD * y / e.height) - std::cos(kPiD * (y + 1) / e.height);
        for (int x = 0; x < e.width; ++x) {
            const size_t i = static_cast<size_t>(y * e.width + x);
            expected[i] = luminance(e.texels[i]) * band;
            total += expected[i];
        }
    }
    constexpr int kSamples = 400000;
    for (double& v : expected) v *= kSamples / total;
    std::vector<double> observed(e.texels.size(), 0.0);
    Rng rng(5, 6);
    int pdf_mismatches = 0;
    for (int i = 0; i < kSamples; ++i) {
        float pdf = 0.0f;
        const Vec3 d = light.sample(rng.next_vec2(), &pdf);
        ASSERT_GT(pdf, 0.0f);
        ASSERT_NEAR(glm::length(d), 1.0f, 1e-4f);
        observed[static_cast<size_t>(texel_of(light, e, d))] += 1.0;
        if (std::abs(light.pdf(d) - pdf) > 1e-3f * pdf) ++pdf_mismatches;  // texel edges only
    }
    EXPECT_LT(pdf_mismatches, kSamples / 1000);
    EXPECT_GT(chi_square_p_value(observed, expected), 1e-3);
}

TEST(EnvironmentLight, PdfIntegratesToOneAndWeightsGiveTheIntegral) {
    const Environment e = test_sky();
    const EnvironmentLight light(e);
    // Quadrature over the image plane, 8 x 8 points per texel: domega = 2 pi^2 sin(theta) du dv.
    constexpr int kSub = 8;
    double pdf_integral = 0.0;
    DVec3 radiance_integral(0.0);
    const int nu = e.width * kSub, nv = e.height * kSub;
    for (int j = 0; j < nv; ++j) {
        for (int i = 0; i < nu; ++i) {
            const Vec2 uv((static_cast<float>(i) + 0.5f) / static_cast<float>(nu),
                          (static_cast<float>(j) + 0.5f) / static_cast<float>(nv));
            const Vec3 d = light.uv_to_direction(uv);
            const double area = 2.0 * kPiD * kPiD * std::sin(kPiD * uv.y) / (static_cast<double>(nu) * nv);
            pdf_integral += light.pdf(d) * area;
            radiance_integral += DVec3(light.radiance(d)) * area;
        }
    }
    EXPECT_NEAR(pdf_integral, 1.0, 2e-3);
    // Importance sampling: L / pdf averages to the integral, with little noise (L / pdf is
    // nearly constant).
    Rng rng(7, 8);
    DVec3 weighted_sum(0.0);
    constexpr int kSamples = 200000;
    for (int i = 0; i < kSamples; ++i) {
        float pdf = 0.0f;
        const Vec3 s = light.sample(rng.next_vec2(), &pdf);
        weighted_sum += DVec3(light.radiance(s)) / static_cast<double>(pdf);
    }
    const DVec3 integral(light.radiance_integral());
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(radiance_integral[c] / integral[c], 1.0, 2e-3) << c;
        EXPECT_NEAR(weighted_sum[c] / kSamples / integral[c], 1.0, 5e-3) << c;
    }
}

/// A sphere of albedo rho at the origin, radius 1, with `environment` around it.
Scene sphere_under(const Environment& environment, float rho) {
    SceneBuilder builder("sphere under a sky");
    const uint32_t m = builder.add_material(lambertian(Color(rho)));
    EXPECT_TRUE(add_mesh(builder, make_icosphere(Vec3(0.0f), 1.0f, 4), m).is_ok());
    Scene scene = builder.build().value();
    scene.environment = environment;
    return scene;
}

TEST(EnvironmentLight, EmittedPhotonFluxIsTheMapIntegralOverTheSceneDisc) {
    const Scene scene = sphere_under(test_sky(), 0.5f);
    const LightSet lights(scene);
    ASSERT_EQ(lights.size(), 1u);
    ASSERT_EQ(lights.kind(0), LightKind::Environment);
    const float radius = scene.bounds.radius();
    const DVec3 expected = DVec3(lights.environment()->radiance_integral()) * (kPiD * radius * radius);
    Rng rng(9, 10);
    DVec3 flux(0.0);
    constexpr int kSamples = 500000;
    for (int i = 0; i < kSamples; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2());
        ASSERT_TRUE(e.has_value()) << i;
        // Parallel photons start outside the bounding sphere, on a disc across the scene.
        const Vec3 to_origin = e->origin - scene.bounds.center();
        EXPECT_GT(glm::length(to_origin), radius);
        const Vec3 across = to_origin - glm::dot(to_origin, e->direction) * e->direction;
        EXPECT_LE(glm::length(across), radius * 1.0001f);
        flux += DVec3(e->flux_weight);
    }
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(flux[c] / kSamples / expected[c], 1.0, 0.01) << c;
    EXPECT_NEAR(DVec3(lights.total_power())[0] / expected[0], 1.0, 1e-5);
}

std::vector<CameraRay> rays_at_sphere() {
    std::vector<CameraRay> rays;
    for (const Vec3 eye : {Vec3(0, 0, 5), Vec3(3, 3, -3), Vec3(-4, -1, 1), Vec3(0.5f, -5, 0.2f)}) {
        CameraRay ray;
        ray.origin = eye;
        ray.direction = glm::normalize(Vec3(0.2f, 0.1f, 0.0f) - eye);
        rays.push_back(ray);
    }
    return rays;
}

/// Whether the ray (origin, unit direction) meets the sphere.
bool ray_meets_sphere(const Vec3& origin, const Vec3& direction, const EmissionFocus& sphere) {
    const Vec3 to_center = sphere.center - origin;
    const float along = glm::dot(to_center, direction);
    return along > 0.0f && glm::dot(to_center, to_center) - along * along <= sphere.radius * sphere.radius;
}

TEST(EnvironmentLight, FocusedEmissionCarriesTheSameFluxIntoItsSphere) {
    // A big scene (sphere of radius 1 plus a far corner) and a small target inside it: the flux
    // of the photons that meet the target is the same whether they are aimed at it or not.
    Scene scene = sphere_under(test_sky(), 0.5f);
    scene.bounds.extend(Vec3(6.0f, 5.0f, -4.0f));
    PunctualLight sun;
    sun.type = PunctualLightType::Directional;
    sun.direction = glm::normalize(Vec3(-1.0f, -2.0f, 0.5f));
    sun.intensity = Color(40.0f);
    sun.angular_radius = 0.05f;
    scene.lights.push_back(sun);
    const LightSet lights(scene);
    const EmissionFocus target{Vec3(0.3f, 0.2f, -0.1f), 0.6f};
    constexpr int kSamples = 1000000;
    // The mean flux per emitted photon that meets the target, and how many met it.
    const auto into_target = [&](const EmissionFocus* focus, int* inside) {
        Rng rng(21, 22);
        DVec3 flux(0.0);
        *inside = 0;
        for (int i = 0; i < kSamples; ++i) {
            const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2(), focus);
            if (!e) continue;
            EXPECT_GT(glm::length(e->origin - scene.bounds.center()), scene.bounds.radius());
            if (!ray_meets_sphere(e->origin, e->direction, target)) continue;
            flux += DVec3(e->flux_weight);
            ++*inside;
        }
        return flux / static_cast<double>(kSamples);
    };
    int inside_unfocused = 0, inside_focused = 0;
    const DVec3 unfocused = into_target(nullptr, &inside_unfocused);
    const DVec3 focused = into_target(&target, &inside_focused);
    EXPECT_LT(inside_unfocused, kSamples / 10);  // most photons miss the target
    EXPECT_GT(inside_focused, kSamples / 2);     // aimed, most meet it
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(focused[c] / unfocused[c], 1.0, 0.03) << c;
}

TEST(EnvironmentLight, ConvexLambertianUnderUniformSkyIsAlbedoTimesRadiance) {
    Environment sky;
    sky.color = Color(1.0f, 2.0f, 4.0f);
    sky.intensity = 0.5f;
    const float rho = 0.6f;
    auto rs = make_render_scene(sphere_under(sky, rho));
    const Color expected = rho * sky.intensity * sky.color;

    const PathIntegrator path(rs);
    const DirectIntegrator direct(rs);
    const auto uncached = test_support::uncached_photon_map(rs, 20000, 0, 64);
    ASSERT_TRUE(uncached);
    const PhotonMapIntegrator& photon_map = *uncached;

    for (const Integrator* integrator : std::initializer_list<const Integrator*>{&path, &direct, &photon_map}) {
        const int samples = integrator == &photon_map ? 4000 : 20000;
        for (const CameraRay& ray : rays_at_sphere()) {
            const Color L = mean_radiance(*integrator, ray, samples, 11);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(L[c] / expected[c], 1.0, 0.01) << integrator->name() << " channel " << c;
        }
        // A camera ray that misses sees the sky itself.
        CameraRay miss;
        miss.origin = Vec3(0, 0, 5);
        miss.direction = Vec3(0, 1, 0);
        const Color sky_seen = mean_radiance(*integrator, miss, 1, 1);
        EXPECT_EQ(sky_seen, sky.intensity * sky.color) << integrator->name();
    }
}

TEST(EnvironmentLight, ThinWallsUnderAUniformSkyKeepItsRadiance) {
    // White thin walls (Material::thin_walled: air on both sides) reflect F of the sky and pass
    // the rest of it straight through: L = F L + (1 - F) L whatever they are crossed at. Two
    // panes one behind the other, smooth and rough (GGX alpha 0.04: its mirrored lobe loses
    // under 0.1 %). As solids that never closed (refraction into glass with 1/eta^2 at each
    // crossing) they were 0.44 L and darker behind each other.
    Environment sky;
    sky.color = Color(0.5f, 1.0f, 2.0f);
    SceneBuilder builder("thin walls under a sky");
    for (const auto& [z, roughness] : {std::pair{0.0f, 0.0f}, std::pair{-1.0f, 0.2f}}) {
        Material wall;
        wall.base_color = Color(1.0f);
        wall.metallic = 0.0f;
        wall.roughness = roughness;
        wall.transmission = 1.0f;
        wall.ior = 1.5f;
        wall.thin_walled = true;
        const uint32_t m = builder.add_material(wall);
        const Vec3 positions[4] = {{-2, -2, z}, {2, -2, z}, {2, 2, z}, {-2, 2, z}};
        const glm::uvec3 triangles[2] = {{0, 1, 2}, {0, 2, 3}};
        ASSERT_TRUE(builder.add_mesh(positions, {}, {}, triangles, m).is_ok());
    }
    Scene scene = builder.build().value();
    scene.environment = sky;
    auto rs = make_render_scene(std::move(scene));

    // Not `direct`: its shadow rays stop at glass, so the rough pane's lobes see no sky through
    // the other pane.
    const PathIntegrator path(rs);
    const auto uncached = test_support::uncached_photon_map(rs, 20000, 20000, 64);
    ASSERT_TRUE(uncached);
    const PhotonMapIntegrator& photon_map = *uncached;
    for (const Integrator* integrator : std::initializer_list<const Integrator*>{&path, &photon_map}) {
        for (const Vec3 eye : {Vec3(0, 0, 5), Vec3(2, 1, 3), Vec3(-0.5f, 0.3f, -4)}) {
            CameraRay ray;
            ray.origin = eye;
            ray.direction = glm::normalize(Vec3(0.1f, 0.2f, -0.5f) - eye);
            const Color L = mean_radiance(*integrator, ray, 4000, 5);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(L[c] / sky.color[c], 1.0, 0.01) << integrator->name() << " from " << eye.x << ","
                                                            << eye.y << "," << eye.z << " channel " << c;
        }
    }
}

/// A 200 x 200 plane at y = 0 facing +y, albedo rho.
Scene plane_scene(float rho) {
    SceneBuilder builder("plane");
    const uint32_t material = builder.add_material(lambertian(Color(rho)));
    const Vec3 positions[4] = {{-100, 0, -100}, {-100, 0, 100}, {100, 0, 100}, {100, 0, -100}};
    const glm::uvec3 triangles[2] = {{0, 1, 2}, {0, 2, 3}};
    EXPECT_TRUE(builder.add_mesh(positions, {}, {}, triangles, material).is_ok());
    return builder.build().value();
}

CameraRay ray_down_at_origin() {
    CameraRay ray;
    ray.origin = Vec3(0.3f, 5.0f, 0.2f);
    ray.direction = glm::normalize(-ray.origin);
    return ray;
}

TEST(EnvironmentLight, PlaneUnderImageSkyReflectsItsCosineWeightedIntegral) {
    const float rho = 0.5f;
    Scene scene = plane_scene(rho);
    scene.environment = test_sky();
    // E = sum over the upper rows of L times the texel's integral of cos(theta) d(omega):
    // (sin^2(theta1) - sin^2(theta0)) / 2 * (2 pi / w).
    const Environment& e = *scene.environment;
    DVec3 irradiance(0.0);
    for (int y = 0; y < e.height / 2; ++y) {
        const double s0 = std::sin(kPiD * y / e.height), s1 = std::sin(kPiD * (y + 1) / e.height);
        const double cosine_solid_angle = 0.5 * (s1 * s1 - s0 * s0) * (2.0 * kPiD / e.width);
        for (int x = 0; x < e.width; ++x) irradiance += DVec3(e.texels[static_cast<size_t>(y * e.width + x)]) * cosine_solid_angle;
    }
    const Color expected = Color(irradiance * (rho / kPiD));
    auto rs = make_render_scene(std::move(scene));
    const PathIntegrator path(rs);
    const DirectIntegrator direct(rs);
    for (const Integrator* integrator : std::initializer_list<const Integrator*>{&path, &direct}) {
        const Color L = mean_radiance(*integrator, ray_down_at_origin(), 100000, 13);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(L[c] / expected[c], 1.0, 0.01) << integrator->name() << " channel " << c;
    }
}

TEST(SoftSun, IrradianceOnAPlaneIsItsIntensityTimesCosine) {
    const float rho = 0.5f;
    Scene scene = plane_scene(rho);
    PunctualLight sun;
    sun.type = PunctualLightType::Directional;
    const float elevation = 30.0f * kPi / 180.0f;
    sun.direction = -Vec3(std::cos(elevation), std::sin(elevation), 0.0f);
    sun.intensity = Color(3.0f);
    sun.angular_radius = 5.0f * kPi / 180.0f;  // the cap stays above the horizon: E cos is exact
    scene.lights.push_back(sun);
    const float expected = rho * kInvPi * 3.0f * std::sin(elevation);
    auto rs = make_render_scene(std::move(scene));
    ASSERT_TRUE(rs->lights->has_distant_area_lights());
    const PathIntegrator path(rs);
    const DirectIntegrator direct(rs);
    for (const Integrator* integrator : std::initializer_list<const Integrator*>{&path, &direct}) {
        const Color L = mean_radiance(*integrator, ray_down_at_origin(), 20000, 17);
        EXPECT_NEAR(L.x / expected, 1.0, 0.01) << integrator->name();
    }
    // Emission: the flux through the disc is the sun's radiance times its cone's solid angle.
    const LightSet& lights = *rs->lights;
    Rng rng(1, 2);
    DVec3 flux(0.0);
    for (int i = 0; i < 100000; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2());
        ASSERT_TRUE(e.has_value());
        EXPECT_GE(glm::dot(e->direction, sun.direction), std::cos(sun.angular_radius) - 1e-6f);
        flux += DVec3(e->flux_weight);
    }
    EXPECT_NEAR(flux.x / 100000 / lights.total_power().x, 1.0, 1e-4);
}

}  // namespace
}  // namespace photond
