#include "core/integrators/volume_radiance.h"

namespace photond {

Color volume_in_scattering(const PhotonMap& volume, const HomogeneousMedium& medium, const Bounds3* medium_bounds,
                           const Ray& ray, const MediumSpan& span, uint32_t k, float max_radius, uint8_t exclude_flags,
                           int points, SampleContext& context) {
    Color sum(0.0f);
    march_through_medium(medium, ray, span, points, context, [&](const Vec3& x, const Color& weight) {
        sum += weight * volume.estimate_in_scattering(x, -ray.direction, medium.g, k, max_radius, exclude_flags,
                                                      medium_bounds);
    });
    return sum;
}

std::optional<HomogeneousMedium> scattering_interior(const Scene& scene, const SurfaceInteraction& si) {
    if (!segment_inside_solid(scene, si)) return std::nullopt;
    const Material& material = scene.materials[si.material];
    if (!material.interior_scatters()) return std::nullopt;
    return material.interior_medium();
}

Color interior_in_scattering(const RenderScene& rs, const PhotonMap& volume, const HomogeneousMedium& medium,
                             const Ray& ray, const SurfaceInteraction& si, uint32_t k, float max_radius, int points,
                             SampleContext& context) {
    Color sum(0.0f);
    const MediumSpan span{ray.tmin, si.distance};
    if (span.empty()) return sum;
    march_through_medium(medium, ray, span, points, context, [&](const Vec3& x, const Color& weight) {
        // The surface matters within the estimate's radius only: the query looks no farther.
        const auto surface = [&](float radius) { return rs.tracer->distance_to_surface(x, radius); };
        sum += weight * volume.estimate_in_scattering(x, -ray.direction, medium.g, k, max_radius, 0, nullptr, true,
                                                      surface);
    });
    return sum;
}

}  // namespace photond
