// Integrators against closed-form answers: the furnace, a point/spot/directional light over a
// Lambertian plane (I cos / d^2), and a square area light over a plane (Lambert's polygon formula).
#include <gtest/gtest.h>

#include "core/integrators/direct.h"
#include "core/integrators/path.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"

#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;

/// A 200 x 200 plane at y = 0 facing +y, albedo rho.
SceneBuilder plane_scene(float rho) {
    SceneBuilder builder("plane");
    const uint32_t material = builder.add_material(lambertian(Color(rho)));
    const Vec3 positions[4] = {{-100, 0, -100}, {-100, 0, 100}, {100, 0, 100}, {100, 0, -100}};
    const glm::uvec3 triangles[2] = {{0, 1, 2}, {0, 2, 3}};
    EXPECT_TRUE(builder.add_mesh(positions, {}, {}, triangles, material).is_ok());
    return builder;
}

/// Radiance seen along a ray from above that hits the plane at p.
Color radiance_at(const Integrator& integrator, const Vec3& p, int samples, uint64_t seed = 1) {
    CameraRay ray;
    ray.origin = p + Vec3(0.3f, 5.0f, 0.2f);
    ray.direction = glm::normalize(p - ray.origin);
    return test_support::mean_radiance(integrator, ray, samples, seed);
}

TEST(AnalyticLighting, PointLightOverPlaneMatchesInverseSquareCosine) {
    const float rho = 0.6f;
    const Vec3 light_position(0.5f, 3.0f, -1.0f);
    const Color intensity(10.0f, 20.0f, 5.0f);
    SceneBuilder builder = plane_scene(rho);
    PunctualLight light;
    light.position = light_position;
    light.intensity = intensity;
    builder.add_light(light);
    auto rs = make_render_scene(builder.build().value());
    const DirectIntegrator direct(rs);
    const PathIntegrator path(rs);
    for (const Vec3 p : {Vec3(0, 0, 0), Vec3(2, 0, 1), Vec3(-4, 0, 3), Vec3(0.5f, 0, -1)}) {
        const Vec3 d = light_position - p;
        const float dist2 = glm::dot(d, d);
        const float cos_theta = d.y / std::sqrt(dist2);
        const Color expected = rho / kPi * intensity * cos_theta / dist2;
        for (const Integrator* integrator : {static_cast<const Integrator*>(&direct),
                                             static_cast<const Integrator*>(&path)}) {
            const Color got = radiance_at(*integrator, p, 16);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c], expected[c], 0.01f * expected[c]) << integrator->name() << " at x=" << p.x;
        }
    }
}

TEST(AnalyticLighting, SpotLightFollowsItsConeFalloff) {
    const float rho = 0.5f;
    SceneBuilder builder = plane_scene(rho);
    PunctualLight spot;
    spot.type = PunctualLightType::Spot;
    spot.position = Vec3(0, 4, 0);
    spot.direction = Vec3(0, -1, 0);
    spot.intensity = Color(16.0f);
    spot.cos_inner = std::cos(0.3f);
    spot.cos_outer = std::cos(0.6f);
    builder.add_light(spot);
    auto rs = make_render_scene(builder.build().value());
    const DirectIntegrator direct(rs);
    // Inside the inner cone, between the cones, and outside the outer cone.
    for (const float x : {0.5f, 1.8f, 4.0f}) {
        const Vec3 p(x, 0, 0);
        const Vec3 d = spot.position - p;
        const float dist = glm::length(d);
        const float falloff = LightSet::spot_falloff(spot, glm::dot(-d / dist, spot.direction));
        const float expected = rho / kPi * 16.0f * falloff * (d.y / dist) / (dist * dist);
        const Color got = radiance_at(direct, p, 4);
        EXPECT_NEAR(got.x, expected, 0.01f * expected + 1e-7f) << "x=" << x;
    }
    EXPECT_GT(LightSet::spot_falloff(spot, std::cos(0.2f)), 0.999f);
    EXPECT_GT(LightSet::spot_falloff(spot, std::cos(0.45f)), 0.0f);
    EXPECT_EQ(LightSet::spot_falloff(spot, std::cos(0.7f)), 0.0f);
}

