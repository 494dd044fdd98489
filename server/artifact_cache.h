// A cache of built artifacts by content key (photon maps, irradiance caches), so that later jobs
// of the same scene and settings skip the pass that builds them.
//
// Two levels. In memory: an LRU list bounded by the artifacts' bytes. On disk: one file per key,
// <directory>/<key><extension>, written through a unique temporary name and a rename, so that
// several daemons or render nodes sharing the directory (NFS, a farm's cache) never read a
// half-written file. A file that fails its checks (truncated, corrupt, another key or format
// version) is moved aside to <key><extension>.corrupt and the artifact is built again. An import
// (another node's export) never replaces a valid artifact kept under its key by a different one.
//
// What differs between artifacts comes from `Traits`:
//   using Value;                                    the artifact
//   static constexpr const char* kExtension;        ".pm"
//   static constexpr const char* kName;             "photon-map" (in messages)
//   static constexpr const char* kKeyForm;          "pm1-<64 hex digits>" (in messages)
//   static constexpr const char* kRebuilt;          "the maps are traced again"
//   static constexpr const char* kNotForThisKey;    "these photons were not traced for this key"
//   static bool is_valid_key(std::string_view);     keys become file names: nothing else passes
//   static size_t bytes(const Value&);              memory held, for the budget
//   static Status write_file(path, const Value&, const std::string& key);     atomic
//   static Expected<std::shared_ptr<const Value>> read_file(path, const std::string& key);
//   static Expected<std::vector<uint8_t>> serialize(const Value&, const std::string& key);
//   static Expected<std::shared_ptr<const Value>> deserialize(std::span<const uint8_t>, const std::string& key);
//   static std::string read_key(std::span<const uint8_t>);  header only; "" if not such a file
//   static bool same_content(const Value&, const Value&);   the same artifact (timings aside)
//
// Thread safety: every member may be called from any thread at once. One mutex guards the LRU
// and the table of builds in flight; building, file reads and writes run outside it. Concurrent
// get_or_build calls for one key build once: the first caller builds, the others wait for it and
// then take its artifact (a failed build is not cached: the next waiter tries itself). Across
// processes the same holds through a lock file per key (<key>.lock, server/file_lock.h): a
// process that finds the key being built elsewhere waits, then reads the file.
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
#include <system_error>
#include <unordered_map>
#include <vector>

#include "core/util/expected.h"
#include "core/util/file_io.h"
#include "server/file_lock.h"

namespace photond::service {

template <class Traits>
class ArtifactCache {
public:
    using Value = typename Traits::Value;

    /// `directory` is created when missing; `memory_budget_bytes` bounds the artifacts held in
    /// memory (larger ones stay on disk only). `log` receives one line per notable event (a
    /// corrupt file moved aside, a failed write); may be empty.
    ArtifactCache(std::filesystem::path directory, size_t memory_budget_bytes,
                  std::function<void(const std::string&)> log = {})
        : directory_(std::move(directory)), memory_budget_bytes_(memory_budget_bytes), log_(std::move(log)) {
        std::error_code ignored;
        std::filesystem::create_directories(directory_, ignored);
    }

    /// Memory, then disk, then `build` (whose artifact is then kept in memory and written to
    /// disk). `cache_hit` is true when the artifact came from memory or disk.
    Expected<std::shared_ptr<const Value>> get_or_build(
        const std::string& key, const std::function<Expected<std::shared_ptr<const Value>>()>& build,
        bool* cache_hit) {
        if (cache_hit) *cache_hit = false;
        {
            std::unique_lock lock(mutex_);
            // Wait while another caller builds this key; then take its artifact or build ourselves.
            build_finished_.wait(lock, [&] { return !building_.contains(key); });
            if (auto found = find_locked(key)) {
                ++counters_.hits;
                if (cache_hit) *cache_hit = true;
                return found;
            }
            building_.insert(key);
        }
        // Whatever happens below, the key stops being "in flight" and waiters wake up.
        struct Release {
            ArtifactCache& cache;
            const std::string& key;
            ~Release() {
                {
                    std::lock_guard lock(cache.mutex_);
                    cache.building_.erase(key);
                }
                cache.build_finished_.notify_all();
            }
        } release{*this, key};

        // Other processes sharing the directory: one builds, the others wait here and then read
        // its file.
        const FileLock other_processes(directory_ / (key + ".lock"));
        if (!other_processes.held())
            log(std::string(Traits::kName) + " cache: cannot lock " + key + ".lock in " + directory_.string() +
                "; another process sharing the directory may build this key too");
        if (auto found = read_disk(key)) {
            std::lock_guard lock(mutex_);
            insert_locked(key, *found);
            ++counters_.hits;
            if (cache_hit) *cache_hit = true;
            return *found;
        }
        auto built = build();
        if (!built) return built.error();
        if (Status written = Traits::write_file(file_of(key), **built, key); !written)
            log(std::string(Traits::kName) + " cache: " + written.error().message + " (kept in memory only)");
        std::lock_guard lock(mutex_);
        insert_locked(key, *built);
        ++counters_.misses;
        return *built;
    }

