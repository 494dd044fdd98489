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

/// Computes the interaction at `hit` of a ray with direction `ray_direction`.
SurfaceInteraction make_interaction(const Scene& scene, const Hit& hit, const Vec3& ray_direction);

/// Interpolated normals that point away from the geometric side are flipped onto it, so that
/// inverted vertex normals in the input cannot turn a surface inside out.
inline Vec3 oriented_shading_normal(const Vec3& shading, const Vec3& geometric) {
    if (glm::dot(shading, shading) == 0.0f) return geometric;
    return glm::dot(shading, geometric) < 0.0f ? -shading : shading;
}

}  // namespace photond
