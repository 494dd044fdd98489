// The glTF loader's entry points: a file (through the file sandbox) or bytes in memory, parsed by
// tinygltf and read into a Scene by GltfSceneReader (core/scene/gltf_reader.h).
#include "core/scene/gltf_loader.h"

#include <cstring>
#include <exception>
#include <system_error>

#include "core/scene/gltf_compression.h"
#include "core/scene/gltf_reader.h"
#include "core/util/json_depth.h"
#include "core/util/path_containment.h"

namespace photond {
namespace {

namespace fs = std::filesystem;
using namespace gltf;

bool has_glb_magic(std::span<const uint8_t> bytes) {
    return bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
}

Expected<Scene> load_from_bytes(std::span<const uint8_t> bytes, const std::string& display_name,
                                FileSandbox& sandbox) {
    if (bytes.size() > kMaxFileBytes)
        return Error{display_name + ": file larger than " + std::to_string(kMaxFileBytes) +
                     " bytes"};
    const bool binary = has_glb_magic(bytes);
    if (binary && bytes.size() >= 12) {
        uint32_t declared = 0;
        std::memcpy(&declared, bytes.data() + 8, 4);  // little-endian hosts only (x86, ARM)
        if (declared > bytes.size())
            return Error{display_name + ": GLB is truncated: its header declares " +
                         std::to_string(declared) + " bytes, the data has " +
                         std::to_string(bytes.size())};
    }

    // tinygltf and the patching below recurse once per level of the JSON: refuse a deeper one
    // first (a GLB's JSON chunk only: its binary chunk is no text).
    if (json_nesting_depth(gltf_json_text(bytes)) > kMaxJsonNesting)
        return Error{display_name + ": " + json_nesting_message()};

    // Compressed files are patched where tinygltf would refuse them (gltf_compression.h).
    Expected<CompressedFilePatch> patched = patch_compressed_file_for_tinygltf(bytes);
    if (!patched) return Error{display_name + ": " + patched.error().message};
    if (!patched->bytes.empty()) bytes = patched->bytes;

    tinygltf::Model model;
    tinygltf::TinyGLTF parser;
    parser.SetFsCallbacks(sandbox_callbacks(sandbox));
    ImageLoadContext image_context{&model};
    parser.SetImageLoader(&keep_encoded_image, &image_context);

    std::string err, warn;
    bool ok = false;
    try {
        const auto size = static_cast<unsigned int>(bytes.size());
        ok = binary ? parser.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), size,
                                                  sandbox.base_dir)
                    : parser.LoadASCIIFromString(&model, &err, &warn,
                                                 reinterpret_cast<const char*>(bytes.data()), size,
                                                 sandbox.base_dir);
    } catch (const std::exception& e) {
        ok = false;
        err += std::string("parser exception: ") + e.what();
    }
    // A refused uri is reported even where tinygltf only warned (images) or failed vaguely.
    if (!sandbox.refused.empty()) return Error{display_name + ": " + sandbox.refused.front()};
    if (!ok) {
        std::string detail = trim_trailing_whitespace(err);
        if (detail.empty()) detail = trim_trailing_whitespace(warn);
        return Error{display_name + ": cannot load " + (binary ? "GLB" : "glTF") + ": " +
                     (detail.empty() ? "unknown error" : detail)};
    }
    // Compressed geometry becomes plain buffers before the reader checks any accessor.
    for (Status (*decode)(tinygltf::Model&, uint64_t) :
         {&decode_meshopt_buffer_views, &decode_draco_primitives}) {
        try {
            if (Status st = decode(model, kMaxFileBytes); !st)
                return Error{display_name + ": " + st.error().message};
        } catch (const std::exception& e) {
            return Error{display_name + ": decoding compressed geometry: " + e.what()};
        }
    }
    try {
        GltfSceneReader reader(model, display_name);
        return reader.read();
    } catch (const std::exception& e) {
        // Defensive: the reader checks indices itself, but never let a throw escape the loader.
        return Error{display_name + ": " + e.what()};
    }
}

}  // namespace

Expected<Scene> load_gltf_file(const std::filesystem::path& file, const GltfLoadOptions& options) {
    const std::string display_name = file.filename().string();
    std::error_code ec;
    const fs::path canonical_file = fs::weakly_canonical(fs::absolute(file, ec), ec);
    if (ec || !fs::is_regular_file(canonical_file, ec))
        return Error{display_name + ": cannot open '" + file.string() + "': not a readable file"};

    FileSandbox sandbox;
    sandbox.allow_files = true;
    sandbox.root = canonical_directory(options.bundle_root.empty() ? canonical_file.parent_path()
                                                                   : options.bundle_root);
    if (sandbox.root.empty() || !fs::is_directory(sandbox.root, ec))
        return Error{display_name + ": bundle root '" + options.bundle_root.string() +
                     "' is not a directory"};
    if (!resolve_below(sandbox.root, canonical_file))
        return Error{display_name + ": the file lies outside the bundle root '" +
                     sandbox.root.string() + "'"};
    sandbox.base_dir = canonical_file.parent_path().string();

    std::vector<unsigned char> bytes;
    std::string read_error;
    if (!read_whole_file(canonical_file, &bytes, &read_error))
        return Error{display_name + ": cannot read '" + file.string() + "': " + read_error};
    return load_from_bytes(bytes, display_name, sandbox);
}

Expected<Scene> load_gltf_memory(std::span<const uint8_t> bytes, const std::string& display_name) {
    FileSandbox sandbox;  // allow_files = false: every external uri is refused
    return load_from_bytes(bytes, display_name, sandbox);
}

}  // namespace photond