    /// The artifact for `key` from memory or disk (then kept in memory); nullptr when it is not
    /// here (a corrupt file is moved aside).
    std::shared_ptr<const Value> find(const std::string& key) {
        if (!Traits::is_valid_key(key)) return nullptr;
        {
            std::lock_guard lock(mutex_);
            if (auto found = find_locked(key)) return found;
        }
        auto found = read_disk(key);
        if (!found) return nullptr;
        std::lock_guard lock(mutex_);
        insert_locked(key, *found);
        return *found;
    }

    /// The file bytes of the artifact for `key` (from disk, else serialized from memory); nullopt
    /// when the key is unknown here.
    std::optional<std::vector<uint8_t>> export_bytes(const std::string& key) {
        if (!Traits::is_valid_key(key)) return std::nullopt;
        if (auto bytes = read_file_bytes(file_of(key)); bytes && Traits::read_key(*bytes) == key) return std::move(*bytes);
        std::shared_ptr<const Value> found;
        {
            std::lock_guard lock(mutex_);
            found = find_locked(key);
        }
        if (!found) return std::nullopt;
        auto bytes = Traits::serialize(*found, key);
        if (!bytes) return std::nullopt;
        return std::move(bytes).value();
    }

    /// Imports an artifact exported by another node. The bytes are checked (format, checksum,
    /// structure, and that they were written for `key`); an Error says what is wrong. Returns true
    /// when the key was new, false when the same artifact was already kept. A different one than
    /// a valid artifact kept under the key is refused, with *conflict set.
    Expected<bool> import_bytes(const std::string& key, std::span<const uint8_t> bytes, bool* conflict = nullptr) {
        if (conflict) *conflict = false;
        if (!Traits::is_valid_key(key))
            return Error{"'" + key + "' is not a " + Traits::kName + " key (" + Traits::kKeyForm + ")"};
        auto imported = Traits::deserialize(bytes, key);
        if (!imported) return imported.error();
        std::error_code error;
        const bool on_disk = std::filesystem::exists(file_of(key), error);
        std::shared_ptr<const Value> kept;
        {
            std::lock_guard lock(mutex_);
            kept = find_locked(key);
        }
        const bool in_memory = kept != nullptr;
        if (!kept && on_disk) {
            if (auto file = read_file_bytes(file_of(key))) {
                if (auto valid = Traits::deserialize(*file, key)) kept = *valid;
            }
        }
        // Artifacts are keyed by what they were built from: a valid one kept under this key is
        // never replaced by a different one (relabelled photon maps of another scene were taken,
        // and the next render reported a cache hit with another image). A corrupt file is replaced.
        if (kept) {
            if (Traits::same_content(*kept, **imported)) return false;
            if (conflict) *conflict = true;
            return Error{"a different valid " + std::string(Traits::kName) + " is already kept under " + key + ": " +
                         Traits::kName + " files are keyed by the scene and settings they were built from, so " +
                         Traits::kNotForThisKey + " (the kept one stays)"};
        }
        // Written even when a file exists: it may be a corrupt one, and the rename is atomic.
        if (Status written = Traits::write_file(file_of(key), **imported, key); !written) return written.error();
        std::lock_guard lock(mutex_);
        insert_locked(key, *imported);
        return !(on_disk || in_memory);
    }

