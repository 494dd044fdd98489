#include "server/photon_map_cache.h"

#include <cstring>
#include <regex>

#include "core/photon/photon_map_io.h"

namespace photond::service {

bool PhotonMapFiles::is_valid_key(std::string_view key) {
    static const std::regex pattern("pm[0-9]{1,4}-[0-9a-f]{64}");
    return std::regex_match(key.begin(), key.end(), pattern);
}

Status PhotonMapFiles::write_file(const std::filesystem::path& path, const Value& maps, const std::string& key) {
    return write_photon_maps_file(path, maps, key);
}

Expected<std::shared_ptr<const PhotonMaps>> PhotonMapFiles::read_file(const std::filesystem::path& path,
                                                                       const std::string& key) {
    auto maps = read_photon_maps_file(path, key);
    if (!maps) return maps.error();
    return std::make_shared<const PhotonMaps>(std::move(maps).value());
}

Expected<std::vector<uint8_t>> PhotonMapFiles::serialize(const Value& maps, const std::string& key) {
    return serialize_photon_maps(maps, key);
}

Expected<std::shared_ptr<const PhotonMaps>> PhotonMapFiles::deserialize(std::span<const uint8_t> bytes,
                                                                         const std::string& key) {
    auto maps = deserialize_photon_maps(bytes, key);
    if (!maps) return maps.error();
    return std::make_shared<const PhotonMaps>(std::move(maps).value());
}

std::string PhotonMapFiles::read_key(std::span<const uint8_t> bytes) { return read_photon_map_key(bytes); }

bool PhotonMapFiles::same_content(const Value& a, const Value& b) {
    const auto same = [](const std::shared_ptr<const PhotonMap>& x, const std::shared_ptr<const PhotonMap>& y) {
        if (!x || !y) return !x && !y;
        const std::span<const Photon> p = x->tree().photons(), q = y->tree().photons();
        return x->emitted() == y->emitted() && p.size() == q.size() &&
               std::memcmp(p.data(), q.data(), p.size_bytes()) == 0;
    };
    return same(a.global, b.global) && same(a.caustic, b.caustic) && same(a.irradiance, b.irradiance) &&
           same(a.caustic_irradiance, b.caustic_irradiance);
}

Expected<std::shared_ptr<const PhotonMaps>> PhotonMapCache::get_or_build(
    const std::string& key, const std::function<Expected<PhotonMaps>()>& build, bool* cache_hit) {
    return ArtifactCache::get_or_build(
        key,
        [&]() -> Expected<std::shared_ptr<const PhotonMaps>> {
            auto built = build();
            if (!built) return built.error();
            return std::make_shared<const PhotonMaps>(std::move(built).value());
        },
        cache_hit);
}

}  // namespace photond::service
