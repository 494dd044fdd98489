#include "core/integrators/path.h"

#include "core/scene/atmosphere.h"

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
    const float spread = pixel_spread(camera_ray) * camera_ray.texture_footprint_scale;
    float cone_length = 0.0f;
    bool cone_alive = true;

    const std::optional<HomogeneousMedium>& atmosphere = rs.scene->atmosphere;
    // In a medium, free flights are sampled by one hero channel for the whole path, and what the
    // path adds is divided by the average of the channels' pdfs over the hero's
    // (sample_free_flight): `spectral` is that product of ratios, 1 in a scene without media.
    const bool media = atmosphere || rs.scattering_interiors;
    const int hero = media ? std::min(2, static_cast<int>(context.next_1d() * 3.0f)) : 0;
    Color spectral(1.0f);
    const auto weight = [&] { return media ? throughput / average(spectral) : throughput; };
    // Russian roulette once the path is roulette_start_depth_ vertices long: survive with the
    // throughput's largest channel (capped), compensating survivors.
    const auto survives_roulette = [&](int depth) {
        if (depth + 1 < roulette_start_depth_) return true;
        const float survive = std::min(0.95f, max_component(weight()));
        if (!(survive > 0.0f) || context.next_1d() >= survive) return false;
        throughput /= survive;
        return true;
    };

    for (int depth = 0; depth < max_depth_; ++depth) {
        const std::optional<Hit> hit = trace_ray(rs, ray, context.counters);
        std::optional<SurfaceInteraction> hit_point;
        if (hit) {
            cone_length += hit->t;
            hit_point = make_interaction(*rs.scene, *hit, ray.direction, cone_alive ? cone_length * spread : 0.0f);
        }
        // The medium on the way: the solid's own where the segment ends inside a transmissive
        // material that scatters, else the atmosphere. A free flight that scatters before the
        // segment's end makes this vertex a point in the medium (light sampled by the phase
        // function, the path goes on in a direction it samples); one that passes carries its
        // weight on.
        std::optional<HomogeneousMedium> interior;
        const HomogeneousMedium* medium = nullptr;
        MediumSpan span;
        if (hit_point && segment_inside_solid(*rs.scene, *hit_point) &&
            rs.scene->materials[hit_point->material].interior_scatters()) {
            interior = rs.scene->materials[hit_point->material].interior_medium();
            medium = &*interior;
            span = {ray.tmin, hit->t};
        } else if (atmosphere) {
            medium = &*atmosphere;
            span = atmosphere_span(*rs.scene, ray, hit_point ? &*hit_point : nullptr);
        }
        if (medium && !span.empty()) {
            if (!medium->scatters()) {
                throughput *= medium->transmittance(span.t1 - span.t0);
            } else {
                const FreeFlight flight = sample_free_flight(*medium, span.t1 - span.t0, hero, context.next_1d());
                throughput *= flight.weight;
                spectral *= flight.pdf_ratio;
                if (flight.scattered) {
                    const Vec3 x = ray.origin + (span.t0 + flight.t) * ray.direction;
                    const Vec3 wo = -ray.direction;
                    radiance.add(weight() * sample_direct_light_in_medium(rs, *medium, x, wo, context, true),
                                 rough_bounces == 0 ? &RadianceParts::direct : &RadianceParts::indirect);
                    const Vec3 wi = sample_henyey_greenstein(medium->g, wo, context.next_2d());
                    previous_was_delta = false;
                    ++rough_bounces;
                    cone_alive = false;
                    previous_bsdf_pdf = henyey_greenstein(medium->g, wo, wi);
                    previous_point = x;
                    ray = Ray{x, wi};
                    if (is_black(throughput) || !survives_roulette(depth)) break;
                    continue;
                }
            }
        }
        if (!hit) {
            // Left the scene: the environment and soft suns, weighted against their light
            // samples at the previous vertex (whole after the camera or a delta bounce).
            if (rs.lights->has_distant_area_lights())
                radiance.add(weight() * rs.lights->escaped_radiance(ray.direction,
                                                                      previous_was_delta ? 0.0f : previous_bsdf_pdf),
                             emission_part(previous_was_delta));
            break;
        }
        const SurfaceInteraction& si = *hit_point;
        const Vec3 wo = -ray.direction;
        if (!interior) throughput *= volume_transmittance(*rs.scene, si);  // the free flight took it

        const Color emitted = rs.lights->emitted_radiance(si, wo);
        if (!is_black(emitted)) {
            float mis_weight = 1.0f;
            if (!previous_was_delta) {
                const float light_pdf = rs.lights->pdf_incident_triangle(si.triangle, previous_point, si.p);
                mis_weight = power_heuristic(previous_bsdf_pdf, light_pdf);
            }
            radiance.add(weight() * emitted * mis_weight, emission_part(previous_was_delta));
        }

        const Bsdf bsdf = make_bsdf(rs, si, wo);
        if (bsdf.has_non_delta())
            radiance.add(weight() * sample_direct_light(rs, si, bsdf, wo, context, true),
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

        if (!survives_roulette(depth)) break;
    }
    return radiance;
}

}  // namespace photond
