#include "core/scene/scene_transform.h"

#include <cmath>
#include <string>

namespace photond {

Expected<Scene> transform_scene(const Scene& scene, const SimilarityTransform& transform) {
    const std::string context = "transforming scene '" + scene.name + "': ";
    if (!(transform.scale > 0.0) || !std::isfinite(transform.scale))
        return Error{context + "the scale " + std::to_string(transform.scale) +
                     " is not positive and finite"};
    if (!std::isfinite(transform.translation.x) || !std::isfinite(transform.translation.y) ||
        !std::isfinite(transform.translation.z))
        return Error{context + "the translation is not finite"};

    Scene out = scene;
    out.bounds = Bounds3{};
    for (size_t i = 0; i < out.positions.size(); ++i) {
        out.positions[i] = transform.apply(scene.positions[i]);
        if (!is_finite(out.positions[i]))
            return Error{context + "vertex " + std::to_string(i) + " leaves the float range"};
        out.bounds.extend(out.positions[i]);
    }
    // Point and spot lights: I / d^2 with every d scaled by s, so I is scaled by s^2.
    const double intensity_scale = transform.scale * transform.scale;
    for (PunctualLight& light : out.lights) {
        if (light.type == PunctualLightType::Directional) continue;
        light.position = transform.apply(light.position);
        light.intensity = Color(DVec3(light.intensity) * intensity_scale);
        if (!is_finite(light.position) || !is_finite(light.intensity))
            return Error{context + "light '" + light.name + "' leaves the float range"};
        out.bounds.extend(light.position);
    }
    for (CameraDesc& camera : out.cameras) {
        camera.position = transform.apply(camera.position);
        camera.look_at = transform.apply(camera.look_at);
        if (!is_finite(camera.position) || !is_finite(camera.look_at))
            return Error{context + "camera '" + camera.name + "' leaves the float range"};
    }
    // Recomputed rather than kept: the rounded positions define the triangles now.
    out.derive_triangle_data();
    if (Status status = out.validate(); !status) return status.error();
    return out;
}

}  // namespace photond
