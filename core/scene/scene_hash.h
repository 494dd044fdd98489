// Content keys for caching per-scene work (photon maps): a hash of everything in a Scene that
// affects light transport, and the key of one photon pass over it.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "core/scene/scene.h"
#include "core/util/sha256.h"

namespace photond {

struct PhotonTracingSettings;

/// Bump when photon tracing changes what it stores for the same scene and settings (sampling,
/// Russian roulette, flux encoding, kd-tree order): every cached photon map then misses.
inline constexpr uint32_t kPhotonMapAlgorithmVersion = 6;

/// SHA-256 of the scene's light-transport content: positions, normals, uvs, triangles, triangle
/// materials, every Material field but the name, textures (size and texels) and punctual lights
/// but their names. Cameras, the scene name and the (derived) bounds are left out, so scenes that
/// differ only in their views get the same hash. Floats are hashed by their bit patterns, with
/// -0.0 taken as 0.0; the digest does not depend on the host's byte order.
Sha256Digest scene_content_hash(const Scene& scene);

/// The cache key of the photon maps trace_photons builds for (scene, settings):
/// "pm1-" + 64 hex digits, from scene_content_hash, global_photons, caustic_photons, seed,
/// max_bounces, max_emitted_per_stored, irradiance_stride, k_irradiance and
/// kPhotonMapAlgorithmVersion. threads and cancel are not part of it (the maps do not depend on
/// them).
std::string photon_map_key(const Scene& scene, const PhotonTracingSettings& settings);

}  // namespace photond
