#include "core/integrators/direct.h"

#include "core/scene/atmosphere.h"

namespace photond {

DirectIntegrator::DirectIntegrator(std::shared_ptr<const RenderScene> scene, int max_specular_depth)
    : scene_(std::move(scene)), max_specular_depth_(max_specular_depth) {}

RadianceParts DirectIntegrator::radiance_parts(const CameraRay& ray, SampleContext& context) const {
    return radiance_along(primary_ray(ray), 0, context, 0.0f, pixel_spread(ray) * ray.texture_footprint_scale);
}

RadianceParts DirectIntegrator::radiance_along(const Ray& ray, int depth, SampleContext& context,
                                               float path_length, float spread) const {
    const RenderScene& rs = *scene_;
    const std::optional<Hit> hit = trace_ray(rs, ray, context.counters);
    RadianceParts radiance;
    std::optional<SurfaceInteraction> si;
    if (!hit) {
        // A camera ray or a delta bounce that leaves the scene sees the sky whole.
        radiance.add_emission(rs.lights->escaped_radiance(ray.direction, 0.0f));
    } else {
        // The camera's ray cone, widened along ideal specular bounces, picks the texture level.
        const float length = path_length + hit->t;
        si = make_interaction(*rs.scene, *hit, ray.direction, length * spread);
        const Vec3 wo = -ray.direction;
        radiance.add_emission(rs.lights->emitted_radiance(*si, wo));
        const Bsdf bsdf = make_bsdf(rs, *si, wo);
        if (bsdf.has_non_delta()) radiance.add_direct(sample_direct_light(rs, *si, bsdf, wo, context, false));
        if (bsdf.has_delta() && depth < max_specular_depth_) {
            radiance += follow_delta_lobes(bsdf, wo, depth < kBranchDepth, context.rng, [&](const BsdfSample& s) {
                return radiance_along(spawn_ray(rs, *si, s.wi), depth + 1, context, length, spread);
            });
        }
        radiance = volume_transmittance(*rs.scene, *si) * radiance;
    }
    if (const std::optional<HomogeneousMedium>& atmosphere = rs.scene->atmosphere) {
        // The atmosphere on the way: what lies beyond is seen through it, and it sends the light
        // it scatters once towards the ray (single_scattering).
        const MediumSpan span = atmosphere_span(*rs.scene, ray, si ? &*si : nullptr);
        if (!span.empty()) {
            const float length = span.t1 - span.t0;
            radiance = atmosphere->transmittance(length) * radiance;
            if (atmosphere->scatters()) radiance.add_direct(single_scattering(rs, *atmosphere, ray, span, context));
        }
    }
    return radiance;
}

}  // namespace photond
