// Scene bundles: a .gltf with its sibling files (buffers, textures, environment images) uploaded
// as one zip, tar or tar.gz archive (POST /v1/scenes), read with libarchive and unpacked by our
// own code under the sandbox rules of uploaded scenes:
//   - only regular files and directories; symbolic links, hard links, devices, FIFOs and sockets
//     are refused by name;
//   - every entry path is relative and stays inside the bundle: no leading '/', no drive letter,
//     no ".." component, no backslash, no control character ("." and empty components are
//     dropped, so "./scene.gltf" is "scene.gltf");
//   - at most BundleLimits::max_entries entries and max_unpacked_bytes bytes unpacked in all (a
//     zip bomb stops at the limit, and the error says which limit);
//   - exactly one .gltf or .glb file at the bundle's top level, or, when the top level holds no
//     glTF file and a single directory (an archive of a folder), at that directory's top level.
//     glTF files further down are ordinary files of the bundle.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>

namespace photond::service {

enum class BundleFormat { Zip, Tar, TarGzip };

/// By magic bytes: zip "PK\3\4", tar "ustar" at offset 257 (after NUL-terminated header
/// fields), gzip 1f 8b (taken as tar.gz).
/// nullopt for anything else (a .glb or a .gltf).
std::optional<BundleFormat> detect_bundle_format(std::span<const uint8_t> bytes);

/// "zip", "tar" or "tar.gz".
std::string_view to_string(BundleFormat format);

struct BundleLimits {
    uint64_t max_unpacked_bytes = uint64_t{1} << 30;  // photond serve --max-bundle-mb
    uint64_t max_entries = 4096;                      // photond serve --max-bundle-entries
};

/// Why a bundle was refused.
struct BundleError {
    bool over_limit = false;  // a size or entry-count limit (HTTP 413), else a bad bundle (422)
    std::string message;      // names the entry or the limit
};

struct UnpackedBundle {
    std::filesystem::path scene_file;  // relative to the bundle directory
    uint64_t files = 0;                // regular files unpacked
    uint64_t bytes = 0;                // their total size
};

/// Unpacks `archive` into `directory`, which must not exist yet (it is created, and removed
/// again on failure), and finds its glTF file (find_bundle_scene).
std::variant<UnpackedBundle, BundleError> unpack_scene_bundle(
    std::span<const uint8_t> archive, BundleFormat format, const std::filesystem::path& directory,
    const BundleLimits& limits);

/// The bundle's one glTF file, relative to `directory` (the rule in the comment above).
std::variant<std::filesystem::path, BundleError> find_bundle_scene(
    const std::filesystem::path& directory);

}  // namespace photond::service
