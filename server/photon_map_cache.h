// The daemon's photon-map cache: built photon maps by content key (photon_map_key in
// core/photon/photon_map_key.h), so that further camera views of a scene skip photon tracing. Memory
// and disk (<directory>/<key>.pm), as every ArtifactCache (server/artifact_cache.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/photon/photon_tracer.h"
#include "core/util/expected.h"
#include "server/artifact_cache.h"
#include "server/render_pipeline.h"

namespace photond::service {

/// Photon maps as cache artifacts (see ArtifactCache for what each member is for).
struct PhotonMapFiles {
    using Value = PhotonMaps;
    static constexpr const char* kExtension = ".pm";
    static constexpr const char* kName = "photon-map";
    static constexpr const char* kKeyForm = "pm1-<64 hex digits>";
    static constexpr const char* kRebuilt = "the maps are traced again";
    static constexpr const char* kNotForThisKey = "these photons were not traced for this key";

    /// "pm<version>-<64 hex digits>".
    static bool is_valid_key(std::string_view key);
    static size_t bytes(const Value& maps) { return maps.bytes(); }
    static Status write_file(const std::filesystem::path& path, const Value& maps, const std::string& key);
    static Expected<std::shared_ptr<const Value>> read_file(const std::filesystem::path& path, const std::string& key);
    static Expected<std::vector<uint8_t>> serialize(const Value& maps, const std::string& key);
    static Expected<std::shared_ptr<const Value>> deserialize(std::span<const uint8_t> bytes, const std::string& key);
    static std::string read_key(std::span<const uint8_t> bytes);
    /// The same photons (bit for bit, in the same order) and emission counts in every map; the
    /// statistics' timings may differ between two traces of one key.
    static bool same_content(const Value& a, const Value& b);
};

class PhotonMapCache final : public ArtifactCache<PhotonMapFiles>, public PhotonMapStore {
public:
    using ArtifactCache::ArtifactCache;

    Expected<std::shared_ptr<const PhotonMaps>> get_or_build(
        const std::string& key, const std::function<Expected<PhotonMaps>()>& build, bool* cache_hit) override;

    /// ArtifactCache::export_bytes and import_bytes, by their photon-map names.
    std::optional<std::vector<uint8_t>> export_maps(const std::string& key) { return export_bytes(key); }
    Expected<bool> import_maps(const std::string& key, std::span<const uint8_t> bytes, bool* conflict = nullptr) {
        return import_bytes(key, bytes, conflict);
    }
};

}  // namespace photond::service
