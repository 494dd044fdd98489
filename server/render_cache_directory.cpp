#include "server/render_cache_directory.h"

#include <regex>

#include "core/integrators/irradiance_cache_io.h"

namespace photond::service {

bool RenderCacheFiles::is_valid_key(std::string_view key) {
    static const std::regex pattern("rc[0-9]{1,4}-[0-9a-f]{64}");
    return std::regex_match(key.begin(), key.end(), pattern);
}

Status RenderCacheFiles::write_file(const std::filesystem::path& path, const Value& cache, const std::string& key) {
    return write_irradiance_cache_file(path, cache, key);
}

Expected<std::shared_ptr<const IrradianceCache>> RenderCacheFiles::read_file(const std::filesystem::path& path,
                                                                             const std::string& key) {
    auto cache = read_irradiance_cache_file(path, key);
    if (!cache) return cache.error();
    return std::shared_ptr<const IrradianceCache>(std::move(cache).value());
}

Expected<std::vector<uint8_t>> RenderCacheFiles::serialize(const Value& cache, const std::string& key) {
    return serialize_irradiance_cache(cache, key);
}

Expected<std::shared_ptr<const IrradianceCache>> RenderCacheFiles::deserialize(std::span<const uint8_t> bytes,
                                                                               const std::string& key) {
    auto cache = deserialize_irradiance_cache(bytes, key);
    if (!cache) return cache.error();
    return std::shared_ptr<const IrradianceCache>(std::move(cache).value());
}

std::string RenderCacheFiles::read_key(std::span<const uint8_t> bytes) { return read_irradiance_cache_key(bytes); }

bool RenderCacheFiles::same_content(const Value& a, const Value& b) {
    const auto x = serialize_irradiance_cache(a, "");
    const auto y = serialize_irradiance_cache(b, "");
    return x && y && *x == *y;
}

}  // namespace photond::service
