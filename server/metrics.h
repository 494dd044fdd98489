// Counters of the daemon and their Prometheus text exposition (format 0.0.4) for GET /metrics.
//
// Thread safety: the record_* members may be called from any thread at once (atomics, and a mutex
// for the per-pass histograms); render() reads a consistent-enough snapshot.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace photond::service {

/// What the job manager and the photon-map cache report at scrape time.
struct MetricsSnapshot {
    std::map<std::string, uint64_t> jobs_by_state;  // every state name, 0 included
    uint64_t queue_depth = 0;
    uint64_t photon_cache_hits = 0;
    uint64_t photon_cache_misses = 0;
    uint64_t photon_cache_bytes = 0;
    uint64_t photon_cache_entries = 0;
    uint64_t render_cache_hits = 0;
    uint64_t render_cache_misses = 0;
    uint64_t render_cache_bytes = 0;
    uint64_t render_cache_entries = 0;
};

class Metrics {
public:
    void record_submitted() { jobs_submitted_.fetch_add(1, std::memory_order_relaxed); }
    void record_tile() { tiles_rendered_.fetch_add(1, std::memory_order_relaxed); }
    void record_rays(uint64_t rays) { rays_.fetch_add(rays, std::memory_order_relaxed); }
    /// A job record or status the cache directory refused to take.
    void record_store_failure() { store_failures_.fetch_add(1, std::memory_order_relaxed); }
    /// One pass of one job ("scene", "photon_tracing", "render", ...).
    void record_pass(const std::string& pass, double seconds);
    /// One HTTP response, by status class.
    void record_response(int status);

    /// The exposition text: the counters here plus the snapshot's gauges.
    std::string render(const MetricsSnapshot& snapshot) const;

    /// Upper bounds of the pass-duration histogram buckets, in seconds.
    static constexpr std::array<double, 10> kPassBuckets{0.001, 0.01, 0.05, 0.1,   0.5,
                                                         1.0,   5.0,  30.0, 120.0, 600.0};

private:
    struct Histogram {
        std::array<uint64_t, kPassBuckets.size()> buckets{};  // cumulative counts per bound
        uint64_t count = 0;
        double sum = 0.0;
    };

    std::atomic<uint64_t> jobs_submitted_{0};
    std::atomic<uint64_t> tiles_rendered_{0};
    std::atomic<uint64_t> rays_{0};
    std::atomic<uint64_t> store_failures_{0};
    std::array<std::atomic<uint64_t>, 6> responses_{};  // 1xx..5xx by index 1..5, 0 = other
    mutable std::mutex mutex_;
    std::map<std::string, Histogram> pass_seconds_;
};

}  // namespace photond::service
