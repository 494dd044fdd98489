// A whole scene moved and resized: p' = scale * p + translation applied to every vertex,
// punctual light and camera, so that the transformed scene, seen through its transformed camera,
// is "the same scene" and renders the same image (used by the scale-invariance stress tests).
//
// What "the same" means for the radiometric quantities under a uniform scale s > 0:
//  - Radiance is invariant along rays, so emission (W/m^2/sr) stays as it is, and so does the
//    image of every emissive surface and everything it lights: irradiance from an area light
//    E = L * (solid angle * cosine) depends only on angles, which a similarity keeps.
//  - A point or spot light's irradiance falls off as I / d^2, and every d grows by s, so its
//    intensity (W/sr) is multiplied by s^2 to keep the irradiance, hence the image, unchanged
//    (its power 4 pi I grows by s^2, as does an area light's power pi L A).
//  - A directional light gives irradiance (W/m^2) independent of distance: unchanged.
//  - Normals, light directions, the camera's up vector and field of view are unchanged
//    (a positive uniform scale and a translation preserve angles and orientation).
//  - Reflectances, textures and indices of refraction are dimensionless: unchanged.
#pragma once

#include "core/math/vec.h"
#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

/// A positive uniform scale followed by a translation: p' = scale * p + translation.
struct SimilarityTransform {
    double scale = 1.0;
    DVec3 translation{0.0};

    /// The image of a point, computed in double precision and rounded once to float.
    Vec3 apply(const Vec3& p) const { return Vec3(scale * DVec3(p) + translation); }
};

/// The scene under `transform` (see the file comment for the radiometric rules); the bounds are
/// recomputed from the transformed data. Fails with a message when the scale is not positive and
/// finite, or when a transformed coordinate or intensity leaves the float range (naming the
/// vertex, light or camera).
Expected<Scene> transform_scene(const Scene& scene, const SimilarityTransform& transform);

}  // namespace photond
