// Compressed glTF geometry, decoded before the loader reads the accessors: EXT_meshopt_compression
// (meshoptimizer's vertex and index codecs and filters, Debian's libmeshoptimizer) and
// KHR_draco_mesh_compression (Debian's libdraco). Both rewrite the parsed model so that every
// accessor points into plain, uncompressed buffers; the loader then reads them like any other.
//
// Untrusted input: every offset, length and count is checked, decoded sizes are bounded, and
// failures come back as Errors naming the bufferView, mesh and primitive.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/util/expected.h"

namespace tinygltf {
class Model;
}

namespace photond {

/// tinygltf 2.7 refuses two things compressed files are made of: EXT_meshopt_compression's
/// fallback buffers (no uri, a byteLength beyond the GLB's binary chunk) and the index accessors
/// of KHR_draco_mesh_compression primitives (no bufferView). For a file that uses either
/// extension, returns a copy of the file (.gltf text or .glb) in which each fallback buffer is a
/// one-byte data: URI (only compressed views refer to it, and they are decoded into buffers of
/// their own) and each Draco primitive has no "indices" (decode_draco_primitives makes them);
/// returns nothing for any other file.
/// The JSON text of a glTF file: all of a .gltf, a GLB's JSON chunk; empty for a GLB whose
/// header is malformed (tinygltf then says what is wrong).
std::string_view gltf_json_text(std::span<const uint8_t> file);

struct CompressedFilePatch {
    std::vector<uint8_t> bytes;  // the patched file; empty: use the original
};
Expected<CompressedFilePatch> patch_compressed_file_for_tinygltf(std::span<const uint8_t> file);

/// Decodes every bufferView with EXT_meshopt_compression into a new buffer of the model and points
/// the view at it. `max_bytes` bounds the decoded total.
Status decode_meshopt_buffer_views(tinygltf::Model& model, uint64_t max_bytes);

/// Decodes every primitive with KHR_draco_mesh_compression: its indices and the attributes the
/// extension names become new FLOAT (indices: UNSIGNED_INT) accessors over new buffers.
Status decode_draco_primitives(tinygltf::Model& model, uint64_t max_bytes);

}  // namespace photond
