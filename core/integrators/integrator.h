// The interface every integrator implements, and the per-sample context it receives.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "core/accel/ray_tracer.h"
#include "core/integrators/radiance_parts.h"
#include "core/camera/camera.h"
#include "core/material/bsdf.h"
#include "core/math/low_discrepancy.h"
#include "core/math/rng.h"
#include "core/shading/render_scene.h"
#include "core/shading/scene_queries.h"
#include "core/scene/atmosphere.h"
#include "core/scene/interaction.h"
#include "core/util/expected.h"

namespace photond {

/// Which samples of a pixel evaluate a part of its light, and the weight that keeps the pixel's
/// mean unbiased (SampleContext::pixel_share).
struct PixelShare {
    bool taken = true;
    float weight = 1.0f;
};

/// What one camera sample may use: its own random stream and counters. A camera sample also
/// carries its place in its pixel's sample pattern: then its first kStratifiedDraws draws of
/// next_1d/next_2d come from scrambled Sobol' points shared out over the pixel's samples (one
/// independent pattern per draw), so the pixel's samples of, say, the light at the first hit are
/// stratified; later draws, and contexts without a pattern, use the random stream.
struct SampleContext {
    static constexpr uint32_t kStratifiedDraws = 8;  // deeper dimensions gain little

    Rng& rng;
    RayCounters& counters;
    uint64_t pattern_seed = 0;  // 0: no pattern (not a camera sample)
    uint32_t sample_index = 0;  // this sample's index within its pixel
    uint32_t sample_count = 0;  // the pixel's samples (0: not a camera sample)
    uint32_t draws = 0;         // next_1d/next_2d calls so far

    /// A part of the pixel's light that `fraction` (in (0, 1]) of its samples evaluate: the
    /// first c = ceil(fraction * N) of its N samples, each weighted N / c; a context outside a
    /// pixel's samples always evaluates it, with weight 1. The pixel's mean stays unbiased even
    /// where the fraction depends on the sample's own point: its samples are identically
    /// distributed, and for any c the weights of the N samples sum to N. The first samples of a
    /// pixel's pattern are the best stratified over it (a prefix of a (0, 2)-sequence: a net
    /// where c is a power of two). Worth it for a part that is costly and varies little across a
    /// pixel, or is a small share of its light.
    PixelShare pixel_share(float fraction) const {
        if (sample_count <= 1 || !(fraction < 1.0f)) return {};
        const float wanted = std::ceil(std::max(fraction, 0.0f) * static_cast<float>(sample_count));
        const uint32_t count = std::clamp(static_cast<uint32_t>(wanted), 1u, sample_count);
        return {sample_index < count, static_cast<float>(sample_count) / static_cast<float>(count)};
    }

    float next_1d() {
        if (pattern_seed == 0 || draws >= kStratifiedDraws) return rng.next_float();
        return scrambled_sobol_1d(sample_index, hash_indices(pattern_seed, draws++));
    }
    Vec2 next_2d() {
        if (pattern_seed == 0 || draws >= kStratifiedDraws) return rng.next_vec2();
        return scrambled_sobol_2d(sample_index, hash_indices(pattern_seed, draws++));
    }
};

class RenderCacheStore;

/// What Integrator::prepare may use: the view, and where what it builds is kept between jobs.
struct PrepareContext {
    const Camera& camera;
    const CameraDesc& camera_desc;
    int width = 0;
    int height = 0;
    std::string photon_map_key;                 // the content key of the maps it builds on; empty: none
    RenderCacheStore* render_caches = nullptr;  // null: what it builds serves this render only
    std::string start_from;                     // an earlier view's render-cache key to start from
    const std::atomic<bool>* cancel = nullptr;  // set: stop early (what was built is not kept)
};

/// What Integrator::prepare did, for the statistics.
struct PrepareReport {
    bool built = false;          // a cache is in use (built here or taken from the store)
    std::string cache_key;       // its render-cache key (with a store)
    std::string cache_outcome;   // "hit": taken from the store; "miss": built and kept; "": no store
    std::string start_from;      // the key of the cache it started from, if any
    uint64_t records = 0;
    uint64_t records_reused = 0;  // records taken from that cache
    int waves = 0;
    RayCounters counters;        // rays the preparation traced
    /// The radiance cache, when one was built (its seconds are part of the preparation's).
    struct RadianceCacheReport {
        uint64_t records = 0;
        int waves = 0;
        double seconds = 0.0;
    };
    std::optional<RadianceCacheReport> radiance;
};

/// Computes the radiance arriving at the camera along a ray. Implementations are immutable
/// during a render and called concurrently from every worker thread; all randomness comes from
/// the SampleContext, so a pixel's value depends only on its random stream.
class Integrator {
public:
    virtual ~Integrator() = default;
    virtual std::string_view name() const = 0;
    /// The scene it renders (the tile renderer reads the camera rays' first surfaces from it).
    virtual const RenderScene& scene() const = 0;
    /// The radiance along a camera ray, and its parts by how the light arrived (AOVs).
    virtual RadianceParts radiance_parts(const CameraRay& ray, SampleContext& context) const = 0;
    Color radiance(const CameraRay& ray, SampleContext& context) const { return radiance_parts(ray, context).total; }

