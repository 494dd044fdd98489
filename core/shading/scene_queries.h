// What light transport asks of a RenderScene, the same for photon tracing and every integrator:
// ray queries that count themselves, rays that leave a surface, and the BSDF at a hit.
#pragma once

#include <cstdint>
#include <optional>

#include "core/accel/ray_tracer.h"
#include "core/material/bsdf.h"
#include "core/math/frame.h"
#include "core/scene/interaction.h"
#include "core/shading/render_scene.h"

namespace photond {

/// Ray counts of one thread's work; summed after the pass (sums do not depend on the order).
struct RayCounters {
    uint64_t rays = 0;         // intersection queries
    uint64_t shadow_rays = 0;  // occlusion queries
    uint64_t irradiance_lookups = 0;  // indirect irradiance asked of the irradiance cache
    uint64_t irradiance_misses = 0;   // ... that no record covered (gathered on the spot)
    uint64_t radiance_lookups = 0;    // glossy points that asked the radiance cache
    uint64_t radiance_misses = 0;     // ... that no record covered (BSDF-sampled rays instead)
    uint64_t caustic_points = 0;      // visible points where the caustic map could be read (at
                                      // the pixel's samples that estimate it: SampleContext::pixel_share)
    uint64_t caustic_skipped = 0;     // ... where it was not, its light too faint to show
    uint64_t short_ray_bounces = 0;   // gather hits traced a bounce on (GatherSettings::short_ray_radii)

    RayCounters& operator+=(const RayCounters& o) {
        rays += o.rays;
        shadow_rays += o.shadow_rays;
        irradiance_lookups += o.irradiance_lookups;
        irradiance_misses += o.irradiance_misses;
        radiance_lookups += o.radiance_lookups;
        radiance_misses += o.radiance_misses;
        caustic_points += o.caustic_points;
        caustic_skipped += o.caustic_skipped;
        short_ray_bounces += o.short_ray_bounces;
        return *this;
    }
};

/// Intersection query that counts itself.
inline std::optional<Hit> trace_ray(const RenderScene& rs, const Ray& ray, RayCounters& counters) {
    ++counters.rays;
    return rs.tracer->intersect(ray);
}

/// A ray leaving the surface point of `si` in `direction`, offset against self-intersection.
inline Ray spawn_ray(const RenderScene& rs, const SurfaceInteraction& si, const Vec3& direction) {
    return Ray{rs.tracer->offset_origin(si.p, si.geometric_normal, direction), direction};
}

/// The BSDF at a hit seen from direction wo. Opaque materials and thin walls are shaded two-sided
/// (normals turned towards wo); transmissive solids keep the mesh's orientation, so the outside is
/// the front side.
inline Bsdf make_bsdf(const RenderScene& rs, const SurfaceInteraction& si, const Vec3& wo) {
    const Material& material = rs.scene->materials[si.material];
    Vec3 ng = si.geometric_normal, ns = si.shading_normal;
    if ((material.transmission <= 0.0f || material.thin_walled) && glm::dot(wo, ng) < 0.0f) {
        ng = -ng;
        ns = -ns;
    }
    if (!material.textured() && rs.scene->colors.empty())
        return Bsdf(rs.bsdf_materials[si.material], material.base_color, Frame(ns), ng);
    const MaterialPoint mp = rs.scene->material_point(si.material, si.tex);
    if (!material.varying_bsdf())
        return Bsdf(rs.bsdf_materials[si.material], mp.base_color, Frame(ns), ng);
    // Metallic, roughness, transmission, specular or the clearcoat vary over the surface: the
    // constants are derived here.
    BsdfMaterial constants(material, mp);
    // Glossy caustics come only off materials sharp all over (RenderScene::sharp_glossy_materials).
    constants.sharp_glossy = constants.sharp_glossy && rs.sharp_glossy_materials[si.material];
    return Bsdf(std::move(constants), mp.base_color, Frame(ns), ng);
}

}  // namespace photond
