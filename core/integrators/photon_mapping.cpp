#include "core/integrators/photon_mapping.h"

#include <algorithm>

#include "core/integrators/direct.h"
#include "core/integrators/volume_radiance.h"
#include "core/integrators/render_cache_store.h"
#include "core/util/sha256.h"

namespace photond {
namespace {

/// How far beyond a record's domain (as a factor of a) the render pass may extrapolate.
constexpr float kExtrapolationScale = 2.0f;
/// Light samples at a point whose glossy lobes read the radiance cache (one elsewhere): the
/// direct light keeps the two samples a glossy ray and a light sample gave it. On glossy-objects'
/// cached sphere, 16 spp, relMSE 0.0025 -> 0.0018 (README.md, "Glossy surfaces: the radiance
/// cache"); shadow rays cost a fraction of the gather ray the cache saves.
constexpr int kCachedLobeLightSamples = 2;
/// A pixel's samples that trace glossy rays at a point: this times the glossy lobes' share of
/// its non-delta reflectance (Bsdf::glossy_share), all of them from a share of 1/4. Alone, on
/// TransmissionTest (whose cloth is a rough layer over a white and grey base), 256^2, 16 spp:
/// render pass 2.61 -> 2.14 s, relMSE against path 0.003138 -> 0.003293; at 2 instead of 4:
/// 0.00376, at 1: 0.00509 (README.md, "The pipeline", step 5, has both shares' figures).
constexpr float kGlossyRaysPerLobeShare = 4.0f;
/// The share of a pixel's samples that estimate the caustic map's light at their points.
/// Alone, on cornell-box: 2.57 -> 1.89 s, relMSE 0.002161 -> 0.002175.
constexpr float kCausticEstimateShare = 0.25f;

}  // namespace

PhotonMapIntegrator::PhotonMapIntegrator(std::shared_ptr<const RenderScene> scene,
                                         std::shared_ptr<const PhotonMaps> maps,
                                         const PhotonMapIntegratorSettings& settings)
    : scene_(std::move(scene)), maps_(std::move(maps)), settings_(settings) {
    const float scene_radius = scene_->scene->bounds.radius();
    caustic_options_.k = settings_.k_caustic;
    caustic_options_.max_radius = settings_.max_radius_caustic > 0.0f
                                      ? settings_.max_radius_caustic
                                      : kDefaultCausticRadiusShare * scene_radius;
    caustic_options_.cone_filter = true;
    global_options_.k = settings_.k_global;
    global_options_.max_radius = settings_.max_radius_global > 0.0f
                                     ? settings_.max_radius_global
                                     : kDefaultGlobalRadiusShare * scene_radius;
    // Read directly, the global map must skip what light sampling and the caustic map count.
    global_options_.exclude_flags = photon_flags::kDirect | (maps_->caustic ? photon_flags::kCaustic : 0);
    if (maps_->caustic)
        caustic_visibility_ = std::make_shared<const CausticVisibility>(maps_->caustic_irradiance.get(),
                                                                        caustic_options_.max_radius);
    if (settings_.final_gather && maps_->global) {
        GatherSettings gather = settings_.gather;
        gather.k_global = settings_.k_global;
        // Each gather ray's in-scattered light is averaged with the other rays' (hundreds a
        // record): fewer photons an estimate, as at normal-mapped gather hits.
        gather.k_volume = std::min(settings_.k_volume, kGatherVolumePhotons);
        gather.max_radius = global_options_.max_radius;
        gather.k_caustic = caustic_options_.k;
        gather.max_radius_caustic = caustic_options_.max_radius;
        gather.gather_diffuse_sky = scene_->lights_with_sky_peaks != nullptr;
        gatherer_ = std::make_unique<FinalGatherer>(scene_, maps_, gather, caustic_visibility_);
    }
    if (maps_->caustic) {
        for (const Photon& photon : maps_->caustic->tree().photons())
            if (!(photon.user_flags() & photon_flags::kGlossyCaustic)) {
                specular_caustics_ = true;
                break;
            }
    }
    direct_lights_ = gatherer_ && scene_->lights_with_sky_peaks ? scene_->lights_with_sky_peaks.get()
                                                                  : scene_->lights.get();
    if (gatherer_ && settings_.radiance_cache.enabled) {
        // The materials the plan's radiance_cache line lists: those some triangle shows.
        const std::vector<bool> used = scene_->scene->materials_in_use();
        for (size_t i = 0; i < used.size() && i < scene_->bsdf_materials.size(); ++i)
            uses_radiance_cache_ = uses_radiance_cache_ ||
                                   (used[i] && radiance_order_for(scene_->bsdf_materials[i], settings_.radiance_cache) > 0);
    }
}

void PhotonMapIntegrator::build_radiance_cache(const Camera& camera, CacheBuildStatistics* statistics) {
    if (!uses_radiance_cache_) return;
    CacheBuildSettings build = settings_.irradiance_cache;
    build.max_specular_depth = settings_.max_specular_depth;
    build.approximate_importance = settings_.approximate_importance;
    radiance_cache_ = photond::build_radiance_cache(*scene_, *gatherer_, camera, build, settings_.radiance_cache, statistics);
}

void PhotonMapIntegrator::build_cache(const Camera& camera, CacheBuildStatistics* statistics,
                                      const IrradianceCache* start) {
    if (!gatherer_ || !settings_.use_irradiance_cache) return;
    CacheBuildSettings build = settings_.irradiance_cache;
    build.max_specular_depth = settings_.max_specular_depth;
    build.approximate_importance = settings_.approximate_importance;
    cache_ = build_irradiance_cache(*scene_, *gatherer_, camera, build, statistics, start);
}

Expected<PrepareReport> PhotonMapIntegrator::prepare(const PrepareContext& context) {
    Expected<PrepareReport> report = prepare_irradiance_cache(context);
    if (!report || !uses_radiance_cache_ || (context.cancel && context.cancel->load())) return report;
    // The radiance cache is built for each render (render_cache_key keeps irradiance caches only).
    CacheBuildStatistics statistics;
    build_radiance_cache(context.camera, &statistics);
    report->radiance = PrepareReport::RadianceCacheReport{statistics.records, statistics.waves, statistics.seconds};
    report->counters += statistics.counters;
    return report;
}

Expected<PrepareReport> PhotonMapIntegrator::prepare_irradiance_cache(const PrepareContext& context) {
    PrepareReport report;
    if (!uses_irradiance_cache()) return report;
    const bool kept_between_jobs = context.render_caches && !context.photon_map_key.empty();
    const auto cancelled = [&] { return context.cancel && context.cancel->load(); };
    // An earlier view's cache to start from (irradiance_cache.start_from), from the store.
    std::shared_ptr<const IrradianceCache> start_cache;
    if (!context.start_from.empty()) {
        const std::string& start_key = context.start_from;
        if (!kept_between_jobs)
            return Error{"irradiance_cache.start_from: this render keeps no render caches to start from (photond "
                         "render needs --cache-dir)"};
        start_cache = context.render_caches->find_cache(start_key);
        if (!start_cache)
            return Error{"irradiance_cache.start_from: no render cache " + start_key +
                         " here (render that view first, or import its cache with PUT /v1/render-caches/" + start_key +
                         ")"};
        if (!start_matches(*start_cache, *scene_, settings_.irradiance_cache))
            return Error{"irradiance_cache.start_from: render cache " + start_key +
                         " was built for another scene or other irradiance_cache.a/gradients"};
        report.start_from = start_key;
    }
    CacheBuildStatistics build_statistics;
    if (kept_between_jobs) {
        // Built once per key: other views' jobs, other regions of the frame and other nodes
        // sharing the cache directory take it instead of running the prepass.
        report.cache_key = render_cache_key(context.photon_map_key, context.camera_desc, context.width, context.height,
                                            context.start_from);
        const auto build = [&]() -> Expected<std::shared_ptr<const IrradianceCache>> {
            build_cache(context.camera, &build_statistics, start_cache.get());
            if (cancelled()) return Error{"cancelled during the irradiance-cache prepass"};  // incomplete: not kept
            return cache_;
        };
        bool hit = false;
        auto cache = context.render_caches->get_or_build(report.cache_key, build, &hit);
        if (cache) use_cache(*cache);
        else if (!cancelled()) return cache.error();
        report.cache_outcome = hit ? "hit" : "miss";
    } else {
        build_cache(context.camera, &build_statistics);
    }
    if (cache_) {
        report.built = true;
        report.records = cache_->size();
        if (start_cache) report.records_reused = start_cache->size();
        report.waves = build_statistics.waves;
        report.counters = build_statistics.counters;
    }
    return report;
}

std::unique_ptr<Integrator> PhotonMapIntegrator::make_preview() const {
    PhotonMapIntegratorSettings preview = settings_;
    preview.final_gather = false;
    preview.use_irradiance_cache = false;
    // The k-nearest searches are most of a photon-map sample's cost without gathering
    // (cornell-box: 8.2 us a sample with k = 50 and 100, 4.4 us with 16; README.md, "Progressive
    // previews").
    preview.k_global = std::min(preview.k_global, kPreviewPhotons);
    preview.k_caustic = std::min(preview.k_caustic, kPreviewPhotons);
    return std::make_unique<PhotonMapIntegrator>(scene_, maps_, preview);
}

std::string PhotonMapIntegrator::render_cache_key(const std::string& photon_map_key, const CameraDesc& camera,
                                                  int width, int height, const std::string& start_key) const {
    Sha256 hasher;
    const auto hash_float = [&](float value) { hasher.update_value(value == 0.0f ? 0.0f : value); };
    const auto hash_vec3 = [&](const Vec3& v) {
        hash_float(v.x);
        hash_float(v.y);
        hash_float(v.z);
    };
    hasher.update_string("photond render-cache key");
    hasher.update_value(kRenderCacheAlgorithmVersion);
    hasher.update_string(photon_map_key);
    // The view: what the camera's rays are (the name and whether a glTF node placed it are not).
    hash_vec3(camera.position);
    hash_vec3(camera.look_at);
    hash_vec3(camera.up);
    hash_float(camera.vfov_deg);
    hash_float(camera.aspect);
    hasher.update_value(static_cast<int32_t>(camera.projection));
    hash_float(camera.ortho_half_height);
    hasher.update_value(int32_t(width));
    hasher.update_value(int32_t(height));
    // What the prepass does at each record (CacheBuildSettings, GatherSettings); threads, cancel
    // and region do not change the cache.
    const CacheBuildSettings& cache = settings_.irradiance_cache;
    hash_float(cache.accuracy);
    hasher.update_value(uint8_t(cache.gradients));
    hash_float(cache.min_spacing_px);
    hash_float(cache.max_spacing_px);
    hasher.update_value(uint64_t(cache.seed));
    hasher.update_value(int32_t(settings_.max_specular_depth));
    hash_float(settings_.approximate_importance);
    const GatherSettings& gather = gatherer_ ? gatherer_->settings() : settings_.gather;
    hasher.update_value(uint32_t(gather.rays));
    hasher.update_value(int32_t(gather.max_specular_depth));
    hasher.update_value(int32_t(gather.max_glossy_bounces));
    hasher.update_value(uint32_t(gather.k_global));
    // Gather rays read the atmosphere's volume map (keys of scenes without one stay as they were).
    if (scene_->scene->atmosphere) hasher.update_value(uint32_t(gather.k_volume));
    hash_float(gather.max_radius);
    hash_float(gather.short_ray_radii);
    // Short gather rays read the caustic map: its estimates' settings, where they are read.
    if (gather.short_ray_radii > 0.0f && maps_->caustic) {
        hasher.update_value(uint32_t(gather.k_caustic));
        hash_float(gather.max_radius_caustic);
    }
    hasher.update_value(uint8_t(gather.gather_diffuse_sky));
    // Glossy gather hits sample lights (final_gather.cpp): how they pick them changes the records.
    hasher.update_value(uint8_t(scene_->lights->selection()));
    // A cache that starts from another holds that one's records: its key is part of this one.
    if (!start_key.empty()) hasher.update_string(start_key);
    return "rc1-" + Sha256::hex(hasher.finish());
}

bool PhotonMapIntegrator::radiance_field(const Vec3& p, const Vec3& normal, RadianceCache::Field* field,
                                         SampleContext& context) const {
    ++context.counters.radiance_lookups;
    if (radiance_cache_->field_at(p, normal, 1.0f, field)) return true;
    // As for irradiance: samples off the prepass's pixel centres may fall just outside.
    if (radiance_cache_->field_at(p, normal, kExtrapolationScale, field)) return true;
    ++context.counters.radiance_misses;
    return false;
}

RadianceParts PhotonMapIntegrator::radiance_parts(const CameraRay& ray, SampleContext& context) const {
    return radiance_along(primary_ray(ray), 0, 0.0f, camera_footprint(ray), 1.0f, context);
}

Color PhotonMapIntegrator::indirect_irradiance(const DiffusePoint& point, SampleContext& context) const {
    Color e;
    if (cache_) {
        ++context.counters.irradiance_lookups;
        if (cache_->interpolate(point.position, point.normal, &e)) return e;
        // The prepass tested pixel centres; a sample elsewhere in the pixel may fall just outside
        // every record's domain: extrapolate a little before gathering anew.
        if (cache_->interpolate(point.position, point.normal, &e, kExtrapolationScale)) return e;
        ++context.counters.irradiance_misses;
    }
    // No record covers the point (or no cache): gather here, without storing, so the cache stays
    // as the prepass left it and the image independent of tile order; a miss with the sample's
    // share of the rays (miss_gather_rays), without a cache every sample with all of them.
    const GatherResult g = gatherer_->gather(point.position, point.normal, point.geometric_normal, context.rng,
                                             context.counters, false, cache_ ? settings_.miss_gather_rays : 0);
    return g.irradiance;
}

RadianceParts PhotonMapIntegrator::radiance_along(const Ray& ray, int depth, float path_length,
                                                  RayFootprint footprint, float importance,
                                                  SampleContext& context) const {
    const RenderScene& rs = *scene_;
    const std::optional<Hit> hit = trace_ray(rs, ray, context.counters);
    std::optional<SurfaceInteraction> hit_point;
    // The camera's ray cone, widened along ideal specular bounces, picks the texture level.
    if (hit) hit_point = make_interaction(*rs.scene, *hit, ray.direction, footprint.texture_at(path_length + hit->t));
    RadianceParts radiance =
        surface_radiance(ray, hit_point ? &*hit_point : nullptr, depth, path_length, footprint, importance, context);
    // Inside a solid that scatters, all its light comes from the volume map (light samples from
    // inside are blocked by its surface); surface_radiance attenuated what lies beyond.
    if (hit_point && maps_->volume && rs.scattering_interiors) {
        if (const std::optional<HomogeneousMedium> interior = scattering_interior(*rs.scene, *hit_point))
            radiance.add_indirect(interior_in_scattering(rs, *maps_->volume, *interior, ray, *hit_point,
                                                         settings_.k_volume, global_options_.max_radius, 1, context));
    }
    const std::optional<HomogeneousMedium>& atmosphere = rs.scene->atmosphere;
    if (!atmosphere) return radiance;
    // The atmosphere on the way: what lies beyond is seen through it; it sends the light it
    // scatters once from the lights (single_scattering) and the light it scattered before
    // (the volume map without its first events).
    const MediumSpan span = atmosphere_span(*rs.scene, ray, hit_point ? &*hit_point : nullptr);
    if (span.empty()) return radiance;
    radiance = atmosphere->transmittance(span.t1 - span.t0) * radiance;
    if (!atmosphere->scatters()) return radiance;
    radiance.add_direct(single_scattering(rs, *atmosphere, ray, span, context));
    if (maps_->volume)
        // One point: the light scattered more than once varies slowly along the ray, and a
        // pixel's samples spread their points over it.
        radiance.add_indirect(volume_in_scattering(*maps_->volume, *atmosphere, &rs.scene->bounds, ray, span, settings_.k_volume,
                                                   global_options_.max_radius, photon_flags::kDirect, 1, context));
    return radiance;
}

RadianceParts PhotonMapIntegrator::surface_radiance(const Ray& ray, const SurfaceInteraction* hit_point, int depth,
                                                    float path_length, RayFootprint footprint, float importance,
                                                    SampleContext& context) const {
    const RenderScene& rs = *scene_;
    // A camera ray or a delta bounce that leaves the scene sees the sky whole.
    RadianceParts radiance;
    if (!hit_point) {
        radiance.add_emission(rs.lights->escaped_radiance(ray.direction, 0.0f));
        return radiance;
    }
    const SurfaceInteraction& si = *hit_point;
    const float length = path_length + si.distance;
    const Vec3 wo = -ray.direction;
    radiance.add_emission(rs.lights->emitted_radiance(si, wo));
    const Bsdf bsdf = make_bsdf(rs, si, wo);
    if (bsdf.has_non_delta() && gatherer_ && importance < settings_.approximate_importance) {
        // A point of small share in its pixel: its light as a gather ray's hit reads it (no
        // light samples, no cache record, no glossy rays), counted as indirect.
        radiance.add_indirect(gatherer_->photon_radiance(si, bsdf, wo, context.rng));
    } else if (bsdf.has_non_delta()) {
        // Glossy and rough lobes are also BSDF-sampled below: emitters those rays hit are
        // weighted against light sampling (multiple importance sampling).
        const bool glossy = gatherer_ && bsdf.has_non_lambertian_non_delta();
        const LobeMask glossy_lobes = kNonDeltaLobes | kExcludeLambertian;
        const int glossy_rays = std::max(settings_.glossy_rays, 1);
        // Photon discs and cache records follow the surface, not its normal map; estimates weight
        // their photons by the mapped normal (RadianceEstimateOptions::shading_normal; README).
        const bool front = glm::dot(si.surface_normal, wo) >= 0.0f;
        const Vec3 normal = front ? si.surface_normal : -si.surface_normal;
        // Glossy lobes the radiance cache holds read its records; the rest take BSDF-sampled rays.
        thread_local RadianceCache::Field field;
        const bool cached = glossy && radiance_cache_ && radiance_order_for(bsdf, settings_.radiance_cache) > 0 &&
                            radiance_field(si.p, normal, &field, context);
        // Light sampling alone finds the emitters for cached lobes (their records hold no emission).
        const bool glossy_rays_sampled = glossy && !cached;
        // A cached lobe traces no BSDF-sampled ray, whose emission was half of the direct light
        // (MIS): a second light sample takes its place.
        const int light_samples = cached ? kCachedLobeLightSamples : 1;
        // A pixel traces glossy rays at a share of its samples, from the lobes' share of the
        // point's reflectance (kGlossyRaysPerLobeShare): the rays are the costliest part of a
        // point, and where the lobes send little of its light, little of its noise.
        const PixelShare glossy_share =
            glossy_rays_sampled ? context.pixel_share(kGlossyRaysPerLobeShare * bsdf.glossy_share(wo)) : PixelShare{};
        // The light sample's MIS weight against the rays counts the rays a point gets on average.
        const float rays = static_cast<float>(glossy_rays) / glossy_share.weight;
        Color direct(0.0f);
        for (int i = 0; i < light_samples; ++i)
            direct += sample_direct_light(rs, *direct_lights_, si, bsdf, wo, context, false, kAllLobes,
                                          glossy_rays_sampled ? glossy_lobes : LobeMask(0), rays);
        radiance.add_direct(direct / static_cast<float>(light_samples));
        if (gatherer_) {
            const Color rho = bsdf.diffuse_reflectance(wo);
            if (max_component(rho) > 0.0f) {
                const Vec3 ng = glm::dot(si.geometric_normal, wo) >= 0.0f ? si.geometric_normal : -si.geometric_normal;
                const DiffusePoint point{si.p, normal, ng, footprint.at(length)};
                radiance.add_indirect(rho * kInvPi * indirect_irradiance(point, context));
            }
            if (cached) {
                // The lobe integrates the records' incident radiance (radiance_cache.h): samples
                // of a smooth field, no rays.
                const uint32_t samples = std::max<uint32_t>(settings_.radiance_cache.samples, 1);
                Color sum(0.0f);
                for (uint32_t i = 0; i < samples; ++i) {
                    const float u_lobe = context.next_1d();
                    const Vec2 u = context.next_2d();
                    const std::optional<BsdfSample> s = bsdf.sample(wo, u_lobe, u, TransportMode::Radiance, glossy_lobes);
                    if (s && !is_black(s->weight)) sum += s->weight * field.incident(s->wi);
                }
                // The band-limited field rings below zero beside sharp features; its integral
                // over the lobe stays positive but for rare points (clamping each direction
                // instead biased glossy light by +3 %: radiance_cache_test).
                radiance.add_indirect(glm::max(sum / static_cast<float>(samples), Color(0.0f)));
            } else if (glossy && glossy_share.taken) {
                // Glossy and rough lobes: BSDF-sampled rays reading the photon maps where they land
                // (caustics are the maps'), and the emitters they hit weighted by MIS against
                // light sampling, which alone cannot see an emitter behind rough glass.
                // The diffuse sky, which light sampling leaves to the gather, is light-sampled here
                // too, weighted against these rays: a rough metal under a uniform sky saw it through
                // one ray per sample alone, and stayed grainy at 16 spp.
                const EnvironmentLight* sky = rs.lights_with_sky_peaks ? rs.diffuse_sky.get() : nullptr;
                // The sky's sample comes with the rays, at the same samples: weighed against them.
                const float sky_rays = static_cast<float>(glossy_rays);
                // `sum` is the total as it always was; the parts beside it: what the rays found at
                // once (emitters, the sky) is direct light, what they gathered beyond, indirect.
                Color sum(0.0f), sum_direct(0.0f), sum_indirect(0.0f);
                if (sky) {
                    float pdf = 0.0f;
                    const Vec3 wi = sky->sample(context.next_2d(), &pdf);
                    const Color f = pdf > 0.0f ? bsdf.eval(wo, wi, TransportMode::Radiance, glossy_lobes) : Color(0.0f);
                    if (!is_black(f)) {
                        ++context.counters.shadow_rays;
                        const Ray shadow{rs.tracer->offset_origin(si.p, si.geometric_normal, wi), wi};
                        if (!rs.tracer->occluded(shadow)) {
                            const float weight = power_heuristic(pdf, sky_rays * bsdf.pdf(wo, wi, glossy_lobes));
                            radiance.add_direct(f * sky->radiance(wi) * atmosphere_transmittance(*rs.scene, shadow) *
                                                (std::abs(glm::dot(wi, si.shading_normal)) * weight * glossy_share.weight / pdf));
                        }
                    }
                }
                for (int i = 0; i < glossy_rays; ++i) {
                    // From the pixel's stratified dimensions, as light sampling's: the sky seen
                    // through a rough lobe is smooth, and stratification takes most of its noise.
                    const float u_lobe = context.next_1d();
                    const Vec2 u = context.next_2d();
                    const std::optional<BsdfSample> s =
                        bsdf.sample(wo, u_lobe, u, TransportMode::Radiance, glossy_lobes);
                    if (!s || is_black(s->weight)) continue;
                    float distance = 0.0f;
                    FinalGatherer::FirstHitEmission emitted;
                    Color gathered = gatherer_->gather_ray_radiance(spawn_ray(rs, si, s->wi), context.rng,
                                                                    context.counters, &distance, &emitted,
                                                                    glossy_ray_cone(footprint, length, *s, rays));
                    // A ray that left the scene at once saw the diffuse sky (weighted against the
                    // sky's light sample above) and the fog's light on the way (not weighted: the
                    // light sample finds none of it).
                    if (sky && !std::isfinite(distance) && s->kind != LobeKind::Delta)
                        gathered = emitted.in_scattered +
                                   (gathered - emitted.in_scattered) * power_heuristic(sky_rays * s->pdf, sky->pdf(s->wi));
                    sum += s->weight * gathered;
                    (std::isfinite(distance) ? sum_indirect : sum_direct) += s->weight * gathered;
                    if (!is_black(emitted.radiance) && s->kind != LobeKind::Delta) {
                        const float light_pdf = direct_lights_->pdf_incident_triangle(emitted.triangle, si.p, emitted.point);
                        sum += s->weight * emitted.radiance * power_heuristic(rays * s->pdf, light_pdf);
                        sum_direct += s->weight * emitted.radiance * power_heuristic(rays * s->pdf, light_pdf);
                    }
                }
                const float scale = glossy_share.weight / static_cast<float>(glossy_rays);
                radiance.total += sum * scale;
                radiance.direct += sum_direct * scale;
                radiance.indirect += sum_indirect * scale;
            }
        } else if (maps_->global) {
            radiance.add_indirect(maps_->global->estimate_radiance(si.p, normal, bsdf, wo,
                                                                   estimate_options_at(global_options_, si, bsdf, front)));
        }
        // Last, so that what the point sends otherwise is known (CausticVisibility::may_show).
        // A caustic estimate (k photons over a disc most often wider than the pixel) varies
        // little across the pixel: a share of its samples take it (kCausticEstimateShare).
        const PixelShare caustic_share = context.pixel_share(kCausticEstimateShare);
        if (maps_->caustic && caustic_share.taken) {
            ++context.counters.caustic_points;
            // The rays (or the radiance cache) of the other non-delta lobes follow glossy lobes to
            // the lights: they hold the glossy caustics those lobes reflect, and with no ideal
            // specular caustics in the map, all the caustic light those lobes see.
            const bool lambertian_only = glossy && !specular_caustics_;
            // The estimate stands for `weight` samples' caustic light, and may be left out only
            // where all of it would not show beside this sample's other light: summed over the
            // pixel's samples, what they leave out stays under kInvisibleCausticRatio of its light.
            if (caustic_visibility_->may_show(si.p, normal, bsdf, wo, luminance(radiance.total) / caustic_share.weight,
                                              lambertian_only ? kLambertianLobe : kNonDeltaLobes)) {
                RadianceEstimateOptions options = estimate_options_at(caustic_options_, si, bsdf, front);
                if (lambertian_only)
                    options.lobes = kLambertianLobe;
                else if (glossy)
                    options.restricted_flags = photon_flags::kGlossyCaustic;
                radiance.add_caustic(caustic_share.weight *
                                     maps_->caustic->estimate_radiance(si.p, normal, bsdf, wo, options));
            } else {
                ++context.counters.caustic_skipped;
            }
        }
    }
    if (bsdf.has_delta() && depth < settings_.max_specular_depth) {
        radiance += follow_delta_lobes(bsdf, wo, depth < kBranchDepth, context.rng, [&](const BsdfSample& s) {
            return radiance_along(spawn_ray(rs, si, s.wi), depth + 1, length, footprint, path_importance(importance, s),
                                  context);
        });
    }
    return volume_transmittance(*rs.scene, si) * radiance;
}

}  // namespace photond
