// The content hash of a Scene: everything in it that affects light transport, from which the keys
// of the work cached per scene are made (core/photon/photon_map_key.h).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "core/scene/scene.h"
#include "core/util/sha256.h"

namespace photond {

/// SHA-256 of the scene's light-transport content: positions, normals, uvs, triangles, triangle
/// materials, every Material field but the name, textures (size and texels) and punctual lights
/// but their names. Cameras, the scene name and the (derived) bounds are left out, so scenes that
/// differ only in their views get the same hash. Floats are hashed by their bit patterns, with
/// -0.0 taken as 0.0; the digest does not depend on the host's byte order.
Sha256Digest scene_content_hash(const Scene& scene);

}  // namespace photond
