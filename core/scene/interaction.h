// The local geometry at a ray hit: position, normals, texture coordinates, material.
#pragma once

#include "core/accel/ray_tracer.h"
#include "core/math/frame.h"
#include "core/scene/scene.h"

namespace photond {

struct SurfaceInteraction {
    Vec3 p{0.0f};
    Vec3 geometric_normal{0.0f, 0.0f, 1.0f};  // the triangle's front-face normal (winding)
    Vec3 shading_normal{0.0f, 0.0f, 1.0f};    // interpolated, on the geometric normal's side
    Vec2 uv{0.0f};  // interpolated texture coordinates; zero when the material has no texture
    uint32_t triangle = 0;
    uint32_t material = 0;
    /// True when the incoming ray arrived from the front side (the side the normal points to).
    bool front_face = true;
    float distance = 0.0f;  // ray parameter t of the hit
};

/// Interpolated normals that point away from the geometric side are flipped onto it, so that
/// inverted vertex normals in the input cannot turn a surface inside out.
inline Vec3 oriented_shading_normal(const Vec3& shading, const Vec3& geometric) {
    if (glm::dot(shading, shading) == 0.0f) return geometric;
    return glm::dot(shading, geometric) < 0.0f ? -shading : shading;
}

/// Computes the interaction at `hit` of a ray with direction `ray_direction`. Inline: it runs at
/// every hit of every integrator and photon, whose callers use only some of its fields.
inline SurfaceInteraction make_interaction(const Scene& scene, const Hit& hit, const Vec3& ray_direction) {
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
    // A flat-shaded triangle's vertices share one normal, unit or zero (SceneBuilder).
    Vec3 shading = scene.normals[tri.x];
    if (!scene.flat_shaded[hit.triangle]) {
        const Vec3 n = w * shading + hit.u * scene.normals[tri.y] + hit.v * scene.normals[tri.z];
        const float len = glm::length(n);
        shading = len > 1e-12f && std::isfinite(len) ? n * (1.0f / len) : Vec3(0.0f);
    }
    si.shading_normal = oriented_shading_normal(shading, si.geometric_normal);
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
