// The in-scattered light from the volume photon map along a ray segment (Jensen & Christensen
// 1998). In the atmosphere the photon-map integrator's camera rays take the multiple scattering
// from it (their single scattering from light samples, single_scattering), its gather rays all
// of it. Inside a solid that scatters (Material::interior_scatters) every ray takes all of it:
// light samples from inside are blocked by the solid's surface.
#pragma once

#include "core/integrators/integrator.h"
#include "core/photon/photon_map.h"

namespace photond {

/// The light `volume`'s photons say `medium` scatters towards the ray's origin over `span` of
/// the ray (unit direction): `points` distances stratified in the transmittance truncated to the
/// span (sample_distance_in_segment, one channel for all, two draws from `context`), each the
/// map's in-scattered source there (PhotonMap::estimate_in_scattering with k photons, radius
/// capped at max_radius, photons with exclude_flags left out, the sphere clipped to
/// medium_bounds) times the transmittance to it.
/// Not attenuated by what lies before the span: the caller's throughput holds that.
Color volume_in_scattering(const PhotonMap& volume, const HomogeneousMedium& medium, const Bounds3* medium_bounds,
                           const Ray& ray, const MediumSpan& span, uint32_t k, float max_radius, uint8_t exclude_flags,
                           int points, SampleContext& context);

/// The medium of the solid a ray segment ending at `si` ran inside, when that solid scatters.
std::optional<HomogeneousMedium> scattering_interior(const Scene& scene, const SurfaceInteraction& si);

/// All the light the scattering solid whose inside the ray (unit direction) crossed up to `si`
/// sends towards its origin: volume_in_scattering over [ray.tmin, si.distance] from the map's
/// photons inside solids (photon_flags::kInterior), each sphere cut by the solid's surface as a
/// plane at its nearest point (RayTracer::distance_to_surface). Not attenuated by what lies before.
Color interior_in_scattering(const RenderScene& rs, const PhotonMap& volume, const HomogeneousMedium& medium,
                             const Ray& ray, const SurfaceInteraction& si, uint32_t k, float max_radius, int points,
                             SampleContext& context);

}  // namespace photond
