#include "core/scene/atmosphere.h"

#include <algorithm>
#include <limits>

namespace photond {

MediumSpan span_in_bounds(const Bounds3& bounds, const Ray& ray, float t_end) {
    if (bounds.empty()) return {};
    float t0 = ray.tmin, t1 = t_end;
    for (int axis = 0; axis < 3; ++axis) {
        const float d = ray.direction[axis];
        const float o = ray.origin[axis];
        if (d == 0.0f) {
            if (o < bounds.lower[axis] || o > bounds.upper[axis]) return {};
            continue;
        }
        const float inverse = 1.0f / d;
        float near = (bounds.lower[axis] - o) * inverse;
        float far = (bounds.upper[axis] - o) * inverse;
        if (near > far) std::swap(near, far);
        t0 = std::max(t0, near);
        t1 = std::min(t1, far);
        if (!(t1 > t0)) return {};
    }
    return {t0, t1};
}

MediumSpan atmosphere_span(const Scene& scene, const Ray& ray, const SurfaceInteraction* si) {
    if (!scene.atmosphere) return {};
    if (si && segment_inside_solid(scene, *si)) return {};
    return span_in_bounds(scene.bounds, ray, si ? si->distance : std::numeric_limits<float>::infinity());
}

Color atmosphere_transmittance(const Scene& scene, const Ray& shadow) {
    if (!scene.atmosphere) return Color(1.0f);
    const MediumSpan span = span_in_bounds(scene.bounds, shadow, shadow.tmax);
    if (span.empty()) return Color(1.0f);
    return scene.atmosphere->transmittance((span.t1 - span.t0) * glm::length(shadow.direction));
}

}  // namespace photond
