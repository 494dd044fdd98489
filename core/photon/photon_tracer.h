// Pass 1 of photon mapping: photons emitted from the lights by power and traced through the
// scene (docs/ARCHITECTURE.md, "Where each algorithm lives"; Jensen 2001, ch. 5). Russian roulette on the BSDF's
// reflectivities, importance-sampled directions, no flux change at refraction, storage at every
// non-delta interaction. Paths are classified by the light-path grammar: the global map gets
// L[S|D]*D, the caustic map L S+ D with S an ideal specular (delta) bounce: glossy bounces
// count as D, their light reaches the image through final gathering.
//
// Deterministic in parallel: photon i draws from the random stream (seed, i), photons are traced
// in batches, and each batch's stored photons are appended in photon order, so the maps do not
// depend on the thread count.
//
// Work skipped: batches are sized for the map that fills first, and once only the caustic map
// is collecting, photons are aimed at the scene's specular triangles (RenderScene::
// caustic_casters; core/light/emission_focus.h) and the map starts again with these alone (the
// few caustic photons of whole paths would carry far more flux each); each first casts one ray
// against those triangles and ends if it misses them all: it could store nothing. A
// caustic map whose photons carry a negligible share of the light that reaches the surfaces
// (kNegligibleCausticShare of the global map's, measured on the photons stored so far) stops
// early with what it has: its flux is divided by the photons emitted so far, so it stays
// unbiased, and tracing on to fill it would cost the most time for the least light (a scene
// lit by a sky, with small emitters near glossy surfaces, reached the emission cap after
// 50 M photons for caustics a thousandth of a percent as bright as the rest).
//
// A caustic map is also dropped when its light would not show: once the global map is full (and
// again when the caustic map ends), the caustic irradiance at up to kCausticTestSites of its
// photons is compared with all the irradiance the global map finds there. Where the largest
// ratio is under kInvisibleCausticRatio, adding the caustic changes no pixel by more than that,
// while tracing it and estimating it at visible points would cost time: the map is not built,
// tracing for it stops, and the statistics say why (caustic_dropped, caustic_peak_ratio). A map
// that shows somewhere is kept; where it is faint, the render skips it point by point
// (CausticVisibility::may_show, with the caustic irradiance precomputed here).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "core/photon/photon_map.h"
#include "core/shading/render_scene.h"

