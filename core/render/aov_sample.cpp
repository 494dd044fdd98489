#include "core/render/aov_sample.h"

namespace photond {

FirstSurface first_surface(const RenderScene& rs, const CameraRay& ray, RayCounters& counters) {
    FirstSurface surface;
    const Ray primary = primary_ray(ray);
    const std::optional<Hit> hit = trace_ray(rs, primary, counters);
    if (!hit) return surface;
    const SurfaceInteraction si = make_interaction(*rs.scene, *hit, primary.direction, 0.0f);
    const Material& material = rs.scene->materials[si.material];
    surface.albedo = material.textured() || !rs.scene->colors.empty()
                         ? rs.scene->material_point(si.material, si.tex).base_color
                         : material.base_color;
    surface.normal = glm::dot(si.shading_normal, primary.direction) > 0.0f ? -si.shading_normal : si.shading_normal;
    surface.depth = hit->t * glm::length(primary.direction);
    return surface;
}

Color aov_value(Aov aov, const RadianceParts& parts, const FirstSurface& surface) {
    switch (aov) {
        case Aov::Emission: return parts.emission;
        case Aov::Direct: return parts.direct;
        case Aov::Indirect: return parts.indirect;
        case Aov::Caustic: return parts.caustic;
        case Aov::Albedo: return surface.albedo;
        case Aov::Normal: return surface.normal;
        case Aov::Depth: return Color(surface.depth);
    }
    return Color(0.0f);
}

}  // namespace photond
