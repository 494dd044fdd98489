// Surface interactions: a flat-shaded triangle (its vertices share one normal) takes that normal
// as it is, a smooth one interpolates and normalises, and either is turned onto the side of the
// geometric normal.
#include <gtest/gtest.h>

#include <vector>

#include "core/scene/interaction.h"

namespace photond {
namespace {

const std::vector<Vec3> kPositions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}};
const std::vector<glm::uvec3> kTriangle = {{0, 1, 2}};

Scene scene_with_normals(const std::vector<Vec3>& normals) {
    SceneBuilder builder("interaction");
    Material m;
    m.name = "white";
    const uint32_t material = builder.add_material(m);
    EXPECT_TRUE(builder.add_mesh(kPositions, normals, {}, kTriangle, material));
    return builder.build().value();
}

// The hit at barycentrics (u, v) of a ray coming down onto the front face (+z).
SurfaceInteraction hit_at(const Scene& scene, float u, float v) {
    return make_interaction(scene, Hit{1.0f, 0, u, v}, Vec3(0.0f, 0.0f, -1.0f));
}

TEST(Interaction, FlatTriangleTakesItsVerticesNormal) {
    const Vec3 n = glm::normalize(Vec3(0.3f, -0.2f, 1.0f));
    const Scene scene = scene_with_normals({n, n, n});
    ASSERT_EQ(scene.flat_shaded.size(), 1u);
    EXPECT_EQ(scene.flat_shaded[0], 1);
    for (const Vec2 b : {Vec2(0.1f, 0.2f), Vec2(0.7f, 0.29f), Vec2(1e-7f, 0.0f)}) {
        const SurfaceInteraction si = hit_at(scene, b.x, b.y);
        // Exactly the stored vertex normal, not a re-normalised interpolation of it.
        EXPECT_EQ(si.shading_normal, scene.normals[0]) << b.x << " " << b.y;
    }
}

TEST(Interaction, GeneratedFlatNormalsAreFlatShaded) {
    const Scene scene = scene_with_normals({});
    EXPECT_EQ(scene.flat_shaded[0], 1);
    EXPECT_EQ(hit_at(scene, 0.25f, 0.25f).shading_normal, Vec3(0.0f, 0.0f, 1.0f));
}

TEST(Interaction, InvertedFlatNormalIsTurnedToTheGeometricSide) {
    const Scene scene = scene_with_normals({Vec3(0.0f, 0.0f, -1.0f), Vec3(0.0f, 0.0f, -1.0f), Vec3(0.0f, 0.0f, -1.0f)});
    EXPECT_EQ(scene.flat_shaded[0], 1);
    EXPECT_EQ(hit_at(scene, 0.25f, 0.25f).shading_normal, Vec3(0.0f, 0.0f, 1.0f));
}

TEST(Interaction, ZeroFlatNormalFallsBackToTheGeometricNormal) {
    const Scene scene = scene_with_normals({Vec3(0.0f), Vec3(0.0f), Vec3(0.0f)});
    EXPECT_EQ(scene.flat_shaded[0], 1);
    EXPECT_EQ(hit_at(scene, 0.25f, 0.25f).shading_normal, Vec3(0.0f, 0.0f, 1.0f));
}

TEST(Interaction, SmoothTriangleInterpolatesItsNormals) {
    const std::vector<Vec3> normals = {glm::normalize(Vec3(-0.5f, -0.5f, 1.0f)), glm::normalize(Vec3(0.5f, 0.0f, 1.0f)),
                                       glm::normalize(Vec3(0.0f, 0.5f, 1.0f))};
    const Scene scene = scene_with_normals(normals);
    EXPECT_EQ(scene.flat_shaded[0], 0);
    const float u = 0.2f, v = 0.5f;
    const Vec3 expected = glm::normalize((1.0f - u - v) * normals[0] + u * normals[1] + v * normals[2]);
    const Vec3 shading = hit_at(scene, u, v).shading_normal;
    EXPECT_NEAR(glm::length(shading - expected), 0.0f, 1e-6f);
    EXPECT_GT(glm::length(shading - normals[0]), 0.1f);  // really interpolated
}

}  // namespace
}  // namespace photond
