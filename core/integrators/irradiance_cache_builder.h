// Filling the irradiance cache (and, with another CacheRecordKind, the radiance cache's records:
// core/integrators/radiance_cache.h) before the render pass, deterministically, in waves over a
// coarse-to-fine pixel grid (steps 32, 16, ..., 1 pixels). In each wave every candidate pixel's
// camera ray finds its visible diffuse points (through ideal specular surfaces) and, where the
// cache (frozen during the wave) cannot interpolate, gathers a new record; all threads only read
// the cache. Then the wave's records are merged as if one thread inserted them in pixel order
// (core/integrators/irradiance_wave_merge.h: the neighbour searches in parallel, the inserts on one
// thread). The records, and so the image, do not depend on the thread count or on tile order; the
// render pass then mostly reads.
#pragma once

#include <any>
#include <atomic>
#include <memory>

#include "core/camera/camera.h"
#include "core/image/image.h"
#include "core/integrators/final_gather.h"
#include "core/integrators/irradiance_cache.h"
#include "core/util/work_log.h"

namespace photond {

/// How a view's irradiance cache is built. The defaults are the `final` preset's (the job field
/// table, protocol/job_fields.cpp).
struct CacheBuildSettings {
    float accuracy = 0.3f;  // Ward's a: the largest error estimate a record may be used at
    bool gradients = true;  // extrapolate records with their rotation and translation gradients
    float min_spacing_px = 1.5f;  // record spacing a R_i limits, in pixels at the record
    float max_spacing_px = 24.0f;
    uint64_t seed = 1;
    int max_specular_depth = 16;
    /// Points whose camera path's importance is under this get no record (the render pass reads
    /// the photon maps there: kApproximateImportance, core/integrators/integrator.h).
    float approximate_importance = kApproximateImportance;
    int threads = 0;
    std::optional<PixelRect> region;
    const std::atomic<bool>* cancel = nullptr;
    /// Set: each wave's work items and serial sections are recorded here, for the scheduling
    /// model of bench/schedule_simulation.cpp: two phases a wave, "wave N" (the candidate chunks)
    /// and "wave N merge" (the merge's neighbour searches, then its serial inserts).
    WorkLog* work_log = nullptr;

    /// What the cache itself keeps of these (its interpolation rule).
    IrradianceCacheSettings interpolation() const { return {accuracy, gradients}; }
};

struct CacheBuildStatistics {
    uint64_t records = 0;
    uint64_t records_reused = 0;  // taken from the start cache
    uint64_t candidates = 0;  // visible points examined
    int waves = 0;
    RayCounters counters;
    double seconds = 0.0;
};

/// A visible point on a Lambertian surface, where indirect irradiance is asked for.
struct DiffusePoint {
    Vec3 position;
    Vec3 normal;             // shading normal on the viewer's side
    Vec3 geometric_normal;   // on the viewer's side
    float footprint;         // width of a pixel there (world units)
};

/// A visible point where a cache wants a record; `order`: the bands of a radiance record's basis
/// (core/integrators/radiance_cache.h), 0 for irradiance records.
struct CachePoint : DiffusePoint {
    int order = 0;
};

/// The kind of record a wave-built cache holds: which visible points want one, and how it is
/// gathered. The cache itself (an IrradianceCache) holds each record's position, normal and
/// radius, by which it decides where records are valid; a kind may keep more per record.
class CacheRecordKind {
public:
    virtual ~CacheRecordKind() = default;
    /// Separates this kind's random streams from other kinds' at the same pixels.
    virtual uint64_t stream_tag() const = 0;
    /// Whether a visible point with `bsdf`, seen from wo, wants a record; may set point->order.
    virtual bool wants(const Bsdf& bsdf, const Vec3& wo, CachePoint* point) const = 0;
    /// Gathers the record at `point`; what the kind keeps beside it goes in `payload`. Called on
    /// any thread (const).
    virtual IrradianceRecord make_record(const CachePoint& point, Rng& rng, RayCounters& counters,
                                         std::any* payload) const = 0;
    /// The payload of each record the cache takes, in the order it takes them (one thread).
    virtual void accepted(std::any&&) {}
};

/// Radius limits from the pixel spacing limits at a point: a R_i in [min, max] pixels.
inline void record_radius_limits(const CacheBuildSettings& s, float footprint, float* min_radius, float* max_radius) {
    *min_radius = s.min_spacing_px * footprint / s.accuracy;
    *max_radius = s.max_spacing_px * footprint / s.accuracy;
}

/// Gathers a new record at a point, its radius clamped to the pixel limits.
IrradianceRecord make_irradiance_record(const FinalGatherer& gatherer, const DiffusePoint& point,
                                        const CacheBuildSettings& settings, Rng& rng, RayCounters& counters);

/// Fills a cache for `camera`. With `start` (a cache built earlier for another view of the same
/// scene and settings, see start_matches), the cache starts as a copy of it: its records serve
/// this view where they are valid and the waves add records only where none is (Radiance's
/// ambient file carried from view to view). The result depends on `start` and the camera alone.
std::unique_ptr<IrradianceCache> build_irradiance_cache(const RenderScene& scene, const FinalGatherer& gatherer,
                                                        const Camera& camera, const CacheBuildSettings& settings,
                                                        CacheBuildStatistics* statistics,
                                                        const IrradianceCache* start = nullptr);

/// Fills `cache` for `camera` with records of `kind`, in the deterministic waves described above.
void fill_cache_in_waves(const RenderScene& scene, const Camera& camera, const CacheBuildSettings& settings,
                         CacheRecordKind& kind, IrradianceCache& cache, CacheBuildStatistics* statistics);

/// Whether `start` can start a cache of `scene` with `settings`: the same accuracy and gradients,
/// and an octree over the same bounds (records of another scene are not).
bool start_matches(const IrradianceCache& start, const RenderScene& scene, const CacheBuildSettings& settings);

}  // namespace photond
