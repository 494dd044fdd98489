// The light tree (core/light/light_tree.h) and next-event estimation's light choice
// (LightSelection): pmfs that sum to one, sampled frequencies against the pmf (chi-square), a
// pdf for MIS equal to the sample's, no light that can reach a point left out, and estimates of
// irradiance from many lights that agree with a brute-force integral, with less variance than
// choosing by power.
#include <gtest/gtest.h>

#include "core/light/light_set.h"
#include "core/math/rng.h"
#include "core/math/sampling.h"
#include "core/scene/shapes.h"
#include "tests/support/chi_square.h"

namespace photond {
namespace {

using test_support::chi_square_p_value;

Vec3 random_direction(Rng& rng) { return sample_uniform_sphere(rng.next_vec2()); }

/// A mix of point lights, spots and one- and two-sided triangles in a 20-unit cube, of
/// intensities over three decades.
std::vector<LightBounds> random_lights(int count, uint64_t seed) {
    Rng rng(seed, 1);
    std::vector<LightBounds> lights;
    for (int i = 0; i < count; ++i) {
        LightBounds b;
        const Vec3 center = 20.0f * Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 10.0f;
        b.intensity = std::pow(10.0f, 3.0f * rng.next_float());
        switch (i % 4) {
            case 0:  // point
                b.bounds.extend(center);
                b.cos_theta_o = -1.0f;
                break;
            case 1:  // spot
                b.bounds.extend(center);
                b.w = random_direction(rng);
                b.cos_theta_o = std::cos(0.2f + rng.next_float());
                b.cos_theta_e = std::cos(0.01f);
                break;
            default: {  // triangle, one- or two-sided
                for (int v = 0; v < 3; ++v) b.bounds.extend(center + 0.5f * random_direction(rng));
                b.w = random_direction(rng);
                b.cos_theta_o = 1.0f;
                b.cos_theta_e = 0.0f;
                b.two_sided = i % 4 == 3;
                break;
            }
        }
        lights.push_back(b);
    }
    return lights;
}

TEST(LightTree, PmfEqualsTheSamplesProbabilityAndSumsToOneForLightsThatShineEverywhere) {
    // Point lights reach every point: their pmfs sum to one. Oriented lights may leave a node
    // that can reach p with children that cannot (a dead end: no sample, pbrt-v4's behaviour),
    // so the sum is at most one, and exactly the chance that a sample finds a light.
    std::vector<LightBounds> points = random_lights(300, 7);
    for (LightBounds& b : points) {
        b.bounds = Bounds3{};
        b.bounds.extend(Vec3(3.0f * b.intensity, 0.0f, 0.0f));
        b.cos_theta_o = -1.0f;
        b.cos_theta_e = 0.0f;
        b.two_sided = false;
    }
    for (const std::vector<LightBounds>& lights : {points, random_lights(300, 7)}) {
        const LightTree tree(lights);
        ASSERT_EQ(tree.light_count(), lights.size());
        EXPECT_EQ(tree.node_count(), 2 * lights.size() - 1);
        EXPECT_LT(tree.depth(), 40);
        Rng rng(3, 4);
        for (int point = 0; point < 50; ++point) {
            const Vec3 p = 24.0f * Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 12.0f;
            double sum = 0.0;
            for (uint32_t l = 0; l < lights.size(); ++l) sum += tree.pmf(p, l);
            if (&lights != &points) {
                EXPECT_LE(sum, 1.0 + 1e-5) << "point " << point;
                EXPECT_GT(sum, 0.5) << "point " << point;
            }
            for (int s = 0; s < 200; ++s) {
                float pmf = 0.0f;
                const std::optional<uint32_t> light = tree.sample(p, rng.next_float(), &pmf);
                if (light) {
                    EXPECT_EQ(pmf, tree.pmf(p, *light)) << "point " << point << ", light " << *light;
                }
            }
        }
        if (&lights == &points) {
            for (int point = 0; point < 20; ++point) {
                const Vec3 p = 24.0f * Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 12.0f;
                double sum = 0.0;
                for (uint32_t l = 0; l < lights.size(); ++l) sum += tree.pmf(p, l);
                EXPECT_NEAR(sum, 1.0, 1e-5) << "point " << point;
            }
        }
    }
}

TEST(LightTree, SampledFrequenciesFollowThePmf) {
    const std::vector<LightBounds> lights = random_lights(120, 11);
    const LightTree tree(lights);
    Rng rng(5, 6);
    constexpr int kPoints = 6, kSamples = 400000;
    for (int point = 0; point < kPoints; ++point) {
        const Vec3 p = 20.0f * Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 10.0f;
        // One cell per light and one for "no light" (a dead end).
        std::vector<double> observed(lights.size() + 1, 0.0), expected(lights.size() + 1, 0.0);
        double sum = 0.0;
        for (uint32_t l = 0; l < lights.size(); ++l) {
            expected[l] = kSamples * double(tree.pmf(p, l));
            sum += tree.pmf(p, l);
        }
        expected.back() = kSamples * std::max(0.0, 1.0 - sum);
        for (int s = 0; s < kSamples; ++s) {
            float pmf = 0.0f;
            const std::optional<uint32_t> light = tree.sample(p, rng.next_float(), &pmf);
            observed[light ? *light : lights.size()] += 1.0;
        }
        EXPECT_GT(chi_square_p_value(observed, expected), 1e-3 / kPoints) << "point " << point;
    }
}

TEST(LightTree, EveryLightThatCanReachAPointKeepsAPositiveProbability) {
    // The nodes' bounds and cones must hold their lights': a light whose own importance at p is
    // positive may not sit under a node whose importance is zero.
    const std::vector<LightBounds> lights = random_lights(400, 13);
    const LightTree tree(lights);
    Rng rng(8, 9);
    int reachable = 0, unreachable = 0;
    for (int point = 0; point < 200; ++point) {
        const Vec3 p = 24.0f * Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 12.0f;
        for (uint32_t l = 0; l < lights.size(); ++l) {
            const bool can_reach = light_importance(lights[l], p) > 0.0f;
            (can_reach ? reachable : unreachable) += 1;
            if (can_reach) {
                ASSERT_GT(tree.pmf(p, l), 0.0f) << "light " << l << " at point " << point;
            } else {
                ASSERT_EQ(tree.pmf(p, l), 0.0f) << "light " << l << " at point " << point;
            }
        }
    }
    EXPECT_GT(unreachable, 1000);  // the one-sided triangles and spots turned away
    EXPECT_GT(reachable, 10000);
}

TEST(LightTree, ImportanceFollowsDistanceIntensityAndOrientation) {
    LightBounds near_point, far_point;
    near_point.bounds.extend(Vec3(0.0f, 1.0f, 0.0f));
    near_point.intensity = 1.0f;
    near_point.cos_theta_o = -1.0f;
    far_point = near_point;
    far_point.bounds = Bounds3{};
    far_point.bounds.extend(Vec3(0.0f, 10.0f, 0.0f));
    EXPECT_NEAR(light_importance(near_point, Vec3(0.0f)), 1.0f, 1e-6f);
    EXPECT_NEAR(light_importance(far_point, Vec3(0.0f)), 0.01f, 1e-8f);
    const LightTree tree(std::vector<LightBounds>{near_point, far_point});
    EXPECT_NEAR(tree.pmf(Vec3(0.0f), 0), 100.0f / 101.0f, 1e-6f);
    // A one-sided triangle facing down at y = 2: nothing above it, full strength below.
    LightBounds triangle;
    for (const Vec3& v : {Vec3(-0.1f, 2.0f, -0.1f), Vec3(0.1f, 2.0f, -0.1f), Vec3(0.0f, 2.0f, 0.1f)})
        triangle.bounds.extend(v);
    triangle.intensity = 1.0f;
    triangle.w = Vec3(0.0f, -1.0f, 0.0f);
    triangle.cos_theta_o = 1.0f;
    triangle.cos_theta_e = 0.0f;
    EXPECT_GT(light_importance(triangle, Vec3(0.0f)), 0.2f);
    EXPECT_EQ(light_importance(triangle, Vec3(0.0f, 4.0f, 0.0f)), 0.0f);
    triangle.two_sided = true;
    EXPECT_GT(light_importance(triangle, Vec3(0.0f, 4.0f, 0.0f)), 0.2f);
}

TEST(LightTree, UnionBoundsBothConesAndBoxes) {
    Rng rng(21, 22);
    for (int i = 0; i < 2000; ++i) {
        LightBounds a, b;
        a.bounds.extend(Vec3(rng.next_float(), 0.0f, 0.0f));
        b.bounds.extend(Vec3(0.0f, rng.next_float(), 2.0f));
        a.intensity = b.intensity = 1.0f;
        a.w = random_direction(rng);
        b.w = random_direction(rng);
        a.cos_theta_o = std::cos(kPi * rng.next_float());
        b.cos_theta_o = std::cos(kPi * rng.next_float());
        const LightBounds u = light_bounds_union(a, b);
        EXPECT_EQ(u.intensity, 2.0f);
        if (u.cos_theta_o <= -1.0f) continue;  // the whole sphere holds anything
        // Each cone's axis, and its rim, lie within the union's cone.
        for (const LightBounds* c : {&a, &b}) {
            const float angle_to_axis = std::acos(std::clamp(glm::dot(u.w, c->w), -1.0f, 1.0f));
            const float half = std::acos(c->cos_theta_o);
            EXPECT_LE(angle_to_axis + half, std::acos(std::max(u.cos_theta_o, -1.0f)) + 1e-3f) << i;
            EXPECT_LE(u.bounds.lower.x, c->bounds.lower.x);
            EXPECT_GE(u.bounds.upper.z, c->bounds.upper.z);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// LightSet: next-event estimation with the tree against power

Material emitter(const Color& radiance, bool double_sided) {
    Material m;
    m.base_color = Color(0.0f);
    m.emission = radiance;
    m.double_sided = double_sided;
    return m;
}

/// A floor of small emitting squares facing up and down at varied heights and radiances over
/// three decades, and a few point lights: many lights where distance decides.
Scene many_lights_scene() {
    SceneBuilder builder("many-lights");
    Rng rng(31, 32);
    for (int i = 0; i < 12; ++i) {
        for (int j = 0; j < 12; ++j) {
            const float radiance = std::pow(10.0f, 3.0f * rng.next_float() - 1.0f);
            const uint32_t m = builder.add_material(emitter(Color(radiance, 0.8f * radiance, 0.6f * radiance), i % 5 == 0));
            const Vec3 corner(2.0f * i - 12.0f, 1.0f + 3.0f * rng.next_float(), 2.0f * j - 12.0f);
            const Vec3 facing = (i + j) % 3 == 0 ? Vec3(0.0f, 1.0f, 0.0f) : Vec3(0.0f, -1.0f, 0.0f);
            EXPECT_TRUE(add_mesh(builder, make_quad(corner, Vec3(0.3f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.3f), facing), m)
                            .is_ok());
        }
    }
    for (int k = 0; k < 6; ++k) {
        PunctualLight l;
        l.position = Vec3(8.0f * k - 20.0f, 2.0f, 3.0f);
        l.intensity = Color(0.5f + k);
        builder.add_light(l);
    }
    return builder.build().value();
}

/// The triangle whose plane and edges hold q (the sample's light point).
int triangle_holding(const Scene& scene, const Vec3& q) {
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        const Vec3 a = scene.positions[scene.triangles[t].x], b = scene.positions[scene.triangles[t].y],
                   c = scene.positions[scene.triangles[t].z];
        const Vec3 n = glm::cross(b - a, c - a);
        if (std::abs(glm::dot(q - a, glm::normalize(n))) > 1e-4f) continue;
        const float w0 = glm::dot(glm::cross(b - a, q - a), n), w1 = glm::dot(glm::cross(c - b, q - b), n),
                    w2 = glm::dot(glm::cross(a - c, q - c), n);
        if (w0 >= -1e-7f && w1 >= -1e-7f && w2 >= -1e-7f) return static_cast<int>(t);
    }
    return -1;
}

TEST(LightSelection, ChoiceProbabilitiesSumToAtMostOneAndMisPdfEqualsTheSamplesPdf) {
    const Scene scene = many_lights_scene();
    for (const LightSelection selection : {LightSelection::Tree, LightSelection::Power}) {
        const LightSet lights(scene, selection);
        ASSERT_EQ(lights.selection(), selection);
        EXPECT_EQ(lights.tree().empty(), selection == LightSelection::Power);
        Rng rng(41, 42);
        for (int point = 0; point < 20; ++point) {
            const Vec3 p(24.0f * rng.next_float() - 12.0f, 4.0f * rng.next_float(), 24.0f * rng.next_float() - 12.0f);
            double sum = 0.0;
            for (uint32_t l = 0; l < lights.size(); ++l) sum += lights.incident_choice_probability(l, p);
            if (selection == LightSelection::Power) {
                EXPECT_NEAR(sum, 1.0, 1e-4);
            }
            EXPECT_LE(sum, 1.0 + 1e-5);  // the tree's dead ends (see LightTree's tests)
            EXPECT_GT(sum, 0.5);
            for (int s = 0; s < 50; ++s) {
                const std::optional<LightSample> ls = lights.sample_incident(p, rng.next_float(), rng.next_vec2());
                if (!ls || ls->is_delta) continue;
                const int t = triangle_holding(scene, ls->point);
                ASSERT_GE(t, 0);
                EXPECT_NEAR(lights.pdf_incident_triangle(static_cast<uint32_t>(t), p, ls->point), ls->pdf,
                            2e-4f * ls->pdf);
            }
        }
    }
}

TEST(LightSelection, ASetSharingAnotherSetsSceneLightsChoosesAsOneBuiltAlone) {
    // RenderScene's second set (the sky's peaks in place of the sky) takes the first one's
    // emitters and tree: its choices must be those of a set made from the scene alone.
    const Scene scene = many_lights_scene();
    Environment sky, peaks;
    sky.color = Color(0.2f);
    peaks.color = Color(3.0f, 2.0f, 1.0f);
    for (const LightSelection selection : {LightSelection::Tree, LightSelection::Power}) {
        const LightSet first(scene, &sky, selection);
        const LightSet shared(scene, &peaks, selection, first);
        const LightSet alone(scene, &peaks, selection);
        ASSERT_EQ(shared.size(), alone.size());
        EXPECT_EQ(shared.total_power(), alone.total_power());
        Rng rng(43, 44);
        for (int point = 0; point < 20; ++point) {
            const Vec3 p(24.0f * rng.next_float() - 12.0f, 4.0f * rng.next_float(), 24.0f * rng.next_float() - 12.0f);
            for (uint32_t l = 0; l < alone.size(); ++l)
                ASSERT_EQ(shared.incident_choice_probability(l, p), alone.incident_choice_probability(l, p))
                    << "light " << l;
            const float u = rng.next_float();
            const Vec2 u2 = rng.next_vec2();
            const std::optional<LightSample> a = shared.sample_incident(p, u, u2), b = alone.sample_incident(p, u, u2);
            ASSERT_EQ(a.has_value(), b.has_value());
            if (a) {
                EXPECT_EQ(a->pdf, b->pdf);
            }
        }
        for (uint32_t l = 0; l < alone.size(); ++l) EXPECT_EQ(shared.selection_probability(l), alone.selection_probability(l));
        // Photons leave both alike (the flux weights are this set's own, by its choice).
        for (int k = 0; k < 200; ++k) {
            const float u = rng.next_float();
            const Vec2 u_position = rng.next_vec2(), u_direction = rng.next_vec2();
            const std::optional<EmissionSample> a = shared.sample_emission(u, u_position, u_direction);
            const std::optional<EmissionSample> b = alone.sample_emission(u, u_position, u_direction);
            ASSERT_EQ(a.has_value(), b.has_value());
            if (!a) continue;
            EXPECT_EQ(a->light, b->light);
            EXPECT_EQ(a->flux_weight, b->flux_weight) << "light " << a->light;
        }
    }
}

/// Irradiance at p (normal n) from every light without occlusion: the triangles integrated on
/// a fine grid of sub-triangles, the point lights exactly.
double brute_force_irradiance(const Scene& scene, const Vec3& p, const Vec3& n) {
    double e = 0.0;
    constexpr int kGrid = 24;
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        const Material& m = scene.materials[scene.triangle_materials[t]];
        const Vec3 a = scene.positions[scene.triangles[t].x], b = scene.positions[scene.triangles[t].y],
                   c = scene.positions[scene.triangles[t].z];
        const Vec3 normal = scene.triangle_normal(t);
        const double cell_area = scene.triangle_area(t) / (kGrid * kGrid);
        for (int i = 0; i < kGrid; ++i) {
            for (int j = 0; i + j < kGrid; ++j) {
                for (int upper = 0; upper < 2; ++upper) {
                    if (upper && i + j + 1 >= kGrid) continue;
                    const float o = upper ? 2.0f / 3.0f : 1.0f / 3.0f;
                    const float u = (i + o) / kGrid, v = (j + o) / kGrid;
                    const Vec3 q = a + u * (b - a) + v * (c - a);
                    const Vec3 d = q - p;
                    const double d2 = glm::dot(d, d);
                    const Vec3 wi = d / std::sqrt(static_cast<float>(d2));
                    double cos_light = -glm::dot(wi, normal);
                    if (m.double_sided) cos_light = std::abs(cos_light);
                    const double cos_receiver = glm::dot(wi, n);
                    if (cos_light <= 0.0 || cos_receiver <= 0.0) continue;
                    e += average(m.emission) * cos_light * cos_receiver / d2 * cell_area;
                }
            }
        }
    }
    for (const PunctualLight& l : scene.lights) {
        const Vec3 d = l.position - p;
        const double d2 = glm::dot(d, d);
        const double cos_receiver = glm::dot(glm::normalize(d), n);
        if (cos_receiver > 0.0) e += average(l.intensity) * cos_receiver / d2;
    }
    return e;
}

TEST(LightSelection, TreeAndPowerEstimateTheBruteForceIrradianceAndTheTreeWithLessVariance) {
    const Scene scene = many_lights_scene();
    const LightSet tree(scene, LightSelection::Tree), power(scene, LightSelection::Power);
    constexpr int kSamples = 200000;
    double variance_ratio_sum = 0.0;
    const Vec3 points[] = {{-9.0f, 0.0f, -9.0f}, {0.5f, 0.0f, 0.5f}, {6.0f, 0.0f, -3.0f}, {10.0f, 0.0f, 10.0f}};
    const Vec3 up(0.0f, 1.0f, 0.0f);
    for (const Vec3& p : points) {
        const double expected = brute_force_irradiance(scene, p, up);
        double variance[2];
        int which = 0;
        for (const LightSet* lights : {&tree, &power}) {
            Rng rng(51, 52);
            double sum = 0.0, sum2 = 0.0;
            for (int s = 0; s < kSamples; ++s) {
                const std::optional<LightSample> ls = lights->sample_incident(p, rng.next_float(), rng.next_vec2());
                double value = 0.0;
                if (ls && ls->pdf > 0.0f) value = average(ls->radiance) * std::max(0.0f, glm::dot(ls->wi, up)) / ls->pdf;
                sum += value;
                sum2 += value * value;
            }
            const double mean = sum / kSamples;
            variance[which] = sum2 / kSamples - mean * mean;
            const double standard_error = std::sqrt(variance[which] / kSamples);
            EXPECT_NEAR(mean, expected, 5.0 * standard_error + 2e-3 * expected)
                << (which == 0 ? "tree" : "power") << " at (" << p.x << ", " << p.z << ")";
            ++which;
        }
        variance_ratio_sum += variance[1] / variance[0];
        std::printf("[ info ] at (%5.1f, %5.1f): E = %.4f, variance power / tree = %.1f\n", p.x, p.z, expected,
                    variance[1] / variance[0]);
    }
    EXPECT_GT(variance_ratio_sum / 4.0, 3.0);
}

TEST(LightSelection, OneLightIsChosenWithProbabilityOne) {
    SceneBuilder builder("one-light");
    const uint32_t m = builder.add_material(emitter(Color(5.0f), false));
    const Vec3 positions[3] = {{0, 2, 0}, {1, 2, 0}, {0, 2, 1}};
    const glm::uvec3 triangle[1] = {{0, 2, 1}};  // facing down
    ASSERT_TRUE(builder.add_mesh(positions, {}, {}, triangle, m).is_ok());
    const Scene scene = builder.build().value();
    const LightSet lights(scene);
    for (const Vec3& p : {Vec3(0.2f, 0.0f, 0.2f), Vec3(0.2f, 5.0f, 0.2f)}) {
        EXPECT_EQ(lights.incident_choice_probability(0, p), 1.0f);
    }
}

}  // namespace
}  // namespace photond
