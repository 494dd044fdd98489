#include "server/metrics.h"

#include <cstdio>

namespace photond::service {
namespace {

std::string number(double value) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.9g", value);
    return buffer;
}

void header(std::string& out, const char* name, const char* type, const char* help) {
    out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
}

void sample(std::string& out, const std::string& name, uint64_t value) {
    out += name + " " + std::to_string(value) + "\n";
}

}  // namespace

void Metrics::record_pass(const std::string& pass, double seconds) {
    std::lock_guard lock(mutex_);
    Histogram& h = pass_seconds_[pass];
    for (size_t i = 0; i < kPassBuckets.size(); ++i)
        if (seconds <= kPassBuckets[i]) ++h.buckets[i];
    ++h.count;
    h.sum += seconds;
}

void Metrics::record_response(int status) {
    const int index = status >= 100 && status < 600 ? status / 100 : 0;
    responses_[static_cast<size_t>(index)].fetch_add(1, std::memory_order_relaxed);
}

std::string Metrics::render(const MetricsSnapshot& s) const {
    std::string out;
    header(out, "photond_jobs", "gauge", "Jobs known to the daemon, by state.");
    for (const auto& [state, count] : s.jobs_by_state)
        sample(out, "photond_jobs{state=\"" + state + "\"}", count);
    header(out, "photond_jobs_submitted_total", "counter", "Jobs accepted by POST /v1/jobs.");
    sample(out, "photond_jobs_submitted_total", jobs_submitted_.load());
    header(out, "photond_queue_jobs", "gauge", "Jobs waiting in the queue.");
    sample(out, "photond_queue_jobs", s.queue_depth);
    header(out, "photond_tiles_rendered_total", "counter", "Tiles finished by the renderer.");
    sample(out, "photond_tiles_rendered_total", tiles_rendered_.load());
    header(out, "photond_rays_total", "counter",
           "Rays traced by finished renders (intersection and shadow rays).");
    sample(out, "photond_rays_total", rays_.load());
    header(out, "photond_store_write_failures_total", "counter",
           "Job states the cache directory refused to take (the job carries a warning).");
    sample(out, "photond_store_write_failures_total", store_failures_.load());
    header(out, "photond_photon_cache_hits_total", "counter",
           "Photon maps taken from the cache (memory or disk) instead of traced.");
    sample(out, "photond_photon_cache_hits_total", s.photon_cache_hits);
    header(out, "photond_photon_cache_misses_total", "counter", "Photon maps traced.");
    sample(out, "photond_photon_cache_misses_total", s.photon_cache_misses);
    header(out, "photond_photon_cache_bytes", "gauge", "Bytes of photon maps held in memory.");
    sample(out, "photond_photon_cache_bytes", s.photon_cache_bytes);
    header(out, "photond_photon_cache_entries", "gauge", "Photon-map sets held in memory.");
    sample(out, "photond_photon_cache_entries", s.photon_cache_entries);
    header(out, "photond_render_cache_hits_total", "counter",
           "Jobs whose irradiance cache came from the render-cache store (memory or disk).");
    sample(out, "photond_render_cache_hits_total", s.render_cache_hits);
    header(out, "photond_render_cache_misses_total", "counter", "Irradiance caches built by a prepass.");
    sample(out, "photond_render_cache_misses_total", s.render_cache_misses);
    header(out, "photond_render_cache_bytes", "gauge", "Bytes of irradiance caches held in memory.");
    sample(out, "photond_render_cache_bytes", s.render_cache_bytes);
    header(out, "photond_render_cache_entries", "gauge", "Irradiance caches held in memory.");
    sample(out, "photond_render_cache_entries", s.render_cache_entries);
    header(out, "photond_http_responses_total", "counter", "HTTP responses by status class.");
    for (size_t i = 1; i < responses_.size(); ++i)
        sample(out, "photond_http_responses_total{code=\"" + std::to_string(i) + "xx\"}",
               responses_[i].load());
    const std::string pass_duration = "photond_pass_duration_seconds";
    header(out, pass_duration.c_str(), "histogram", "Duration of the render passes of jobs.");
    std::lock_guard lock(mutex_);
    for (const auto& [pass, h] : pass_seconds_) {
        const std::string label = "pass=\"" + pass + "\"";
        for (size_t i = 0; i < kPassBuckets.size(); ++i)
            sample(out,
                   pass_duration + "_bucket{" + label + ",le=\"" + number(kPassBuckets[i]) + "\"}",
                   h.buckets[i]);
        sample(out, pass_duration + "_bucket{" + label + ",le=\"+Inf\"}", h.count);
        out += pass_duration + "_sum{" + label + "} " + number(h.sum) + "\n";
        sample(out, pass_duration + "_count{" + label + "}", h.count);
    }
    return out;
}

}  // namespace photond::service
