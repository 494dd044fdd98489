// What a render did: timings per pass, ray counts, and (later) the plan of passes.
#pragma once

#include <cstdint>
#include <string>
#include <optional>
#include <vector>

#include "core/photon/photon_tracer.h"
#include "core/render/render_plan.h"

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
    /// Gather and glossy-ray hits traced a bounce on by the short-ray rule, in every pass.
    uint64_t short_ray_bounces = 0;
    double render_seconds = 0.0;  // the tile pass alone
    double total_seconds = 0.0;
    bool cancelled = false;
    /// Tiles of the render pass taken from an interrupted earlier run of the same job (the
    /// daemon's crash-resume) instead of being rendered; their rays are not counted.
    size_t tiles_restored = 0;
    /// What lights the render: the lights of the light set (punctual lights, emissive
    /// triangles, the environment), how many the job added, and the environment's name (empty:
    /// none; "default": the white environment of a scene without light).
    struct LightingFigures {
        size_t lights = 0;
        size_t job_lights = 0;
        std::string environment;
    };
    LightingFigures lighting;
    /// The passes decided for this render, each with its reason (the environment for every
    /// integrator; the photon maps for photon-map).
    std::vector<PassDecision> plan;
    /// The photon pass, when one ran or its maps came from the cache.
    std::optional<PhotonTracingStatistics> photons;
    size_t photon_map_bytes = 0;
    double caustic_flux_share = 0.0;  // caustic_flux_share (core/photon/photon_tracer.h) of the maps used
    /// Visible points of the render pass where the caustic map could be read (at the samples
    /// that estimate it: a share of each pixel's), and those where its estimate was skipped as
    /// too faint to show (CausticVisibility::may_show).
    uint64_t caustic_points = 0;
    uint64_t caustic_skipped = 0;
    /// "hit" when the photon maps came from the cache, "miss" when traced and stored, empty when
    /// no cache was used.
    std::string photon_cache;
    std::string photon_map_key;

    /// A cache of records filled before the render pass and read by it.
    struct CacheFigures {
        uint64_t records = 0;
        int waves = 0;
        uint64_t lookups = 0;  // render pass
        uint64_t misses = 0;   // lookups no record covered (gathered or sampled on the spot)
        double seconds = 0.0;  // the prepass that placed the records (0 when taken from a store)
        double interpolated_share() const {
            return lookups > 0 ? 1.0 - static_cast<double>(misses) / static_cast<double>(lookups) : 0.0;
        }
    };

    /// The irradiance cache, when final gathering used one.
    struct IrradianceCacheFigures : CacheFigures {
        std::string cache;     // "hit" when taken from the render-cache store, "miss" when built
        std::string key;       // its render-cache key (with a store)
        std::string start_from;       // the key of the cache it started from, if any
        uint64_t records_reused = 0;  // records taken from that cache
    };
    std::optional<IrradianceCacheFigures> irradiance_cache;

    /// The radiance cache, when glossy lobes read one (core/integrators/radiance_cache.h): its
    /// lookups are glossy points, its misses those that took BSDF-sampled rays instead.
    using RadianceCacheFigures = CacheFigures;
    std::optional<RadianceCacheFigures> radiance_cache;

    /// The progressive preview (core/render/preview_renderer.h), when one was rendered.
    struct PreviewFigures {
        int stride = 0;         // one camera sample per stride x stride pixels
        uint64_t samples = 0;
        uint64_t tiles = 0;     // preview tiles reported
        double seconds = 0.0;   // the pass, tiles reported included
    };
    std::optional<PreviewFigures> preview;

    /// What the user should know about this render: the scene's warnings (Scene::warnings:
    /// ignored glTF features), then the render's own (an incomplete photon map). One sentence
    /// each; any pass may append.
    std::vector<std::string> warnings;

    double rays_per_second() const {
        return render_seconds > 0.0 ? static_cast<double>(rays + shadow_rays) / render_seconds : 0.0;
    }
};

}  // namespace photond
