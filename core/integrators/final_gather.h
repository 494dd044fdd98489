// Final gathering (docs/ARCHITECTURE.md, "Where each algorithm lives"): indirect irradiance at a surface point by
// stratified, cosine-weighted hemisphere sampling in M x N cells,
//   theta_j = asin(sqrt((j + X) / M)),  phi_k = 2 pi (k + Y) / N,  E = pi / (M N) sum L_jk,
// with the radiance L_jk at each gather ray's hit read from the photon maps. The same samples
// give the record's harmonic mean distance and the irradiance gradients (Ward & Heckbert 1992),
// at no extra rays.
//
// Gather rays add no emitted light, and pass through ideal specular surfaces (up to a depth)
// and sharply glossy ones (by sampling their lobes) without counting emitters behind them
// either: light arriving through such surfaces straight from an emitter is the caustic map's
// share (L S+ D, S ideal specular or sharply glossy: Bsdf::continues_caustic), so nothing is
// counted twice. Other glossy lobes, and any glossy lobe once a gather ray's path has met a
// surface of diffuse kind, take light samples and weight the emitters their rays meet by the
// power heuristic, as a path tracer does. Without a caustic map every glossy lobe does: its
// light then comes from the gather alone. Rough glass, also as rough as diffuse, is followed the
// same way (outside caustic chains), so that the light inside a small solid comes from outside
// it rather than from the few photons on its inner side.
//
// Jensen's short-ray rule (GatherSettings::short_ray_radii): a hit closer to where its ray left
// than the photon estimate there is wide is traced a bounce on instead of read from the photons,
// as a visible point is (a light sample, the caustic map, one lobe sample), so a gather ray's path
// takes direct light there too; the last glossy lobe of a caustic chain is followed a bounce
// more there. Still read from the photons, without the rule: rough glass's far side, where gather
// rays stop following it.
#pragma once

#include <array>

#include "core/integrators/caustic_visibility.h"
#include "core/integrators/integrator.h"
#include "core/photon/photon_tracer.h"

namespace photond {

struct GatherSettings {
    uint32_t rays = 512;         // M x N, N ~ pi M
    int max_specular_depth = 4;  // ideal specular surfaces a gather ray may pass through
    /// Glossy lobes and rough glass a gather ray follows by sampling (a light sample and a lobe
    /// sample, power heuristic) before it reads the photon maps; 0 reads them at once.
    int max_glossy_bounces = 2;
    uint32_t k_global = 50;      // photons per radiance estimate where no precomputed irradiance fits
    uint32_t k_volume = 100;     // photons per volume-map estimate of the atmosphere's in-scattered light
    float max_radius = 0.0f;     // estimate radius cap (world units)
    /// Jensen's short-ray rule: where a ray lands closer to where it left than this many times
    /// the radius of the photon estimate there (the nearest irradiance site's), the estimate
    /// reaches past what shadows the hit into light the hit cannot see (a contact's shadow), so
    /// the hit is traced one bounce on instead, as a visible point is (final_gather.cpp); 0 never.
    float short_ray_radii = 2.0f;
    uint32_t k_caustic = 100;          // caustic photons per estimate at such a hit
    float max_radius_caustic = 0.0f;   // their search radius cap (world units; 0: kCausticRadiusShare of the scene radius)
    /// Gather rays that leave the scene, straight away or through ideal specular surfaces, see
    /// the environment's diffuse sky (RenderScene::diffuse_sky), which light sampling and the
    /// caustic map then leave out (maps traced with a global map do); else they see nothing.
    bool gather_diffuse_sky = false;
};

/// `options` for a photon estimate at `si`, seen from the side `front` says (surface_normal's
/// when true): each photon weighted by a normal map's bent normal, and both sides counted where
/// the BSDF transmits through a rough lobe.
inline RadianceEstimateOptions estimate_options_at(RadianceEstimateOptions options, const SurfaceInteraction& si,
                                                   const Bsdf& bsdf, bool front) {
    options.shading_normal = bent_shading_normal(si, front);
    options.both_sides = bsdf.transmits_non_delta();
    return options;
}

/// Cosine-weighted irradiance and what an irradiance cache record needs.
struct GatherResult {
    Color irradiance{0.0f};
    /// Harmonic mean of the gather rays' hit distances (infinity when every ray escaped).
    float harmonic_mean_distance = 0.0f;
    /// Gradients per colour channel: rotation (Ward & Heckbert 1992) and translation.
    std::array<Vec3, 3> rotation_gradient{};
    std::array<Vec3, 3> translation_gradient{};
    uint32_t rays = 0;
};

/// The stratification of a gather: M rows in theta and N columns in phi, N ~ pi M.
struct GatherGrid {
    int m = 1;
    int n = 1;
    static GatherGrid for_rays(uint32_t rays);
};

class FinalGatherer {
public:
    /// `caustic_visibility`: decides where the short-ray rule's bounces read the caustic map
    /// (null: everywhere).
    FinalGatherer(std::shared_ptr<const RenderScene> scene, std::shared_ptr<const PhotonMaps> maps,
                  const GatherSettings& settings,
                  std::shared_ptr<const CausticVisibility> caustic_visibility = nullptr);

