#include "core/integrators/photon_mapping.h"

#include "core/integrators/direct.h"

namespace photond {

PhotonMapIntegrator::PhotonMapIntegrator(std::shared_ptr<const RenderScene> scene,
                                         std::shared_ptr<const PhotonMaps> maps,
                                         const PhotonMapIntegratorSettings& settings)
    : scene_(std::move(scene)), maps_(std::move(maps)), settings_(settings) {
    const float scene_radius = scene_->scene->bounds.radius();
    caustic_options_.k = settings_.k_caustic;
    caustic_options_.max_radius = settings_.max_radius_caustic > 0.0f
                                      ? settings_.max_radius_caustic
                                      : kDefaultCausticRadiusShare * scene_radius;
    caustic_options_.cone_filter = true;
    global_options_.k = settings_.k_global;
    global_options_.max_radius = settings_.max_radius_global > 0.0f
                                     ? settings_.max_radius_global
                                     : kDefaultGlobalRadiusShare * scene_radius;
    // Direct light comes from light sampling; caustics from the caustic map when there is one.
    global_options_.exclude_flags = photon_flags::kDirect | (maps_->caustic ? photon_flags::kCaustic : 0);
}

Color PhotonMapIntegrator::radiance(const CameraRay& ray, SampleContext& context) const {
    return radiance_along(Ray{ray.origin, ray.direction}, 0, context);
}

Color PhotonMapIntegrator::radiance_along(const Ray& ray, int depth, SampleContext& context) const {
    const RenderScene& rs = *scene_;
    const std::optional<Hit> hit = trace_ray(rs, ray, context.counters);
    if (!hit) return Color(0.0f);
    const SurfaceInteraction si = make_interaction(*rs.scene, *hit, ray.direction);
    const Vec3 wo = -ray.direction;
    Color radiance = rs.lights->emitted_radiance(si, wo);
    const Bsdf bsdf = make_bsdf(*rs.scene, si, wo);
    if (bsdf.has_non_delta()) {
        radiance += sample_direct_light(rs, si, bsdf, wo, context, false);
        const Vec3 normal = glm::dot(si.shading_normal, wo) >= 0.0f ? si.shading_normal : -si.shading_normal;
        if (maps_->caustic)
            radiance += maps_->caustic->estimate_radiance(si.p, normal, bsdf, wo, caustic_options_);
        if (maps_->global)
            radiance += maps_->global->estimate_radiance(si.p, normal, bsdf, wo, global_options_);
    }
    if (bsdf.has_delta() && depth < settings_.max_specular_depth) {
        radiance += follow_delta_lobes(bsdf, wo, depth, context.rng, [&](const BsdfSample& s) {
            return radiance_along(spawn_ray(rs, si, s.wi), depth + 1, context);
        });
    }
    return radiance;
}

}  // namespace photond
