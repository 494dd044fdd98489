#include "protocol/statistics.h"

namespace photond::protocol {

nlohmann::json to_json(const RenderStatistics& s) {
    nlohmann::json passes = nlohmann::json::array();
    for (const PassTiming& p : s.passes) passes.push_back({{"name", p.name}, {"seconds", p.seconds}});
    nlohmann::json result = {
        {"integrator", s.integrator},
        {"width", s.width},
        {"height", s.height},
        {"spp", s.samples_per_pixel},
        {"threads", s.threads},
        {"passes", passes},
        {"rays", s.rays},
        {"shadow_rays", s.shadow_rays},
        {"short_ray_bounces", s.short_ray_bounces},
        {"rays_per_second", s.rays_per_second()},
        {"render_seconds", s.render_seconds},
        {"total_seconds", s.total_seconds},
        {"cancelled", s.cancelled},
        {"tiles_restored", s.tiles_restored},
        {"warnings", s.warnings},
    };
    result["lighting"] = {{"lights", s.lighting.lights},
                          {"job_lights", s.lighting.job_lights},
                          {"environment", s.lighting.environment}};
    if (!s.plan.empty()) {
        nlohmann::json plan = nlohmann::json::array();
        for (const PassDecision& d : s.plan)
            plan.push_back({{"pass", d.pass}, {"enabled", d.enabled}, {"reason", d.reason}});
        result["plan"] = plan;
    }
    if (s.photons) {
        const PhotonTracingStatistics& p = *s.photons;
        result["photons"] = {
            {"emitted", p.emitted},
            {"emitted_global", p.emitted_global},
            {"emitted_caustic", p.emitted_caustic},
            {"stored_global", p.stored_global},
            {"stored_caustic", p.stored_caustic},
            {"emitted_volume", p.emitted_volume},
            {"stored_volume", p.stored_volume},
            {"volume_complete", p.volume_complete},
            {"rays", p.rays},
            {"tracing_seconds", p.tracing_seconds},
            {"build_seconds", p.build_seconds},
            {"global_complete", p.global_complete},
            {"caustic_complete", p.caustic_complete},
            {"map_bytes", s.photon_map_bytes},
            {"caustic_flux_share", s.caustic_flux_share},
            {"caustic_dropped", p.caustic_dropped},
            {"caustic_points", s.caustic_points},
            {"caustic_skipped", s.caustic_skipped},
        };
        if (p.caustic_tested) result["photons"]["caustic_peak_ratio"] = p.caustic_peak_ratio;
        if (!s.photon_cache.empty()) result["photons"]["cache"] = s.photon_cache;
        if (!s.photon_map_key.empty()) result["photons"]["key"] = s.photon_map_key;
    }
    const auto cache_json = [](const RenderStatistics::CacheFigures& c) {
        return nlohmann::json{
            {"records", c.records},
            {"waves", c.waves},
            {"lookups", c.lookups},
            {"misses", c.misses},
            {"interpolated_share", c.interpolated_share()},
            {"seconds", c.seconds},
        };
    };
    if (s.irradiance_cache) {
        const auto& c = *s.irradiance_cache;
        result["irradiance_cache"] = cache_json(c);
        if (!c.cache.empty()) result["irradiance_cache"]["cache"] = c.cache;
        if (!c.key.empty()) result["irradiance_cache"]["key"] = c.key;
        if (!c.start_from.empty()) {
            result["irradiance_cache"]["start_from"] = c.start_from;
            result["irradiance_cache"]["records_reused"] = c.records_reused;
        }
    }
    if (s.radiance_cache) result["radiance_cache"] = cache_json(*s.radiance_cache);
    if (s.preview) {
        const auto& p = *s.preview;
        result["preview"] = {{"stride", p.stride}, {"samples", p.samples}, {"tiles", p.tiles}, {"seconds", p.seconds}};
    }
    return result;
}

}  // namespace photond::protocol
