#include "core/shading/render_scene.h"

#include <gtest/gtest.h>

#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

std::shared_ptr<const RenderScene> render_scene(const std::string& name) {
    auto scene = std::make_shared<const Scene>(make_builtin_scene(name).value());
    return RenderScene::create(EmbreeDevice::create().value(), scene).value();
}

TEST(RenderScene, CausticCastersAreExactlyTheSpecularTriangles) {
    const auto rs = render_scene("cornell-box");
    ASSERT_NE(rs->caustic_casters, nullptr);
    const Scene& scene = *rs->scene;
    const float d = 1e-2f * max_component(scene.bounds.extent());
    int specular = 0, diffuse = 0;
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        const glm::uvec3& tri = scene.triangles[t];
        const Vec3 centroid = (scene.positions[tri.x] + scene.positions[tri.y] + scene.positions[tri.z]) / 3.0f;
        const Vec3 n = scene.triangle_normal(t);
        if (glm::dot(n, n) == 0.0f) continue;
        // Head-on at the centroid from a little way off the surface, stopping just past it.
        Ray ray{centroid + d * n, -n};
        ray.tmin = 0.9f * d;
        ray.tmax = 1.1f * d;
        const bool is_specular = (rs->bsdf_materials[scene.triangle_materials[t]].other_lobes &
                                  (mask_of(LobeKind::Delta) | mask_of(LobeKind::Glossy))) != 0;
        if (is_specular) {
            ++specular;
            EXPECT_TRUE(rs->caustic_casters->occluded(ray)) << "specular triangle " << t << " is missing";
        } else {
            ++diffuse;
            EXPECT_FALSE(rs->caustic_casters->occluded(ray)) << "diffuse triangle " << t << " is among the casters";
        }
    }
    EXPECT_GT(specular, 100);       // the two tessellated spheres
    EXPECT_GT(diffuse, 10);         // the box
}

TEST(RenderScene, NoCausticCastersWithoutSpecularSurfaces) {
    EXPECT_EQ(render_scene("cornell-box-diffuse")->caustic_casters, nullptr);
}

}  // namespace
}  // namespace photond
