// Integrator `photon-map` (docs/ARCHITECTURE.md, "Where each algorithm lives"): emitted light, direct light by light
// sampling, ideal specular reflection and refraction by recursion, caustics from the caustic map
// at visible points, and indirect light by final gathering from the global map through the
// shared irradiance cache:
//   L = Le + L_direct + L_caustic + rho_d / pi * E_indirect + L_indirect,non-Lambertian
// E_indirect comes from the irradiance cache (or a gather at the point when the cache is off or
// has no record there); non-Lambertian lobes (glossy and rough microfacet) take BSDF-sampled rays
// that read the photon maps where they land.
//
// Without final gathering (`final_gather = false`) indirect light is read from the global map
// directly at the first hit, skipping its direct (L D) and caustic (L S+ D) photons, which the
// other terms count: fast and blotchy, the classic look of a photon map seen directly.
#pragma once

#include <algorithm>
#include <memory>

#include "core/integrators/final_gather.h"
#include "core/integrators/integrator.h"
#include "core/integrators/irradiance_cache_builder.h"
#include "core/integrators/radiance_cache.h"
#include "core/photon/photon_tracer.h"

namespace photond {

struct PhotonMapIntegratorSettings {
    uint32_t k_global = 50;
    uint32_t k_caustic = 100;
    uint32_t k_volume = 100;  // photons per volume-map estimate of the atmosphere's in-scattered light
    float max_radius_global = 0.0f;   // world units; 0 = kDefaultGlobalRadiusShare of the scene
    float max_radius_caustic = 0.0f;  // world units; 0 = kDefaultCausticRadiusShare of the scene
    int max_specular_depth = 16;
    bool final_gather = true;
    GatherSettings gather;
    /// Rays of a gather where the render pass finds no record (miss_gather_rays); 0: gather.rays.
    uint32_t miss_gather_rays = 0;
    bool use_irradiance_cache = true;
    CacheBuildSettings irradiance_cache;
    int glossy_rays = 1;  // BSDF-sampled rays per visible point for non-Lambertian lobes
    /// Visible points whose camera path's importance (path_importance) is under this read their
    /// light from the photon maps at once, as gather hits do (kApproximateImportance; 0: never).
    float approximate_importance = kApproximateImportance;
    /// Glossy lobes from radiance records instead of glossy rays (needs final gathering).
    RadianceCacheSettings radiance_cache;
};

/// A render-pass gather where no record covers the point feeds one of the pixel's `spp` samples
/// and is not stored: gather_rays / spp rays (at least kMinMissGatherRays) give a pixel whose
/// every sample misses as many rays in all as one record has, at a sixteenth of the cost at 16 spp.
inline constexpr uint32_t kMinMissGatherRays = 16;
inline uint32_t miss_gather_rays(uint32_t gather_rays, uint32_t spp) {
    return std::min(gather_rays, std::max(kMinMissGatherRays, gather_rays / std::max(spp, 1u)));
}

/// Bump when the irradiance cache's prepass or gathering changes what it stores for the same
/// inputs: every cached render cache then misses. 2: the light tree (LightSelection); 3: rough
/// glass at gather hits read from both sides; 4: glossy caustics left to the caustic map; 5: short
/// gather rays trace a bounce (GatherSettings::short_ray_radii); 6: rough glass followed as glossy
/// lobes are, and glass of any roughness read from both sides where the rays stop; 7: photon
/// estimates without the photon on their edge (core/photon/photon_map.cpp, estimate_support); 8: glossy lobes
/// up to roughness 0.36 (was 0.25) continue caustic paths (kSharpGlossyRoughness): gathers leave their caustics
/// to the map; 9: a gather hit whose nearest irradiance sites face away reads a farther one that covers it
/// (PhotonMap::nearest_irradiance) instead of a full photon estimate; 10: the nearest site that faces
/// the hit's way and covers it, in one search, and the short-ray rule's caustic estimates only where
/// they may show (CausticVisibility); 11: no records where the camera path's importance is under
/// approximate_importance (the render pass reads the photon maps there).
inline constexpr uint32_t kRenderCacheAlgorithmVersion = 11;

/// Nearest volume photons per estimate of the in-scattered light along a gather ray, at most.
inline constexpr uint32_t kGatherVolumePhotons = 32;

/// Nearest photons per estimate in the progressive preview's integrator (make_preview), at most.
inline constexpr uint32_t kPreviewPhotons = 16;

/// Default search radius caps as a share of the scene's bounding radius (the caustic map's is
/// the photon pass's, which tests the map's visibility with it: core/photon/photon_tracer.h).
inline constexpr float kDefaultGlobalRadiusShare = 0.2f;
inline constexpr float kDefaultCausticRadiusShare = kCausticRadiusShare;

class PhotonMapIntegrator final : public Integrator {
public:
    PhotonMapIntegrator(std::shared_ptr<const RenderScene> scene, std::shared_ptr<const PhotonMaps> maps,
                        const PhotonMapIntegratorSettings& settings);
    std::string_view name() const override { return "photon-map"; }

