// The job's atmosphere along rays (Scene::atmosphere): a homogeneous medium that fills the
// scene's bounding box (its triangles, the job's quads and light positions) except the inside
// of closed transmissive solids, which their own material fills (KHR_materials_volume). A ray
// segment runs inside such a solid when it ends on the back face of a transmissive material,
// the rule volume_transmittance (core/scene/interaction.h) already follows.
#pragma once

#include <optional>

#include "core/math/ray.h"
#include "core/scene/interaction.h"
#include "core/scene/scene.h"

namespace photond {

/// The part [t0, t1) of a ray's parameters that the atmosphere's box holds; empty when t1 <= t0.
struct MediumSpan {
    float t0 = 0.0f;
    float t1 = 0.0f;
    bool empty() const { return !(t1 > t0); }
};

/// The span of ray parameters in [ray.tmin, t_end) inside `bounds` (slab test; t_end may be
/// infinite). In units of the ray's direction, which need not be unit.
MediumSpan span_in_bounds(const Bounds3& bounds, const Ray& ray, float t_end);

/// Whether the ray segment that ends at `si` ran inside a closed transmissive solid.
inline bool segment_inside_solid(const Scene& scene, const SurfaceInteraction& si) {
    const Material& m = scene.materials[si.material];
    return !si.front_face && m.transmission > 0.0f && !m.thin_walled;
}

/// The atmosphere's span of a camera or path ray (unit direction) that ends at the hit `si`
/// (null: it leaves the scene); empty without an atmosphere or inside a solid.
MediumSpan atmosphere_span(const Scene& scene, const Ray& ray, const SurfaceInteraction* si);

/// Transmittance of the atmosphere along an unoccluded shadow ray over [ray.tmin, ray.tmax]
/// (tmax infinite: to where it leaves the box); 1 without an atmosphere.
Color atmosphere_transmittance(const Scene& scene, const Ray& shadow);

}  // namespace photond
