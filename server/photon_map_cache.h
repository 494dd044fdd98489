// The daemon's photon-map cache: built photon maps by content key (photon_map_key in
// core/scene/scene_hash.h), so that further camera views of a scene skip photon tracing.
//
// Two levels. In memory: an LRU list bounded by the maps' bytes (PhotonMaps::bytes()). On disk:
// one file per key, <directory>/<key>.pm, written by write_photon_maps_file (a unique temporary
// name, then rename), so that several daemons sharing the directory (NFS, a farm's cache) never
// read a half-written map. A file that fails its checks (truncated, corrupt, another key or
// format version) is moved aside to <key>.pm.corrupt and the maps are traced again.
//
// Thread safety: every member may be called from any thread at once. One mutex guards the LRU
// and the table of builds in flight; tracing, file reads and writes run outside it. Concurrent
// get_or_build calls for one key trace once: the first caller builds, the others wait for it and
// then take its maps (a failed build is not cached: the next waiter tries itself). Across
// processes nothing is locked: two daemons may both trace a missing key, and the second rename
// wins with identical content.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "server/render_pipeline.h"

namespace photond::service {

class PhotonMapCache final : public PhotonMapStore {
public:
    /// `directory` is created when missing; `memory_budget_bytes` bounds the in-memory maps
    /// (maps larger than the budget stay on disk only). `log` receives one line per notable
    /// event (a corrupt file moved aside, a failed write); may be empty.
    PhotonMapCache(std::filesystem::path directory, size_t memory_budget_bytes,
                   std::function<void(const std::string&)> log = {});

    /// Memory, then disk, then `build` (whose maps are then kept in memory and written to disk).
    /// `cache_hit` is true when the maps came from memory or disk.
    Expected<std::shared_ptr<const PhotonMaps>> get_or_build(
        const std::string& key, const std::function<Expected<PhotonMaps>()>& build,
        bool* cache_hit) override;

    /// The file format bytes of the maps for `key` (from disk, else serialized from memory);
    /// nullopt when the key is unknown here.
    std::optional<std::vector<uint8_t>> export_maps(const std::string& key);

    /// Imports maps exported by another node. The bytes are checked (format, checksum, kd-tree,
    /// and that they were written for `key`); an Error says what is wrong. Returns true when the
    /// key was new, false when the same photons were already kept. Different photons than a
    /// valid map kept under the key are refused, with *conflict set.
    Expected<bool> import_maps(const std::string& key, std::span<const uint8_t> bytes, bool* conflict = nullptr);

    /// The keys on disk or in memory, sorted.
    std::vector<std::string> keys() const;

    struct Counters {
        uint64_t hits = 0;          // get_or_build answered from memory or disk
        uint64_t misses = 0;        // get_or_build traced the maps
        uint64_t memory_bytes = 0;  // bytes of the maps held in memory now
        uint64_t memory_entries = 0;
        uint64_t corrupt_files = 0;  // files on disk refused and moved aside
    };
    Counters counters() const;

    /// "pm<version>-<64 hex digits>": the only keys accepted (they become file names).
    static bool is_valid_key(std::string_view key);

    const std::filesystem::path& directory() const { return directory_; }

private:
    std::filesystem::path file_of(const std::string& key) const;
    /// The maps from disk; nullopt when there is no usable file (a corrupt one is moved aside).
    std::optional<std::shared_ptr<const PhotonMaps>> read_disk(const std::string& key);
    /// Keeps maps in memory (most recently used) and evicts the least recently used beyond the
    /// budget. Caller holds mutex_.
    void insert_locked(const std::string& key, std::shared_ptr<const PhotonMaps> maps);
    std::shared_ptr<const PhotonMaps> find_locked(const std::string& key);
    void log(const std::string& line) const;

    std::filesystem::path directory_;
    size_t memory_budget_bytes_;
    std::function<void(const std::string&)> log_;

    mutable std::mutex mutex_;
    std::condition_variable build_finished_;
    struct Entry {
        std::shared_ptr<const PhotonMaps> maps;
        size_t bytes = 0;
        std::list<std::string>::iterator lru_position;
    };
    std::unordered_map<std::string, Entry> entries_;
    std::list<std::string> lru_;      // front = most recently used
    std::set<std::string> building_;  // keys being traced (or read from disk) now
    Counters counters_;
};

}  // namespace photond::service
