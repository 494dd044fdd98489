// The content key of one photon pass over a scene, under which its photon maps are cached and
// exported, so that further camera views of the scene skip photon tracing.
#pragma once

#include <cstdint>
#include <string>

#include "core/photon/photon_tracer.h"
#include "core/scene/scene.h"

namespace photond {

/// Bump when photon tracing changes what it stores for the same scene and settings (sampling,
/// Russian roulette, flux encoding, kd-tree order): every cached photon map then misses.
inline constexpr uint32_t kPhotonMapAlgorithmVersion = 14;  // 11: caustic photons from lights with a position aimed at their casters; 12: irradiance sites estimated without the photon on their disc's edge; 13: glossy lobes up to roughness 0.36 (was 0.25) continue caustic paths; 14: parallel caustic photons aimed at the discs of the casters' cover spheres

/// The cache key of the photon maps trace_photons builds for (scene, settings):
/// "pm1-" + 64 hex digits, from scene_content_hash, global_photons, caustic_photons, seed,
/// max_bounces, max_emitted_per_stored, irradiance_stride, k_irradiance and
/// kPhotonMapAlgorithmVersion. threads and cancel are not part of it (the maps do not depend on
/// them).
std::string photon_map_key(const Scene& scene, const PhotonTracingSettings& settings);

}  // namespace photond
