// Photon emission per light type: chi-square tests of emitted directions and origins against
// the distributions they must follow, and flux weights that average to each light's power.
#include <gtest/gtest.h>


#include "core/light/light_set.h"
#include "core/math/rng.h"
#include "tests/support/chi_square.h"

namespace photond {
namespace {

using test_support::chi_square_p_value;

constexpr int kSamples = 200000;
constexpr double kSignificance = 1e-3;

Material emitter(float radiance, bool double_sided) {
    Material m;
    m.base_color = Color(0.0f);
    m.emission = Color(radiance);
    m.double_sided = double_sided;
    return m;
}

Scene scene_with(const std::vector<PunctualLight>& lights, bool with_triangle, bool double_sided = false) {
    SceneBuilder builder("emission");
    const uint32_t m = builder.add_material(emitter(with_triangle ? 2.0f : 0.0f, double_sided));
    // A triangle in the plane z = 1 (front face +z); also gives the scene its bounds.
    const Vec3 positions[3] = {{0, 0, 1}, {2, 0, 1}, {0, 1, 1}};
    const glm::uvec3 triangle[1] = {{0, 1, 2}};
    EXPECT_TRUE(builder.add_mesh(positions, {}, {}, triangle, m).is_ok());
    for (const PunctualLight& l : lights) builder.add_light(l);
    return builder.build().value();
}

/// Bins a direction by (cos theta about `axis`, phi) into a grid of cos_bins x phi_bins.
size_t direction_bin(const Vec3& d, const Frame& frame, int cos_bins, int phi_bins, float cos_min) {
    const Vec3 l = frame.to_local(d);
    const float c = std::clamp((l.z - cos_min) / (1.0f - cos_min), 0.0f, 0.99999f);
    float phi = std::atan2(l.y, l.x);
    if (phi < 0.0f) phi += 2.0f * kPi;
    const int pi = std::min(static_cast<int>(phi / (2.0f * kPi) * phi_bins), phi_bins - 1);
    return static_cast<size_t>(static_cast<int>(c * cos_bins) * phi_bins + pi);
}

TEST(Emission, PointLightDirectionsAreUniformOnTheSphere) {
    PunctualLight light;
    light.position = Vec3(0.5f, 0.2f, 0.0f);
    light.intensity = Color(3.0f);
    const Scene scene = scene_with({light}, false);
    const LightSet lights(scene);
    const int cos_bins = 10, phi_bins = 20;
    std::vector<double> observed(cos_bins * phi_bins, 0.0), expected(observed.size(), double(kSamples) / observed.size());
    DVec3 flux(0.0);
    Rng rng(1, 2);
    for (int i = 0; i < kSamples; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2());
        ASSERT_TRUE(e.has_value());
        EXPECT_EQ(e->origin, light.position);
        observed[direction_bin(e->direction, Frame(Vec3(0, 0, 1)), cos_bins, phi_bins, -1.0f)] += 1.0;
        flux += DVec3(e->flux_weight);
    }
    EXPECT_GT(chi_square_p_value(observed, expected), kSignificance);
    EXPECT_NEAR(flux.x / kSamples, 4.0 * kPi * 3.0, 1e-3);
}

TEST(Emission, SpotLightDirectionsFillItsConeAndFluxFollowsTheFalloff) {
    PunctualLight light;
    light.type = PunctualLightType::Spot;
    light.position = Vec3(0.0f);
    light.direction = glm::normalize(Vec3(0.3f, -1.0f, 0.2f));
    light.intensity = Color(5.0f);
    light.cos_inner = std::cos(0.2f);
    light.cos_outer = std::cos(0.5f);
    const Scene scene = scene_with({light}, false);
    const LightSet lights(scene);
    const int cos_bins = 10, phi_bins = 12;
    std::vector<double> observed(cos_bins * phi_bins, 0.0), expected(observed.size(), double(kSamples) / observed.size());
    DVec3 flux(0.0);
    Rng rng(3, 4);
    const Frame frame(light.direction);
    for (int i = 0; i < kSamples; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2());
        ASSERT_TRUE(e.has_value());
        ASSERT_GE(glm::dot(e->direction, light.direction), light.cos_outer - 1e-5f);
        observed[direction_bin(e->direction, frame, cos_bins, phi_bins, light.cos_outer)] += 1.0;
        flux += DVec3(e->flux_weight);
    }
    EXPECT_GT(chi_square_p_value(observed, expected), kSignificance);
    EXPECT_NEAR(flux.x / kSamples, lights.power(0).x, 0.01 * lights.power(0).x);
}

TEST(Emission, DirectionalLightOriginsAreUniformOnADiscCoveringTheScene) {
    PunctualLight light;
    light.type = PunctualLightType::Directional;
    light.direction = glm::normalize(Vec3(0.0f, -1.0f, -1.0f));
    light.intensity = Color(2.0f);
    const Scene scene = scene_with({light}, false);
    const LightSet lights(scene);
    const Vec3 center = scene.bounds.center();
    const float radius = scene.bounds.radius();
    const Frame frame(light.direction);
    const int r_bins = 8, phi_bins = 16;
    std::vector<double> observed(r_bins * phi_bins, 0.0), expected(observed.size(), double(kSamples) / observed.size());
    Rng rng(5, 6);
    for (int i = 0; i < kSamples; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2());
        ASSERT_TRUE(e.has_value());
        EXPECT_EQ(e->direction, light.direction);
        const Vec3 l = frame.to_local(e->origin - center);
        EXPECT_LT(l.z, -radius);  // the disc lies before the scene, facing it
        const float r2 = (l.x * l.x + l.y * l.y) / (radius * radius);  // uniform area: r^2 uniform
        ASSERT_LE(r2, 1.0001f);
        float phi = std::atan2(l.y, l.x);
        if (phi < 0.0f) phi += 2.0f * kPi;
        const int rb = std::min(static_cast<int>(r2 * r_bins), r_bins - 1);
        const int pb = std::min(static_cast<int>(phi / (2.0f * kPi) * phi_bins), phi_bins - 1);
        observed[static_cast<size_t>(rb * phi_bins + pb)] += 1.0;
    }
    EXPECT_GT(chi_square_p_value(observed, expected), kSignificance);
}

