// What a render did: timings per pass, ray counts, and (later) the plan of passes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace photond {

struct PassTiming {
    std::string name;  // "scene", "acceleration", "render", ...
    double seconds = 0.0;
};

struct RenderStatistics {
    std::string integrator;
    int width = 0;
    int height = 0;
    int samples_per_pixel = 0;
    int threads = 0;
    std::vector<PassTiming> passes;
    uint64_t rays = 0;         // intersection queries
    uint64_t shadow_rays = 0;  // occlusion queries
    double render_seconds = 0.0;  // the tile pass alone
    double total_seconds = 0.0;
    bool cancelled = false;

    double rays_per_second() const {
        return render_seconds > 0.0 ? static_cast<double>(rays + shadow_rays) / render_seconds : 0.0;
    }
};

}  // namespace photond
