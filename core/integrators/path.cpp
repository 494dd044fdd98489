#include "core/integrators/path.h"

namespace photond {

PathIntegrator::PathIntegrator(std::shared_ptr<const RenderScene> scene, int max_depth,
                               int roulette_start_depth)
    : scene_(std::move(scene)), max_depth_(max_depth), roulette_start_depth_(roulette_start_depth) {}

RadianceParts PathIntegrator::radiance_parts(const CameraRay& camera_ray, SampleContext& context) const {
    const RenderScene& rs = *scene_;
    RadianceParts radiance;
    int rough_bounces = 0;  // non-delta BSDF samples so far
    // The part emission found along the path counts in, and light sampled at the current vertex.
    const auto emission_part = [&](bool after_delta) {
        if (rough_bounces == 0) return &RadianceParts::emission;
        if (rough_bounces == 1) return after_delta ? &RadianceParts::caustic : &RadianceParts::direct;
        return &RadianceParts::indirect;
    };
    Color throughput(1.0f);
    Ray ray = primary_ray(camera_ray);
    bool previous_was_delta = true;  // the camera ray counts as specular: emission is taken whole
    float previous_bsdf_pdf = 0.0f;
    Vec3 previous_point = camera_ray.origin;
    // The camera's ray cone picks texture levels along the camera ray and ideal specular bounces
    // after it; after a rough bounce the path is an integral over directions, textures at level 0.
    const float spread = pixel_spread(camera_ray);
    float cone_length = 0.0f;
    bool cone_alive = true;

    for (int depth = 0; depth < max_depth_; ++depth) {
        const std::optional<Hit> hit = trace_ray(rs, ray, context.counters);
        if (!hit) {
            // Left the scene: the environment and soft suns, weighted against their light
            // samples at the previous vertex (whole after the camera or a delta bounce).
            if (rs.lights->has_distant_area_lights())
                radiance.add(throughput * rs.lights->escaped_radiance(ray.direction,
                                                                      previous_was_delta ? 0.0f : previous_bsdf_pdf),
                             emission_part(previous_was_delta));
            break;
        }
        cone_length += hit->t;
        const SurfaceInteraction si =
            make_interaction(*rs.scene, *hit, ray.direction, cone_alive ? cone_length * spread : 0.0f);
        const Vec3 wo = -ray.direction;
        throughput *= volume_transmittance(*rs.scene, si);

        const Color emitted = rs.lights->emitted_radiance(si, wo);
        if (!is_black(emitted)) {
            float weight = 1.0f;
            if (!previous_was_delta) {
                const float light_pdf = rs.lights->pdf_incident_triangle(si.triangle, previous_point, si.p);
                weight = power_heuristic(previous_bsdf_pdf, light_pdf);
            }
            radiance.add(throughput * emitted * weight, emission_part(previous_was_delta));
        }

        const Bsdf bsdf = make_bsdf(rs, si, wo);
        if (bsdf.has_non_delta())
            radiance.add(throughput * sample_direct_light(rs, si, bsdf, wo, context, true),
                         rough_bounces == 0 ? &RadianceParts::direct : &RadianceParts::indirect);

        const float u_lobe = context.next_1d();
        const Vec2 u = context.next_2d();
        const std::optional<BsdfSample> s = bsdf.sample(wo, u_lobe, u);
        if (!s || !(s->pdf > 0.0f) || is_black(s->weight)) break;
        throughput *= s->weight;
        previous_was_delta = s->kind == LobeKind::Delta;
        if (!previous_was_delta) ++rough_bounces;
        cone_alive = cone_alive && previous_was_delta;
        previous_bsdf_pdf = s->pdf;
        previous_point = si.p;
        ray = spawn_ray(rs, si, s->wi);

        if (depth + 1 >= roulette_start_depth_) {
            // Survive with the throughput's largest channel (capped), compensating survivors.
            const float survive = std::min(0.95f, max_component(throughput));
            if (!(survive > 0.0f) || context.next_1d() >= survive) break;
            throughput /= survive;
        }
    }
    return radiance;
}

}  // namespace photond
