#include "protocol/statistics.h"

namespace photond::protocol {

nlohmann::json to_json(const RenderStatistics& s) {
    nlohmann::json passes = nlohmann::json::array();
    for (const PassTiming& p : s.passes) passes.push_back({{"name", p.name}, {"seconds", p.seconds}});
    return {
        {"integrator", s.integrator},
        {"width", s.width},
        {"height", s.height},
        {"spp", s.samples_per_pixel},
        {"threads", s.threads},
        {"passes", passes},
        {"rays", s.rays},
        {"shadow_rays", s.shadow_rays},
        {"rays_per_second", s.rays_per_second()},
        {"render_seconds", s.render_seconds},
        {"total_seconds", s.total_seconds},
        {"cancelled", s.cancelled},
    };
}

}  // namespace photond::protocol