    /// The name of the pass prepare() runs before the tiles (timed and reported under it), or
    /// empty when this integrator needs none.
    virtual std::string_view preparation_pass() const { return {}; }
    /// Builds what the render of this view reads (the photon-map integrator's irradiance cache),
    /// or takes it from the store. Called once, before render_tiles, from one thread.
    virtual Expected<PrepareReport> prepare(const PrepareContext&) { return PrepareReport{}; }

    /// A cheaper integrator of the same scene and light for the progressive preview
    /// (core/render/preview_renderer.h), which needs nothing prepare() builds; null when this
    /// one is cheap enough per sample and needs no preparation (it renders the preview itself).
    virtual std::unique_ptr<Integrator> make_preview() const { return nullptr; }
};

/// The camera-ray footprint: the width of one pixel per unit of distance along the ray.
inline float pixel_spread(const CameraRay& ray) {
    return 0.5f * (glm::length(ray.direction_dx - ray.direction) + glm::length(ray.direction_dy - ray.direction));
}

/// The width of a camera ray's pixel along its path: `width` at the camera (an orthographic
/// camera's pixel side; 0 for a pinhole) growing by `spread` per unit of distance travelled.
struct RayFootprint {
    float width = 0.0f;
    float spread = 0.0f;
    float texture_scale = 1.0f;  // CameraRay::texture_footprint_scale
    float at(float distance) const { return width + distance * spread; }
    /// The footprint a texture lookup filters over there.
    float texture_at(float distance) const { return texture_scale * at(distance); }
    /// The same cone from the point `distance` along the ray on (a ray continued there).
    RayFootprint from(float distance) const { return {at(distance), spread, texture_scale}; }
};

inline RayFootprint camera_footprint(const CameraRay& ray) {
    return {ray.pixel_width, pixel_spread(ray), ray.texture_footprint_scale};
}

/// The cone of a ray sampled from a lobe at a point `distance` along a camera path of cone
/// `footprint`, one of `rays` such rays there: it goes on from the path's width at the point,
/// spread over the solid angle the sample stands for, 1 / (rays pdf) (a sharp lobe's rays stay
/// narrow). The path's texture scale carries over: the pixel's samples average what their rays
/// meet, as they do at the visible point.
inline RayFootprint glossy_ray_cone(const RayFootprint& footprint, float distance, const BsdfSample& sample,
                                    float rays) {
    const float spread = sample.kind != LobeKind::Delta && sample.pdf > 0.0f ? std::sqrt(1.0f / (rays * sample.pdf)) : 0.0f;
    return {footprint.at(distance), spread, footprint.texture_scale};
}

/// A camera path's importance after ideal specular bounces: the product of their lobes'
/// reflectances and transmittances (Fresnel, tint, coat; largest channel), which never grows
/// along the path. A refraction's weight for radiance also holds 1/eta^2 (in, 0.44 for glass) or
/// eta^2 (out): that is radiance compressed into a smaller solid angle, not a share of the pixel,
/// and it is taken out here (a path into glass, reflected inside and out again, would otherwise
/// fall under the threshold and rise above it). Under kApproximateImportance, `photon-map` reads
/// a visible point's light from the photon maps at once (FinalGatherer::photon_radiance), and its
/// irradiance cache places no record there: Jensen (1996) evaluates the photon map approximately
/// where a ray's contribution is small. A glass sphere's reflection (a Fresnel weight of 0.04
/// head-on) and what its inner reflections show took a quarter of TransmissionTest's records and
/// a sixth of its render pass's rays (README, *The pipeline*).
inline constexpr float kApproximateImportance = 0.1f;
inline float path_importance(float importance, const BsdfSample& delta_sample) {
    const float solid_angle = delta_sample.is_transmission ? delta_sample.eta * delta_sample.eta : 1.0f;
    return importance * max_component(delta_sample.weight) * solid_angle;
}

/// The ray of a camera sample: from the camera itself, which RayTracer::intersect puts on the front
/// side of a surface it lies on (so a camera on a floor sees the room, and the floor below it).
inline Ray primary_ray(const CameraRay& ray) {
    return RayTracer::viewpoint_ray(ray.origin, ray.direction);
}

/// Next-event estimation: one light sample with a shadow ray, lobes in `mask` only. With
/// `use_mis`, area-light samples are weighted by the power heuristic against BSDF sampling.
/// Without `use_mis`, distant area lights (environment, soft suns) still get MIS against one
/// BSDF sample taken here, and the lobes in `mis_lobes` get MIS against `mis_samples` BSDF
/// samples of those lobes with which the caller adds the emission it hits, weighted with
/// power_heuristic(mis_samples * bsdf_pdf, light_pdf) (photon-map's glossy rays).
Color sample_direct_light(const RenderScene& rs, const LightSet& lights, const SurfaceInteraction& si,
                          const Bsdf& bsdf, const Vec3& wo, SampleContext& context, bool use_mis,
                          LobeMask mask = kAllLobes, LobeMask mis_lobes = 0, float mis_samples = 1.0f);
/// The same with the scene's lights.
inline Color sample_direct_light(const RenderScene& rs, const SurfaceInteraction& si, const Bsdf& bsdf,
                                 const Vec3& wo, SampleContext& context, bool use_mis,
                                 LobeMask mask = kAllLobes) {
    return sample_direct_light(rs, *rs.lights, si, bsdf, wo, context, use_mis, mask);
}

/// Next-event estimation at a point x inside `medium` (the atmosphere, or a solid's) seen from wo: one light
/// sample times the phase function and the atmosphere's transmittance to the light (the
/// radiance scattered towards wo per unit of scattering coefficient: the caller's weight holds
/// sigma_s). With `use_mis`, area lights are weighted by the power heuristic
/// against phase-function sampling. The caller's throughput carries the transmittance up to x.
Color sample_direct_light_in_medium(const RenderScene& rs, const HomogeneousMedium& medium, const Vec3& x,
                                    const Vec3& wo, SampleContext& context, bool use_mis);
/// Calls f(x, weight) at `points` distances along `span` of the ray (unit direction), stratified
/// in the transmittance truncated to the span (sample_distance_in_segment, one channel for all,
/// two draws from `context`), weight = T(t) / (pdf(t) points): sums of weight times a quantity
/// at x estimate the quantity's integral along the span, attenuated from the span's start.
template <typename F>
void march_through_medium(const HomogeneousMedium& medium, const Ray& ray, const MediumSpan& span, int points,
                          SampleContext& context, F&& f) {
    const float length = span.t1 - span.t0;
    const float u_channel = context.next_1d();
    const float u_jitter = context.next_1d();
    for (int i = 0; i < points; ++i) {
        const float u = (static_cast<float>(i) + u_jitter) / static_cast<float>(points);
        const SegmentDistance d = sample_distance_in_segment(medium, length, u_channel, u);
        if (!(d.pdf > 0.0f)) continue;
        f(ray.origin + (span.t0 + d.t) * ray.direction,
          medium.transmittance(d.t) / (d.pdf * static_cast<float>(points)));
    }
}

/// Points along a ray segment at which single_scattering samples the light.
inline constexpr int kSingleScatteringPoints = 4;
/// The light `medium` scatters once towards the ray's origin over `span` of the ray (unit
/// direction): kSingleScatteringPoints distances stratified by the transmittance truncated to
/// the span (sample_distance_in_segment, one channel for all), each lit by one light sample
/// (sample_direct_light_in_medium, no MIS). Not attenuated by the span's own transmittance
/// before it: the caller's throughput holds that.
Color single_scattering(const RenderScene& rs, const HomogeneousMedium& medium, const Ray& ray, const MediumSpan& span,
                        SampleContext& context);

}  // namespace photond
