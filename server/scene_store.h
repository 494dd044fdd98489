// Uploaded scenes (POST /v1/scenes), stored by content (the SHA-256 of the uploaded bytes):
// <directory>/<sha256>.glb or .gltf, or for a bundle (a zip, tar or tar.gz of a .gltf with its
// sibling files, scene_bundle.h) the unpacked directory <directory>/<sha256>.bundle/; the
// metadata lies beside them in <sha256>.json. An upload is validated by loading it
// (load_gltf_memory: a .glb or a self-contained .gltf; load_gltf_file with the bundle directory
// as the bundle root for a bundle) before it is kept. Jobs name an upload as
// {"scene": {"id": "sha256:<hex>"}}; lookup() loads it and keeps the last few loaded scenes.
//
// Thread safety: every member may be called from any thread at once (one mutex guards the
// loaded-scene cache; files are written to a temporary name and renamed, so concurrent uploads
// of the same bytes, even by several daemons sharing the directory, are harmless; a bundle is
// unpacked into a temporary directory that is renamed into place).
#pragma once

#include <cstdint>
#include <filesystem>
#include <list>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "core/scene/scene.h"
#include "core/util/expected.h"
#include "server/scene_bundle.h"

namespace photond::service {

/// GET /v1/scenes/{id}.
struct SceneInfo {
    std::string id;      // "sha256:<64 hex digits>"
    std::string format;  // "glb" or "gltf": the scene file's own format
    uint64_t bytes = 0;  // of the upload (for a bundle: the archive)
    // Bundles only: "zip", "tar" or "tar.gz" (empty for a plain upload), the glTF file's path
    // inside the bundle, and the files unpacked.
    std::string bundle;
    std::string entry;
    uint64_t files = 0;
    std::string name;
    uint64_t triangles = 0;
    uint64_t vertices = 0;
    uint64_t materials = 0;
    uint64_t textures = 0;
    uint64_t lights = 0;  // punctual lights (KHR_lights_punctual)
    uint64_t emissive_triangles = 0;
    uint64_t cameras = 0;
    Bounds3 bounds;
    /// Scene::warnings: what the file holds that the renderer ignores or takes its own way.
    std::vector<std::string> warnings;
};

nlohmann::json to_json(const SceneInfo& info);

class SceneStore {
public:
    explicit SceneStore(std::filesystem::path directory, BundleLimits bundle_limits = {},
                        size_t loaded_scenes_kept = 4);

    struct Added {
        SceneInfo info;
        bool created = false;  // false: these bytes were already stored
    };
    /// Why an upload was refused: the loader's or the bundle check's message.
    struct Refused {
        bool over_limit = false;  // a bundle beyond BundleLimits (HTTP 413), else invalid (422)
        std::string message;
    };
    /// Validates and stores an upload: a .glb, a self-contained .gltf, or a bundle (told apart
    /// by magic bytes, detect_bundle_format).
    std::variant<Added, Refused> add(std::span<const uint8_t> bytes);

    /// The metadata of a stored scene; nullopt when unknown. `id` is "sha256:<hex>" or "<hex>".
    std::optional<SceneInfo> info(const std::string& id);
    bool contains(const std::string& id) const;
    /// Removes the scene; false when it was not there.
    bool remove(const std::string& id);
    /// Every stored scene, sorted by id.
    std::vector<SceneInfo> list();

    /// The loaded scene, for the render pipeline (service::SceneLookup).
    Expected<std::shared_ptr<const Scene>> lookup(const std::string& id);

    /// The directory an uploaded bundle was unpacked into: the root below which its files (the
    /// glTF's buffers and images, environment images) may be read, with the same sandbox rules
    /// as scene files. nullopt for an unknown id and for a plain .glb or .gltf upload.
    std::optional<std::filesystem::path> bundle_root(const std::string& id) const;

    /// "sha256:<hex>" for "sha256:<hex>" or "<hex>" (64 lower-case hex digits); nullopt else.
    static std::optional<std::string> normalize_id(const std::string& id);

private:
    /// The stored file of a normalized id, if any.
    std::optional<std::filesystem::path> file_of(const std::string& normalized_id) const;
    std::filesystem::path metadata_file_of(const std::string& normalized_id) const;
    std::filesystem::path bundle_dir_of(const std::string& normalized_id) const;
    /// Loads a stored scene (plain or bundle) and describes it.
    Expected<std::pair<Scene, SceneInfo>> load_stored(const std::string& normalized_id) const;
    std::variant<Added, Refused> add_bundle(std::span<const uint8_t> bytes, BundleFormat format,
                                            const std::string& id);
    void remember_loaded(const std::string& id, std::shared_ptr<const Scene> scene);

    std::filesystem::path directory_;
    BundleLimits bundle_limits_;
    size_t loaded_scenes_kept_;
    mutable std::mutex mutex_;
    std::list<std::pair<std::string, std::shared_ptr<const Scene>>> loaded_;  // front = newest
};

}  // namespace photond::service
