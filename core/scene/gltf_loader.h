// glTF 2.0 loader (.gltf and .glb) producing a photond::Scene through SceneBuilder.
//
// Reads triangle meshes (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN; points and lines are skipped)
// under the default scene's node hierarchy (and EXT_mesh_gpu_instancing's instances), also
// quantized (KHR_mesh_quantization) and compressed (EXT_meshopt_compression,
// KHR_draco_mesh_compression: gltf_compression.h), metallic-roughness materials with
// KHR_materials_emissive_strength / _transmission / _ior / _specular, textures (PNG, JPEG, and
// WebP by EXT_texture_webp), perspective and orthographic cameras (one
// Scene::cameras entry per cameras[] entry) and KHR_lights_punctual lights (candela and lux
// converted to W/sr and W/m^2). What the file holds and the loader ignores is named in
// Scene::warnings.
//
// Untrusted input is expected: every accessor, index and buffer range is checked before use, no
// file outside the bundle root is ever opened, and every failure comes back as an Error whose
// message names the file and the node / mesh / primitive / accessor involved.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

struct GltfLoadOptions {
    // Only files inside this directory may be read (buffers, images). Empty = the glTF file's own
    // directory.
    std::filesystem::path bundle_root;
};

/// Loads a .gltf or .glb file (told apart by the "glTF" magic, not by the extension). External
/// buffers and images are read only from inside options.bundle_root; a uri that escapes it (by
/// "..", an absolute path or a symbolic link) is refused with an error naming the uri.
Expected<Scene> load_gltf_file(const std::filesystem::path& file,
                               const GltfLoadOptions& options = {});

/// For uploaded scenes: a .glb or a self-contained .gltf (data: URIs only; any external uri is
/// refused). `display_name` names the scene and prefixes every error message.
Expected<Scene> load_gltf_memory(std::span<const uint8_t> bytes, const std::string& display_name);

}  // namespace photond