    /// The keys on disk or in memory, sorted.
    std::vector<std::string> keys() const {
        std::set<std::string> keys;
        {
            std::lock_guard lock(mutex_);
            for (const auto& [key, entry] : entries_) keys.insert(key);
        }
        std::error_code error;
        for (std::filesystem::directory_iterator it(directory_, error), end; !error && it != end; it.increment(error)) {
            const std::filesystem::path& path = it->path();
            if (path.extension() != Traits::kExtension) continue;
            const std::string key = path.stem().string();
            if (Traits::is_valid_key(key)) keys.insert(key);
        }
        return {keys.begin(), keys.end()};
    }

    struct Counters {
        uint64_t hits = 0;          // get_or_build answered from memory or disk
        uint64_t misses = 0;        // get_or_build built the artifact
        uint64_t memory_bytes = 0;  // bytes of the artifacts held in memory now
        uint64_t memory_entries = 0;
        uint64_t corrupt_files = 0;  // files on disk refused and moved aside
    };
    Counters counters() const {
        std::lock_guard lock(mutex_);
        return counters_;
    }

    static bool is_valid_key(std::string_view key) { return Traits::is_valid_key(key); }
    const std::filesystem::path& directory() const { return directory_; }

private:
    std::filesystem::path file_of(const std::string& key) const { return directory_ / (key + Traits::kExtension); }

    void log(const std::string& line) const {
        if (log_) log_(line);
    }

    /// The artifact from disk; nullopt when there is no usable file (a corrupt one is moved aside).
    std::optional<std::shared_ptr<const Value>> read_disk(const std::string& key) {
        const std::filesystem::path path = file_of(key);
        std::error_code error;
        if (!std::filesystem::exists(path, error)) return std::nullopt;
        auto found = Traits::read_file(path, key);
        if (found) return *found;
        // Corrupt, truncated or foreign: kept for inspection but out of the way, and built anew.
        std::filesystem::rename(path, std::filesystem::path(path.string() + ".corrupt"), error);
        if (error) std::filesystem::remove(path, error);
        {
            std::lock_guard lock(mutex_);
            ++counters_.corrupt_files;
        }
        log(std::string(Traits::kName) + " cache: " + found.error().message + "; moved aside, " + Traits::kRebuilt);
        return std::nullopt;
    }

    std::shared_ptr<const Value> find_locked(const std::string& key) {
        const auto it = entries_.find(key);
        if (it == entries_.end()) return nullptr;
        lru_.splice(lru_.begin(), lru_, it->second.lru_position);
        return it->second.value;
    }

    /// Keeps an artifact in memory (most recently used) and evicts the least recently used beyond
    /// the budget. Caller holds mutex_.
    void insert_locked(const std::string& key, std::shared_ptr<const Value> value) {
        const size_t bytes = Traits::bytes(*value);
        if (bytes > memory_budget_bytes_) return;  // on disk only
        if (auto it = entries_.find(key); it != entries_.end()) {
            counters_.memory_bytes -= it->second.bytes;
            lru_.erase(it->second.lru_position);
            entries_.erase(it);
        }
        lru_.push_front(key);
        entries_[key] = Entry{std::move(value), bytes, lru_.begin()};
        counters_.memory_bytes += bytes;
        // Jobs still rendering with an evicted artifact keep it alive through their shared_ptr.
        while (counters_.memory_bytes > memory_budget_bytes_ && !lru_.empty()) {
            const auto it = entries_.find(lru_.back());
            counters_.memory_bytes -= it->second.bytes;
            entries_.erase(it);
            lru_.pop_back();
        }
        counters_.memory_entries = entries_.size();
    }

    std::filesystem::path directory_;
    size_t memory_budget_bytes_;
    std::function<void(const std::string&)> log_;

    mutable std::mutex mutex_;
    std::condition_variable build_finished_;
    struct Entry {
        std::shared_ptr<const Value> value;
        size_t bytes = 0;
        std::list<std::string>::iterator lru_position;
    };
    std::unordered_map<std::string, Entry> entries_;
    std::list<std::string> lru_;      // front = most recently used
    std::set<std::string> building_;  // keys being built (or read from disk) now
    Counters counters_;
};

}  // namespace photond::service