TEST(AnalyticLighting, DirectionalLightGivesIrradianceTimesCosine) {
    const float rho = 0.5f;
    SceneBuilder builder = plane_scene(rho);
    PunctualLight sun;
    sun.type = PunctualLightType::Directional;
    sun.direction = glm::normalize(Vec3(1, -2, 0));
    sun.intensity = Color(2.0f, 1.0f, 0.5f);
    builder.add_light(sun);
    auto rs = make_render_scene(builder.build().value());
    const DirectIntegrator direct(rs);
    const PathIntegrator path(rs);
    const Color expected = rho / kPi * sun.intensity * -sun.direction.y;
    for (const Integrator* integrator : {static_cast<const Integrator*>(&direct),
                                         static_cast<const Integrator*>(&path)}) {
        const Color got = radiance_at(*integrator, Vec3(3.0f, 0.0f, -2.0f), 4);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 0.01f * expected[c]) << integrator->name();
    }
}

/// Irradiance at the origin (normal +y) from a uniformly emitting polygon: Lambert's formula
/// E = L/2 * sum_i angle(v_i, v_i+1) * (n . normalize(v_i x v_i+1)).
double polygon_irradiance(const std::vector<Vec3>& vertices, double radiance) {
    double sum = 0.0;
    for (size_t i = 0; i < vertices.size(); ++i) {
        const glm::dvec3 a = glm::normalize(glm::dvec3(vertices[i]));
        const glm::dvec3 b = glm::normalize(glm::dvec3(vertices[(i + 1) % vertices.size()]));
        const double angle = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
        sum += angle * glm::normalize(glm::cross(a, b)).y;
    }
    return 0.5 * radiance * std::abs(sum);
}

TEST(AnalyticLighting, SquareAreaLightMatchesLambertPolygonFormula) {
    const float rho = 0.7f, emission = 5.0f;
    SceneBuilder builder = plane_scene(rho);
    Material light_material = lambertian(Color(0.0f));
    light_material.emission = Color(emission);
    const uint32_t light = builder.add_material(light_material);
    // A 1 x 1 square at height 1.5, shifted sideways, facing down (-y).
    const std::vector<Vec3> square = {{0.2f, 1.5f, -0.5f}, {1.2f, 1.5f, -0.5f}, {1.2f, 1.5f, 0.5f}, {0.2f, 1.5f, 0.5f}};
    const glm::uvec3 triangles[2] = {{0, 1, 2}, {0, 2, 3}};
    ASSERT_TRUE(builder.add_mesh(square, {}, {}, triangles, light).is_ok());
    auto rs = make_render_scene(builder.build().value());
    ASSERT_LT(rs->scene->triangle_normal(rs->scene->triangles.size() - 1).y, -0.99f);
    const double expected = rho / kPi * polygon_irradiance(square, emission);
    const DirectIntegrator direct(rs);
    const PathIntegrator path(rs);
    const Color got_direct = radiance_at(direct, Vec3(0.0f), 20000);
    const Color got_path = radiance_at(path, Vec3(0.0f), 20000);
    EXPECT_NEAR(got_direct.x, expected, 0.01 * expected);
    // The path tracer adds a second bounce (plane -> light's black back side): nothing, so equal.
    EXPECT_NEAR(got_path.x, expected, 0.01 * expected);
}

TEST(AnalyticLighting, FurnaceRadianceIsEmissionOverOneMinusAlbedo) {
    auto rs = make_render_scene(make_builtin_scene("furnace").value());
    const PathIntegrator path(rs);
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 32, 32).value();
    TileSettings settings;
    settings.samples_per_pixel = 64;
    const TileRenderResult result = render_tiles(path, camera, settings);
    double sum = 0.0;
    for (const Color& c : result.layers.beauty.pixels()) sum += average(c);
    const double mean = sum / static_cast<double>(result.layers.beauty.pixel_count());
    const double relative_error = std::abs(mean - kFurnaceRadiance) / kFurnaceRadiance;
    RecordProperty("furnace_relative_error", std::to_string(relative_error));
    std::printf("furnace: mean radiance %.5f, expected %.5f, relative error %.4f %%\n", mean,
                static_cast<double>(kFurnaceRadiance), 100.0 * relative_error);
    EXPECT_LT(relative_error, 0.01);
}

}  // namespace
}  // namespace photond
