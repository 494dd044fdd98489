#include "core/integrators/integrator.h"

#include "core/scene/atmosphere.h"

namespace photond {

namespace {

/// The BSDF-sampled half of multiple importance sampling for distant area lights (environment,
/// soft suns): one BSDF direction; where it leaves the scene unblocked, the sky's radiance
/// weighted by the power heuristic against the light samples of sample_direct_light. Delta
/// directions are left to the caller's specular recursion.
Color sample_distant_lights_by_bsdf(const RenderScene& rs, const LightSet& lights, const SurfaceInteraction& si,
                                    const Bsdf& bsdf, const Vec3& wo, SampleContext& context, LobeMask mask) {
    const float u_lobe = context.next_1d();
    const Vec2 u = context.next_2d();
    const std::optional<BsdfSample> s = bsdf.sample(wo, u_lobe, u, TransportMode::Radiance, mask);
    if (!s || s->kind == LobeKind::Delta || !(s->pdf > 0.0f) || is_black(s->weight)) return Color(0.0f);
    const Color sky = lights.escaped_radiance(s->wi, s->pdf);
    if (is_black(sky)) return Color(0.0f);
    ++context.counters.shadow_rays;
    const Ray ray = spawn_ray(rs, si, s->wi);
    if (rs.tracer->occluded(ray)) return Color(0.0f);
    return s->weight * sky * atmosphere_transmittance(*rs.scene, ray);
}

/// The shadow ray from `origin` to a light sample: towards the light point moved off its own
/// surface (direction unnormalised, tmax 1), or along wi for distant lights.
Ray shadow_ray_to(const RenderScene& rs, const Vec3& origin, const LightSample& ls) {
    Ray shadow{origin, ls.wi};
    if (std::isfinite(ls.distance)) {
        Vec3 target = ls.point;
        if (glm::dot(ls.normal, ls.normal) > 0.0f) target = rs.tracer->offset_origin(ls.point, ls.normal, -ls.wi);
        shadow.direction = target - origin;
        shadow.tmax = 1.0f;
    }
    return shadow;
}

}  // namespace

Color sample_direct_light(const RenderScene& rs, const LightSet& lights, const SurfaceInteraction& si,
                          const Bsdf& bsdf, const Vec3& wo, SampleContext& context, bool use_mis, LobeMask mask,
                          LobeMask mis_lobes, float mis_samples) {
    // Without the caller's MIS, distant area lights still get both strategies here: light
    // sampling alone is poor for glossy lobes under a sky, BSDF sampling alone for a small sun.
    const bool distant_mis = !use_mis && lights.has_distant_area_lights();
    Color radiance(0.0f);
    if (distant_mis) radiance += sample_distant_lights_by_bsdf(rs, lights, si, bsdf, wo, context, mask);

    const float u_select = context.next_1d();
    const Vec2 u = context.next_2d();
    const std::optional<LightSample> ls = lights.sample_incident(si.p, u_select, u);
    if (!ls || !(ls->pdf > 0.0f) || is_black(ls->radiance)) return radiance;
    const Color f = bsdf.eval(wo, ls->wi, TransportMode::Radiance, mask);
    if (is_black(f)) return radiance;
    const float cos_theta = std::abs(glm::dot(ls->wi, si.shading_normal));

    const Ray shadow = shadow_ray_to(rs, rs.tracer->offset_origin(si.p, si.geometric_normal, ls->wi), *ls);
    ++context.counters.shadow_rays;
    if (rs.tracer->occluded(shadow)) return radiance;

    float weight = 1.0f;
    const bool distant_area = !ls->is_delta && !std::isfinite(ls->distance);
    if ((use_mis || (distant_mis && distant_area)) && !ls->is_delta)
        weight = power_heuristic(ls->pdf, bsdf.pdf(wo, ls->wi, mask));
    Color weighted = f * weight;
    if (!use_mis && mis_lobes != 0 && !ls->is_delta && std::isfinite(ls->distance)) {
        // An area light: the caller's BSDF samples of mis_lobes find it too.
        const Color f_mis = bsdf.eval(wo, ls->wi, TransportMode::Radiance, mis_lobes);
        const float w = power_heuristic(ls->pdf, mis_samples * bsdf.pdf(wo, ls->wi, mis_lobes));
        weighted = glm::max(f - f_mis, Color(0.0f)) + f_mis * w;
    }
    return radiance + weighted * ls->radiance * atmosphere_transmittance(*rs.scene, shadow) * (cos_theta / ls->pdf);
}

Color sample_direct_light_in_medium(const RenderScene& rs, const HomogeneousMedium& medium, const Vec3& x,
                                    const Vec3& wo, SampleContext& context, bool use_mis) {
    const float u_select = context.next_1d();
    const Vec2 u = context.next_2d();
    const std::optional<LightSample> ls = rs.lights->sample_incident(x, u_select, u);
    if (!ls || !(ls->pdf > 0.0f) || is_black(ls->radiance)) return Color(0.0f);
    const float phase = henyey_greenstein(medium.g, wo, ls->wi);
    const Ray shadow = shadow_ray_to(rs, x, *ls);
    ++context.counters.shadow_rays;
    if (rs.tracer->occluded(shadow)) return Color(0.0f);
    const float weight = use_mis && !ls->is_delta ? power_heuristic(ls->pdf, phase) : 1.0f;
    return ls->radiance * atmosphere_transmittance(*rs.scene, shadow) * (phase * weight / ls->pdf);
}

Color single_scattering(const RenderScene& rs, const HomogeneousMedium& medium, const Ray& ray, const MediumSpan& span,
                        SampleContext& context) {
    // Points stratified along the ray: a narrow beam (a sun through a window) is crossed by some
    // point of most rays instead of by the one point of a few.
    Color sum(0.0f);
    march_through_medium(medium, ray, span, kSingleScatteringPoints, context, [&](const Vec3& x, const Color& weight) {
        sum += weight * sample_direct_light_in_medium(rs, medium, x, -ray.direction, context, false);
    });
    return medium.sigma_s * sum;
}

}  // namespace photond
