// The daemon's render-cache store: irradiance caches by render-cache key
// (PhotonMapIntegrator::render_cache_key), so that a view's cache prepass runs once for all its
// jobs, regions and nodes. Memory and disk (<directory>/<key>.rc), as every ArtifactCache
// (server/artifact_cache.h); the file format is core/integrators/irradiance_cache_io.h.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/integrators/irradiance_cache.h"
#include "core/util/expected.h"
#include "server/artifact_cache.h"
#include "server/render_pipeline.h"

namespace photond::service {

/// Irradiance caches as cache artifacts (see ArtifactCache for what each member is for).
struct RenderCacheFiles {
    using Value = IrradianceCache;
    static constexpr const char* kExtension = ".rc";
    static constexpr const char* kName = "render-cache";
    static constexpr const char* kKeyForm = "rc1-<64 hex digits>";
    static constexpr const char* kRebuilt = "the cache is built again";
    static constexpr const char* kNotForThisKey = "this cache was not built for this key";

    /// "rc<version>-<64 hex digits>".
    static bool is_valid_key(std::string_view key);
    static size_t bytes(const Value& cache) { return cache.memory_bytes(); }
    static Status write_file(const std::filesystem::path& path, const Value& cache, const std::string& key);
    static Expected<std::shared_ptr<const Value>> read_file(const std::filesystem::path& path, const std::string& key);
    static Expected<std::vector<uint8_t>> serialize(const Value& cache, const std::string& key);
    static Expected<std::shared_ptr<const Value>> deserialize(std::span<const uint8_t> bytes, const std::string& key);
    static std::string read_key(std::span<const uint8_t> bytes);
    /// The same records and octree, bit for bit.
    static bool same_content(const Value& a, const Value& b);
};

class RenderCacheDirectory final : public ArtifactCache<RenderCacheFiles>, public RenderCacheStore {
public:
    using ArtifactCache::ArtifactCache;

    Expected<std::shared_ptr<const IrradianceCache>> get_or_build(
        const std::string& key, const std::function<Expected<std::shared_ptr<const IrradianceCache>>()>& build,
        bool* cache_hit) override {
        return ArtifactCache::get_or_build(key, build, cache_hit);
    }
    std::shared_ptr<const IrradianceCache> find_cache(const std::string& key) override { return find(key); }
};

}  // namespace photond::service