    /// Whether this integrator fills an irradiance cache (final gathering with the cache on).
    bool uses_irradiance_cache() const { return gatherer_ && settings_.use_irradiance_cache; }
    /// Whether it fills a radiance cache: final gathering with the cache on, and a material
    /// whose glossy lobe the cache can hold (radiance_cache_materials).
    bool uses_radiance_cache() const { return uses_radiance_cache_; }
    /// "irradiance_cache" when it fills one, else "radiance_cache" when it fills that, else none.
    /// The radiance cache's own seconds are in PrepareReport::radiance.
    std::string_view preparation_pass() const override {
        return uses_irradiance_cache() ? "irradiance_cache" : uses_radiance_cache() ? "radiance_cache" : "";
    }
    /// The irradiance cache of this view (a no-op without one): with a store and a photon-map key,
    /// taken from the store by render_cache_key or built once and kept there; else built for this
    /// render. `start_from` names an earlier view's cache in the store to start from (an error
    /// when there is no store, no such cache, or it was built for another scene or settings).
    Expected<PrepareReport> prepare(const PrepareContext& context) override;
    /// The preview's integrator: the same maps read directly at the first hit (final_gather
    /// off, so no irradiance cache and no prepass), direct light and caustics as here.
    std::unique_ptr<Integrator> make_preview() const override;
    /// Fills the irradiance cache for this camera (a no-op without final gathering or cache),
    /// starting from `start` when given (build_irradiance_cache; check start_matches first).
    void build_cache(const Camera& camera, CacheBuildStatistics* statistics, const IrradianceCache* start = nullptr);
    const CacheBuildSettings& cache_settings() const { return settings_.irradiance_cache; }
    /// Takes a cache built earlier for the same render_cache_key (another job or node).
    void use_cache(std::shared_ptr<const IrradianceCache> cache) { cache_ = std::move(cache); }
    /// The content key of the cache build_cache() builds for this camera over maps of
    /// `photon_map_key`: "rc1-" + 64 hex digits, from the photon-map key, the camera and image
    /// size, the cache's and gathering's settings, the seed, the key of the cache it starts from
    /// (if any) and kRenderCacheAlgorithmVersion.
    std::string render_cache_key(const std::string& photon_map_key, const CameraDesc& camera, int width, int height,
                                 const std::string& start_key = "") const;

    const RenderScene& scene() const override { return *scene_; }
    /// The parts by estimator: emission seen through ideal specular surfaces; direct from light
    /// sampling (and the emitters and the sky the glossy rays find at once); caustic from the
    /// caustic map; indirect from final gathering (or the global map read directly), which also
    /// holds the diffuse part of a sky (final gathering collects it, light sampling only its peaks)
    /// and all the light of points evaluated approximately (approximate_importance).
    RadianceParts radiance_parts(const CameraRay& ray, SampleContext& context) const override;

    const IrradianceCache* cache() const { return cache_.get(); }
    const RadianceCache* radiance_cache() const { return radiance_cache_.get(); }
    /// Fills the radiance cache for this camera (a no-op unless uses_radiance_cache()).
    void build_radiance_cache(const Camera& camera, CacheBuildStatistics* statistics);
    const std::shared_ptr<const IrradianceCache>& shared_cache() const { return cache_; }

private:
    /// `importance`: the camera path's share of the pixel so far (path_importance).
    RadianceParts radiance_along(const Ray& ray, int depth, float path_length, RayFootprint footprint,
                                 float importance, SampleContext& context) const;
    /// What the ray's hit sends back (null: it left the scene), before the atmosphere on its way.
    RadianceParts surface_radiance(const Ray& ray, const SurfaceInteraction* hit_point, int depth, float path_length,
                                   RayFootprint footprint, float importance, SampleContext& context) const;
    Expected<PrepareReport> prepare_irradiance_cache(const PrepareContext& context);
    Color indirect_irradiance(const DiffusePoint& point, SampleContext& context) const;
    /// The radiance cache's field at a glossy point, extrapolating a little where no record is
    /// usable; false (BSDF-sampled rays instead) where none is even then.
    bool radiance_field(const Vec3& p, const Vec3& normal, RadianceCache::Field* field, SampleContext& context) const;

    std::shared_ptr<const RenderScene> scene_;
    std::shared_ptr<const PhotonMaps> maps_;
    PhotonMapIntegratorSettings settings_;
    RadianceEstimateOptions caustic_options_;
    RadianceEstimateOptions global_options_;
    std::unique_ptr<FinalGatherer> gatherer_;
    std::shared_ptr<const IrradianceCache> cache_;
    std::unique_ptr<RadianceCache> radiance_cache_;
    bool uses_radiance_cache_ = false;
    /// Whether the caustic map holds photons of ideal specular paths alone (L S+ D without a
    /// glossy bounce): glossy lobes read only those.
    bool specular_caustics_ = false;
    /// Whether a caustic estimate may show (with a caustic map; shared with gatherer_).
    std::shared_ptr<const CausticVisibility> caustic_visibility_;
    /// What next-event estimation samples: the scene's lights, or with final gathering under an
    /// environment, the lights with only the sky's peaks (the gather collects the rest).
    const LightSet* direct_lights_ = nullptr;
};

}  // namespace photond
