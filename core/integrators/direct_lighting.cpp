#include "core/integrators/integrator.h"

namespace photond {

Color sample_direct_light(const RenderScene& rs, const SurfaceInteraction& si, const Bsdf& bsdf,
                          const Vec3& wo, SampleContext& context, bool use_mis, LobeMask mask) {
    const float u_select = context.next_1d();
    const Vec2 u = context.next_2d();
    const std::optional<LightSample> ls = rs.lights->sample_incident(si.p, u_select, u);
    if (!ls || !(ls->pdf > 0.0f) || is_black(ls->radiance)) return Color(0.0f);
    const Color f = bsdf.eval(wo, ls->wi, TransportMode::Radiance, mask);
    if (is_black(f)) return Color(0.0f);
    const float cos_theta = std::abs(glm::dot(ls->wi, si.shading_normal));

    const Vec3 origin = rs.tracer->offset_origin(si.p, si.geometric_normal, ls->wi);
    Ray shadow{origin, ls->wi};
    if (std::isfinite(ls->distance)) {
        // Aim at the light point moved off its own surface; direction unnormalised, tmax = 1.
        Vec3 target = ls->point;
        if (glm::dot(ls->normal, ls->normal) > 0.0f)
            target = rs.tracer->offset_origin(ls->point, ls->normal, -ls->wi);
        shadow.direction = target - origin;
        shadow.tmax = 1.0f;
    }
    ++context.counters.shadow_rays;
    if (rs.tracer->occluded(shadow)) return Color(0.0f);

    float weight = 1.0f;
    if (use_mis && !ls->is_delta) weight = power_heuristic(ls->pdf, bsdf.pdf(wo, ls->wi, mask));
    return f * ls->radiance * (cos_theta * weight / ls->pdf);
}

}  // namespace photond
