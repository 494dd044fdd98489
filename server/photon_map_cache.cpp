#include "server/photon_map_cache.h"

#include <algorithm>
#include <cstring>
#include <regex>
#include <system_error>

#include "core/photon/photon_map_io.h"
#include "server/atomic_file.h"

namespace photond::service {
namespace {

namespace fs = std::filesystem;

constexpr const char* kExtension = ".pm";

}  // namespace

PhotonMapCache::PhotonMapCache(fs::path directory, size_t memory_budget_bytes,
                               std::function<void(const std::string&)> log)
    : directory_(std::move(directory)),
      memory_budget_bytes_(memory_budget_bytes),
      log_(std::move(log)) {
    std::error_code ignored;
    fs::create_directories(directory_, ignored);
}

bool PhotonMapCache::is_valid_key(std::string_view key) {
    static const std::regex pattern("pm[0-9]{1,4}-[0-9a-f]{64}");
    return std::regex_match(key.begin(), key.end(), pattern);
}

fs::path PhotonMapCache::file_of(const std::string& key) const {
    return directory_ / (key + kExtension);
}

void PhotonMapCache::log(const std::string& line) const {
    if (log_) log_(line);
}

std::shared_ptr<const PhotonMaps> PhotonMapCache::find_locked(const std::string& key) {
    const auto it = entries_.find(key);
    if (it == entries_.end()) return nullptr;
    lru_.splice(lru_.begin(), lru_, it->second.lru_position);
    return it->second.maps;
}

void PhotonMapCache::insert_locked(const std::string& key, std::shared_ptr<const PhotonMaps> maps) {
    const size_t bytes = maps->bytes();
    if (bytes > memory_budget_bytes_) return;  // on disk only
    if (auto it = entries_.find(key); it != entries_.end()) {
        counters_.memory_bytes -= it->second.bytes;
        lru_.erase(it->second.lru_position);
        entries_.erase(it);
    }
    lru_.push_front(key);
    entries_[key] = Entry{std::move(maps), bytes, lru_.begin()};
    counters_.memory_bytes += bytes;
    // Jobs still rendering with an evicted map keep it alive through their shared_ptr.
    while (counters_.memory_bytes > memory_budget_bytes_ && !lru_.empty()) {
        const std::string& oldest = lru_.back();
        const auto it = entries_.find(oldest);
        counters_.memory_bytes -= it->second.bytes;
        entries_.erase(it);
        lru_.pop_back();
    }
    counters_.memory_entries = entries_.size();
}

std::optional<std::shared_ptr<const PhotonMaps>> PhotonMapCache::read_disk(const std::string& key) {
    const fs::path path = file_of(key);
    std::error_code error;
    if (!fs::exists(path, error)) return std::nullopt;
    auto maps = read_photon_maps_file(path, key);
    if (maps) return std::make_shared<const PhotonMaps>(std::move(maps).value());
    // Corrupt, truncated or foreign: keep it for inspection but out of the way, and trace anew.
    fs::rename(path, fs::path(path.string() + ".corrupt"), error);
    if (error) fs::remove(path, error);
    {
        std::lock_guard lock(mutex_);
        ++counters_.corrupt_files;
    }
    log("photon-map cache: " + maps.error().message + "; moved aside, the maps are traced again");
    return std::nullopt;
}

Expected<std::shared_ptr<const PhotonMaps>> PhotonMapCache::get_or_build(
    const std::string& key, const std::function<Expected<PhotonMaps>()>& build, bool* cache_hit) {
    if (cache_hit) *cache_hit = false;
    {
        std::unique_lock lock(mutex_);
        // Wait while another caller builds this key; then take its maps or build ourselves.
        build_finished_.wait(lock, [&] { return !building_.contains(key); });
        if (auto maps = find_locked(key)) {
            ++counters_.hits;
            if (cache_hit) *cache_hit = true;
            return maps;
        }
        building_.insert(key);
    }
    // Whatever happens below, the key stops being "in flight" and waiters wake up.
    struct Release {
        PhotonMapCache& cache;
        const std::string& key;
        ~Release() {
            {
                std::lock_guard lock(cache.mutex_);
                cache.building_.erase(key);
            }
            cache.build_finished_.notify_all();
        }
    } release{*this, key};

    if (auto maps = read_disk(key)) {
        std::lock_guard lock(mutex_);
        insert_locked(key, *maps);
        ++counters_.hits;
        if (cache_hit) *cache_hit = true;
        return *maps;
    }
    auto built = build();
    if (!built) return built.error();
    auto maps = std::make_shared<const PhotonMaps>(std::move(built).value());
    if (Status written = write_photon_maps_file(file_of(key), *maps, key); !written)
        log("photon-map cache: " + written.error().message + " (kept in memory only)");
    std::lock_guard lock(mutex_);
    insert_locked(key, maps);
    ++counters_.misses;
    return maps;
}

std::optional<std::vector<uint8_t>> PhotonMapCache::export_maps(const std::string& key) {
    if (!is_valid_key(key)) return std::nullopt;
    if (auto bytes = read_file_bytes(file_of(key)); bytes && read_photon_map_key(*bytes) == key)
        return bytes;
    std::shared_ptr<const PhotonMaps> maps;
    {
        std::lock_guard lock(mutex_);
        maps = find_locked(key);
    }
    if (!maps) return std::nullopt;
    auto bytes = serialize_photon_maps(*maps, key);
    if (!bytes) return std::nullopt;
    return std::move(bytes).value();
}

namespace {

/// The same photons (bit for bit, in the same order) and emission counts in every map; the
/// statistics' timings may differ between two traces of one key.
bool same_photons(const PhotonMaps& a, const PhotonMaps& b) {
    const auto same = [](const std::shared_ptr<const PhotonMap>& x, const std::shared_ptr<const PhotonMap>& y) {
        if (!x || !y) return !x && !y;
        const std::span<const Photon> p = x->tree().photons(), q = y->tree().photons();
        return x->emitted() == y->emitted() && p.size() == q.size() &&
               std::memcmp(p.data(), q.data(), p.size_bytes()) == 0;
    };
    return same(a.global, b.global) && same(a.caustic, b.caustic) && same(a.irradiance, b.irradiance);
}

}  // namespace

Expected<bool> PhotonMapCache::import_maps(const std::string& key, std::span<const uint8_t> bytes, bool* conflict) {
    if (conflict) *conflict = false;
    if (!is_valid_key(key))
        return Error{"'" + key + "' is not a photon-map key (pm1-<64 hex digits>)"};
    auto maps = deserialize_photon_maps(bytes, key);
    if (!maps) return maps.error();
    auto shared = std::make_shared<const PhotonMaps>(std::move(maps).value());
    std::error_code error;
    const bool on_disk = fs::exists(file_of(key), error);
    std::shared_ptr<const PhotonMaps> kept;
    {
        std::lock_guard lock(mutex_);
        kept = find_locked(key);
    }
    const bool in_memory = kept != nullptr;
    if (!kept && on_disk) {
        if (auto file = read_file_bytes(file_of(key))) {
            if (auto valid = deserialize_photon_maps(*file, key))
                kept = std::make_shared<const PhotonMaps>(std::move(valid).value());
        }
    }
    // Maps are keyed by what they were traced from: a valid one kept under this key is never
    // replaced by different photons (relabelled maps of another scene were taken, and the next
    // render reported a cache hit with another image). A corrupt file is replaced.
    if (kept) {
        if (same_photons(*kept, *shared)) return false;
        if (conflict) *conflict = true;
        return Error{"a different valid photon map is already kept under " + key +
                     ": photon maps are keyed by the scene and settings they were traced from, so these photons were "
                     "not traced for this key (the kept map stays)"};
    }
    // Written even when a file exists: it may be a corrupt one, and the rename is atomic.
    if (Status written = write_photon_maps_file(file_of(key), *shared, key); !written)
        return written.error();
    std::lock_guard lock(mutex_);
    insert_locked(key, shared);
    return !(on_disk || in_memory);
}

std::vector<std::string> PhotonMapCache::keys() const {
    std::set<std::string> keys;
    {
        std::lock_guard lock(mutex_);
        for (const auto& [key, entry] : entries_) keys.insert(key);
    }
    std::error_code error;
    for (fs::directory_iterator it(directory_, error), end; !error && it != end;
         it.increment(error)) {
        const fs::path& path = it->path();
        if (path.extension() != kExtension) continue;
        const std::string key = path.stem().string();
        if (is_valid_key(key)) keys.insert(key);
    }
    return {keys.begin(), keys.end()};
}

PhotonMapCache::Counters PhotonMapCache::counters() const {
    std::lock_guard lock(mutex_);
    return counters_;
}

}  // namespace photond::service
