#include "core/scene/interaction.h"

namespace photond {

SurfaceInteraction make_interaction(const Scene& scene, const Hit& hit, const Vec3& ray_direction) {
    const glm::uvec3& tri = scene.triangles[hit.triangle];
    const float w = 1.0f - hit.u - hit.v;
    SurfaceInteraction si;
    // Barycentric interpolation is more accurate than origin + t * direction far from the origin.
    si.p = w * scene.positions[tri.x] + hit.u * scene.positions[tri.y] + hit.v * scene.positions[tri.z];
    si.geometric_normal = scene.triangle_normal(hit.triangle);
    if (glm::dot(si.geometric_normal, si.geometric_normal) == 0.0f) {
        // A degenerate (zero-area) triangle that Embree still reported: face the ray.
        si.geometric_normal = -glm::normalize(ray_direction);
    }
    const Vec3 n = w * scene.normals[tri.x] + hit.u * scene.normals[tri.y] + hit.v * scene.normals[tri.z];
    const float len = glm::length(n);
    si.shading_normal = oriented_shading_normal(len > 1e-12f && std::isfinite(len) ? n / len : Vec3(0.0f),
                                                si.geometric_normal);
    si.triangle = hit.triangle;
    si.material = scene.triangle_materials[hit.triangle];
    // Texture coordinates serve texture lookups only: untextured materials skip their three loads.
    if (scene.materials[si.material].base_color_texture >= 0)
        si.uv = w * scene.uvs[tri.x] + hit.u * scene.uvs[tri.y] + hit.v * scene.uvs[tri.z];
    si.front_face = glm::dot(ray_direction, si.geometric_normal) < 0.0f;
    si.distance = hit.t;
    return si;
}

}  // namespace photond