    /// Gathers at point p with unit normal n (the side light is gathered from), frame around n.
    /// `compute_gradients` adds the rotation and translation gradients. `rays`: how many rays
    /// (0: the settings' count).
    GatherResult gather(const Vec3& p, const Vec3& n, const Vec3& geometric_normal, Rng& rng,
                        RayCounters& counters, bool compute_gradients, uint32_t rays = 0) const;

    /// Radiance leaving the first non-specular surface along a ray, from the photon maps (no
    /// emission); writes the hit distance (infinity on a miss).
    /// What a gather ray found at its first hit, for callers that weight emission by MIS.
    struct FirstHitEmission {
        Color radiance{0.0f};  // emitted towards the ray's origin; zero when nothing emits
        uint32_t triangle = 0;
        Vec3 point{0.0f};
        /// The atmosphere's light scattered towards the ray's origin along it (part of what
        /// gather_ray_radiance returns; zero without an atmosphere).
        Color in_scattered{0.0f};
    };
    /// For rays sampled from the glossy lobes of a visible point (and radiance-cache records):
    /// glossy lobes met on the way count all the light they reflect, emitters included, so the
    /// point reads the caustic map's glossy photons by its Lambertian lobe only
    /// (photon_flags::kGlossyCaustic).
    /// `cone`: the ray's cone (its width at the ray's origin and its spread), which picks the
    /// texture level at the surfaces it meets (RayFootprint; zero: the finest level).
    Color gather_ray_radiance(const Ray& ray, Rng& rng, RayCounters& counters, float* distance,
                              FirstHitEmission* emission = nullptr, RayFootprint cone = {}) const;

    /// Radiance leaving a non-delta surface towards wo from the photon maps, all light in one
    /// (direct, caustic and indirect; no emission), as a gather ray reads a surface where it
    /// stops (without following glossy lobes or the short-ray rule): the nearest irradiance site
    /// times the albedo where the lobes read as diffuse, for rough glass the site on the side one
    /// lobe sample picks, else the global map's estimate through the BSDF. For visible points of
    /// small importance (kApproximateImportance, core/integrators/integrator.h).
    Color photon_radiance(const SurfaceInteraction& si, const Bsdf& bsdf, const Vec3& wo, Rng& rng) const;

    const GatherSettings& settings() const { return settings_; }
    const RenderScene& scene() const { return *scene_; }

private:
    /// gather_ray_radiance; `caustic_chains`: the light that reaches the ray's origin from an
    /// emitter through specular and glossy bounces alone is the caustic map's (a gather for
    /// irradiance at a diffuse point, when there is a caustic map). `short_ray_bounces`: the
    /// bounces the short-ray rule may trace for this ray. `cone`: as gather_ray_radiance's.
    Color trace_gather_ray(const Ray& ray, Rng& rng, RayCounters& counters, float* distance,
                           FirstHitEmission* emission, bool caustic_chains, int short_ray_bounces,
                           RayFootprint cone) const;

    std::shared_ptr<const RenderScene> scene_;
    std::shared_ptr<const PhotonMaps> maps_;
    GatherSettings settings_;
    std::shared_ptr<const CausticVisibility> caustic_visibility_;
    GatherGrid grid_;
    /// The irradiance sites' estimate radius cap (kIrradianceRadiusShare of the scene's radius):
    /// a ray longer than short_ray_radii of it is never short.
    float site_radius_cap_ = 0.0f;
    /// How far a lookup of the nearest irradiance site searches (site_search_radius: no site
    /// farther than its own radius is taken, so the result is the same, and the search stops
    /// sooner where the nearest sites face away).
    float site_reach_ = 0.0f;
};

}  // namespace photond
