#include "core/integrators/volume_radiance.h"

namespace photond {

Color volume_in_scattering(const PhotonMap& volume, const HomogeneousMedium& medium, const Bounds3* medium_bounds,
                           const Ray& ray, const MediumSpan& span, uint32_t k, float max_radius, uint8_t exclude_flags,
                           int points, SampleContext& context) {
    const float length = span.t1 - span.t0;
    const float u_channel = context.next_1d();
    const float u_jitter = context.next_1d();
    Color sum(0.0f);
    for (int i = 0; i < points; ++i) {
        const float u = (static_cast<float>(i) + u_jitter) / static_cast<float>(points);
        const SegmentDistance d = sample_distance_in_segment(medium, length, u_channel, u);
        if (!(d.pdf > 0.0f)) continue;
        const Vec3 x = ray.origin + (span.t0 + d.t) * ray.direction;
        sum += medium.transmittance(d.t) / d.pdf *
               volume.estimate_in_scattering(x, -ray.direction, medium.g, k, max_radius, exclude_flags, medium_bounds);
    }
    return sum / static_cast<float>(points);
}

}  // namespace photond