void check_triangle_emission(bool double_sided) {
    const Scene scene = scene_with({}, true, double_sided);
    const LightSet lights(scene);
    ASSERT_EQ(lights.size(), 1u);
    // Origins: uniform on the triangle (0,0,1), (2,0,1), (0,1,1): bin by the barycentric grid of
    // a 4 x 4 subdivision (16 equal-area sub-triangles). Directions: cosine-weighted about the
    // emitting face: cos^2 theta is uniform.
    const int n = 4;
    std::vector<double> origin_observed(n * n, 0.0), origin_expected(n * n, double(kSamples) / (n * n));
    const int cos_bins = 10, phi_bins = 12;
    std::vector<double> dir_observed(cos_bins * phi_bins * 2, 0.0);
    std::vector<double> dir_expected(dir_observed.size(), 0.0);
    for (size_t i = 0; i < dir_expected.size(); ++i) {
        const bool back = i >= static_cast<size_t>(cos_bins * phi_bins);
        dir_expected[i] = double(kSamples) / (cos_bins * phi_bins) * (double_sided ? 0.5 : (back ? 0.0 : 1.0));
    }
    DVec3 flux(0.0);
    Rng rng(7, 8);
    for (int i = 0; i < kSamples; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2());
        ASSERT_TRUE(e.has_value());
        const float u = e->origin.x / 2.0f, v = e->origin.y;  // barycentrics of vertices 1 and 2
        ASSERT_NEAR(e->origin.z, 1.0f, 1e-6f);
        ASSERT_LE(u + v, 1.0f + 1e-5f);
        // Sub-triangle index in the n x n subdivision (row by v, then position within the row).
        const int row = std::min(static_cast<int>(v * n), n - 1);
        const float uu = u * n, vv = v * n - row;
        const int col = std::min(static_cast<int>(uu), n - 1 - row);
        const bool upper = (uu - col) + vv > 1.0f && col < n - 1 - row;
        // Row r holds 2 (n - r) - 1 sub-triangles; the rows before it 2 n r - r^2.
        const int index = 2 * n * row - row * row + 2 * col + (upper ? 1 : 0);
        origin_observed[static_cast<size_t>(index)] += 1.0;
        const bool back = e->direction.z < 0.0f;
        const float c2 = sqr(std::abs(e->direction.z));
        float phi = std::atan2(e->direction.y, e->direction.x);
        if (phi < 0.0f) phi += 2.0f * kPi;
        const int cb = std::min(static_cast<int>(c2 * cos_bins), cos_bins - 1);
        const int pb = std::min(static_cast<int>(phi / (2.0f * kPi) * phi_bins), phi_bins - 1);
        dir_observed[static_cast<size_t>((back ? cos_bins * phi_bins : 0) + cb * phi_bins + pb)] += 1.0;
        flux += DVec3(e->flux_weight);
    }
    // Origins: the index scheme above maps the 16 sub-triangles onto 16 bins of equal area.
    EXPECT_GT(chi_square_p_value(origin_observed, origin_expected), kSignificance) << "origins";
    EXPECT_GT(chi_square_p_value(dir_observed, dir_expected), kSignificance) << "directions";
    const double area = 1.0;
    EXPECT_NEAR(flux.x / kSamples, (double_sided ? 2.0 : 1.0) * kPi * 2.0 * area, 1e-3);
}

TEST(Emission, EmissiveTriangleOriginsUniformDirectionsCosineWeighted) { check_triangle_emission(false); }
TEST(Emission, DoubleSidedEmissiveTriangleEmitsFromBothFaces) { check_triangle_emission(true); }

TEST(Emission, LightsAreChosenByPower) {
    PunctualLight weak, strong;
    weak.position = Vec3(0.0f);
    weak.intensity = Color(1.0f);
    strong.position = Vec3(1.0f);
    strong.intensity = Color(3.0f);
    const Scene scene = scene_with({weak, strong}, false);
    const LightSet lights(scene);
    EXPECT_NEAR(lights.selection_probability(0), 0.25f, 1e-6f);
    EXPECT_NEAR(lights.selection_probability(1), 0.75f, 1e-6f);
    int strong_count = 0;
    DVec3 flux(0.0);
    Rng rng(9, 10);
    for (int i = 0; i < kSamples; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2());
        strong_count += e->light == 1;
        flux += DVec3(e->flux_weight);
    }
    EXPECT_NEAR(double(strong_count) / kSamples, 0.75, 0.005);
    // Every photon carries about the same flux: the total over the count.
    EXPECT_NEAR(flux.x / kSamples, lights.total_power().x, 1e-3 * lights.total_power().x);
}

}  // namespace
}  // namespace photond