namespace photond {

/// The share of the global map's stored flux below which the caustic map stops early, once it
/// holds kCausticShareMinPhotons photons (enough for the share to be known to about 1/8).
inline constexpr double kNegligibleCausticShare = 1e-4;
inline constexpr uint64_t kCausticShareMinPhotons = 64;

/// How many irradiance sites a map gets at most before their stride widens (PhotonTracingSettings::
/// irradiance_stride).
inline constexpr size_t kMaxIrradianceSites = size_t(1) << 19;

/// The caustic map's visibility test: the largest ratio of caustic irradiance to all irradiance
/// at its photons under which the map is dropped, how many of its photons are tested, and the
/// photons per caustic estimate at the map's final count (a partly filled map is estimated with
/// proportionally fewer, so that the estimates' radii are the final map's; never fewer than
/// kCausticTestMinPhotons, and the test waits until the map holds enough for that).
inline constexpr double kInvisibleCausticRatio = 0.01;
inline constexpr uint32_t kCausticTestSites = 1024;
inline constexpr uint32_t kCausticTestPhotons = 100;
inline constexpr uint32_t kCausticTestMinPhotons = 8;
/// The caustic estimate's radius cap as a share of the scene's bounding radius (the render's
/// default too: core/integrators/photon_mapping.h).
inline constexpr float kCausticRadiusShare = 0.05f;
/// The precomputed irradiance estimates' radius cap as a share of the scene's bounding radius.
inline constexpr float kIrradianceRadiusShare = 0.2f;

struct PhotonTracingSettings {
    uint32_t global_photons = 200000;   // photons to store in the global map (0: no global map)
    uint32_t caustic_photons = 100000;  // photons to store in the caustic map (0: no caustic map)
    /// Photons to store in the volume map at scattering events in the atmosphere (0, or a scene
    /// whose atmosphere does not scatter: no volume map); Jensen & Christensen 1998.
    uint32_t volume_photons = 0;
    uint64_t seed = 1;
    int max_bounces = 64;               // safety net; Russian roulette ends paths first
    /// Emission stops after this many photons per requested stored photon, and the pass fails
    /// with a message if a map received no photon at all by then (lights facing away, black
    /// scene). Maps that are partly filled are kept with what they have.
    uint32_t max_emitted_per_stored = 1000;
    /// Irradiance is precomputed at every n-th global photon (0: none), with k_irradiance
    /// photons per estimate, for fast lookups at final-gather hits (Christensen 1999); in maps
    /// of more than kMaxIrradianceSites times n photons, at fewer (photon_tracer.cpp).
    uint32_t irradiance_stride = 4;
    uint32_t k_irradiance = 50;
    int threads = 0;                    // 0 = every core
    const std::atomic<bool>* cancel = nullptr;
};

struct PhotonTracingStatistics {
    uint64_t emitted = 0;            // photons emitted in total
    uint64_t emitted_global = 0;     // emitted when the global map was filled
    uint64_t emitted_caustic = 0;    // emitted when the caustic map was filled
    uint64_t stored_global = 0;
    uint64_t stored_caustic = 0;
    uint64_t emitted_volume = 0;     // emitted when the volume map was filled
    uint64_t stored_volume = 0;
    uint64_t rays = 0;
    double tracing_seconds = 0.0;
    double build_seconds = 0.0;      // kd-trees
    double irradiance_seconds = 0.0; // precomputed irradiance
    uint64_t irradiance_photons = 0;
    bool global_complete = true;     // false: the emission cap stopped it short
    bool caustic_complete = true;    // false: the emission cap, or a negligible share, stopped it
    bool volume_complete = true;     // false: the emission cap stopped it short
    /// The caustic map's visibility test: whether it ran, its largest ratio of caustic to all
    /// irradiance at the photons tested, and whether the map was dropped for it (then
    /// PhotonMaps::caustic is null; stored_caustic and emitted_caustic say what was traced).
    bool caustic_tested = false;
    double caustic_peak_ratio = 0.0;
    bool caustic_dropped = false;
};

/// The maps of a scene; a map not asked for is null. `irradiance` holds precomputed irradiance
/// at a subset of the global photons as irradiance sites (make_irradiance_site: irradiance,
/// surface normal, the estimate's radius), `caustic_irradiance` the caustic map's at a subset of
/// the caustic photons (with kCausticTestPhotons an estimate), when both maps exist.
struct PhotonMaps {
    std::shared_ptr<const PhotonMap> global;
    std::shared_ptr<const PhotonMap> caustic;
    std::shared_ptr<const PhotonMap> irradiance;
    std::shared_ptr<const PhotonMap> caustic_irradiance;
    /// Photons at scattering events in the atmosphere (flux after the event's albedo, direction
    /// of travel before it, no normal; photon_flags::kDirect on a photon's first event), for
    /// PhotonMap::estimate_in_scattering; null without a scattering atmosphere.
    std::shared_ptr<const PhotonMap> volume;
    PhotonTracingStatistics statistics;

    size_t bytes() const {
        return (global ? global->bytes() : 0) + (caustic ? caustic->bytes() : 0) +
               (irradiance ? irradiance->bytes() : 0) + (caustic_irradiance ? caustic_irradiance->bytes() : 0) +
               (volume ? volume->bytes() : 0);
    }
};

/// The caustic map's stored flux over the global map's (luminance; each photon's flux already
/// divided by its map's emissions); 0 without both maps.
double caustic_flux_share(const PhotonMaps& maps);

/// Traces the photons and builds the maps. Fails (with a message naming the reason) when the
/// scene has no light with power, or when the global map received no photon within the cap (a
/// caustic map that none reached is kept empty: nothing focuses light).
Expected<PhotonMaps> trace_photons(const RenderScene& scene, const PhotonTracingSettings& settings);

}  // namespace photond
