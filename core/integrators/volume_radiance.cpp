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

}  // namespace photond
