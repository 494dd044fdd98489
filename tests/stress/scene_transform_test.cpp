// transform_scene: what moves, what scales and what stays, so that a transformed scene is "the
// same scene" (core/scene/scene_transform.h).
#include "core/scene/scene_transform.h"

#include <gtest/gtest.h>

#include "core/light/light_set.h"
#include "tests/stress/stress_support.h"

namespace photond {
namespace {

void expect_near(const Vec3& actual, const Vec3& expected, float relative = 1e-6f) {
    const float tolerance = relative * std::max(1.0f, max_abs_component(expected));
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

/// The test room plus a point, a spot and a directional light.
Scene room_with_punctual_lights() {
    return stress::make_room({},
                             [](SceneBuilder& builder, const stress::RoomMaterials&) {
                                 PunctualLight point;
                                 point.name = "point";
                                 point.position = Vec3(0.2f, 1.5f, -0.3f);
                                 point.intensity = Color(3.0f, 2.0f, 1.0f);
                                 builder.add_light(point);
                                 PunctualLight spot = point;
                                 spot.name = "spot";
                                 spot.type = PunctualLightType::Spot;
                                 spot.direction = Vec3(0.0f, -1.0f, 0.0f);
                                 spot.cos_inner = 0.9f;
                                 spot.cos_outer = 0.8f;
                                 builder.add_light(spot);
                                 PunctualLight sun;
                                 sun.name = "sun";
                                 sun.type = PunctualLightType::Directional;
                                 sun.direction = glm::normalize(Vec3(0.3f, -1.0f, 0.2f));
                                 sun.intensity = Color(2.0f);
                                 builder.add_light(sun);
                                 return Status::ok();
                             })
        .value();
}

TEST(SceneTransform, IdentityKeepsEverything) {
    const Scene scene = room_with_punctual_lights();
    const Scene same = transform_scene(scene, {}).value();
    EXPECT_EQ(same.positions, scene.positions);
    EXPECT_EQ(same.normals, scene.normals);
    EXPECT_EQ(same.triangles, scene.triangles);
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        EXPECT_EQ(same.lights[i].position, scene.lights[i].position);
        EXPECT_EQ(same.lights[i].intensity, scene.lights[i].intensity);
    }
    EXPECT_EQ(same.cameras[0].position, scene.cameras[0].position);
    EXPECT_EQ(same.bounds.lower, scene.bounds.lower);
    EXPECT_EQ(same.bounds.upper, scene.bounds.upper);
}

TEST(SceneTransform, PositionsMoveNormalsStayPointIntensitiesScaleBySquare) {
    const Scene scene = room_with_punctual_lights();
    const SimilarityTransform t{2.5, DVec3(10.0, -20.0, 30.0)};
    const Scene moved = transform_scene(scene, t).value();
    ASSERT_EQ(moved.positions.size(), scene.positions.size());
    for (size_t i = 0; i < scene.positions.size(); ++i) {
        expect_near(moved.positions[i], 2.5f * scene.positions[i] + Vec3(10.0f, -20.0f, 30.0f));
        EXPECT_EQ(moved.normals[i], scene.normals[i]);
    }
    for (uint32_t i = 0; i < scene.triangles.size(); ++i) {
        expect_near(moved.triangle_normal(i), scene.triangle_normal(i), 1e-5f);
        EXPECT_NEAR(moved.triangle_area(i), 6.25f * scene.triangle_area(i),
                    1e-4f * scene.triangle_area(i) + 1e-12f);
    }
    expect_near(moved.bounds.lower, 2.5f * scene.bounds.lower + Vec3(10.0f, -20.0f, 30.0f));
    expect_near(moved.bounds.upper, 2.5f * scene.bounds.upper + Vec3(10.0f, -20.0f, 30.0f));
    // Materials (radiance, reflectance) are untouched.
    for (size_t i = 0; i < scene.materials.size(); ++i)
        EXPECT_EQ(moved.materials[i].emission, scene.materials[i].emission);
    // Point and spot: position moved, intensity times s^2; directional: unchanged.
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        SCOPED_TRACE(scene.lights[i].name);
        const PunctualLight& before = scene.lights[i];
        const PunctualLight& after = moved.lights[i];
        EXPECT_EQ(after.direction, before.direction);
        if (before.type == PunctualLightType::Directional) {
            EXPECT_EQ(after.intensity, before.intensity);
        } else {
            expect_near(after.position, t.apply(before.position));
            expect_near(after.intensity, 6.25f * before.intensity);
        }
    }
    // The camera: position and target moved, up and field of view kept.
    expect_near(moved.cameras[0].position, t.apply(scene.cameras[0].position));
    expect_near(moved.cameras[0].look_at, t.apply(scene.cameras[0].look_at));
    EXPECT_EQ(moved.cameras[0].up, scene.cameras[0].up);
    EXPECT_EQ(moved.cameras[0].vfov_deg, scene.cameras[0].vfov_deg);
}

TEST(SceneTransform, IncidentRadianceAtCorrespondingPointsIsUnchanged) {
    // I / d^2 with I scaled by s^2 and d by s: each punctual light's incident radiance at a
    // transformed point equals the original's; and so does an area light's radiance.
    const Scene scene = room_with_punctual_lights();
    for (const double s : {1e-3, 1e3, 1e5}) {
        SCOPED_TRACE("scale " + std::to_string(s));
        const SimilarityTransform t{s, DVec3(0.5 * s, 0.0, -0.25 * s)};
        const Scene moved = transform_scene(scene, t).value();
        const LightSet before(scene), after(moved);
        ASSERT_EQ(before.size(), after.size());
        const Vec3 p(0.1f, 0.0f, 0.2f);
        for (uint32_t light = 0; light < before.size(); ++light) {
            // Pick each light in turn: u_select at the middle of its selection interval.
            float cdf = 0.0f;
            for (uint32_t j = 0; j < light; ++j) cdf += before.selection_probability(j);
            const float u = cdf + 0.5f * before.selection_probability(light);
            const std::optional<LightSample> a = before.sample_incident(p, u, Vec2(0.3f, 0.6f));
            const std::optional<LightSample> b =
                after.sample_incident(t.apply(p), u, Vec2(0.3f, 0.6f));
            ASSERT_EQ(a.has_value(), b.has_value());
            if (!a) continue;
            expect_near(b->radiance, a->radiance, 1e-4f);
            expect_near(b->wi, a->wi, 1e-4f);
        }
    }
}

}  // namespace
}  // namespace photond
