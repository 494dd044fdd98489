#include "core/integrators/irradiance_cache_builder.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <iterator>
#include <string>

#include "core/integrators/direct.h"
#include "core/integrators/irradiance_wave_merge.h"

namespace photond {
namespace {

constexpr uint64_t kRecordStreamTag = 0x69727263616368ull;  // separates record streams
constexpr int kFirstWaveStep = 32;                            // pixels between first-wave candidates
constexpr int kMaxPointsPerPixel = 8;
// Where a candidate's camera ray crosses its pixel: a hair off the centre, 1/1024 pixel right and
// 1/2048 down. A camera on a symmetry plane of the scene maps the image's diagonals and centre
// lines onto edges of the scene (cornell-box: its corner edges lie exactly on the diagonals of a
// square image), and a ray through an edge hits one face or the other as rounding decides: the
// record there takes either face's normal, and every record after it follows (the scene scaled by
// 1.0000001 changed the image visibly). Unequal offsets whose sum is no integer keep every
// candidate off those lines, by about 100 float steps of the coordinates in cornell-box.
constexpr float kCandidateX = 0.5f + 1.0f / 1024.0f;
constexpr float kCandidateY = 0.5f + 1.0f / 2048.0f;

/// The points a camera ray sees through ideal specular surfaces where `kind` wants a record:
/// every delta lobe for the first kBranchDepth bounces, then the heaviest one (deterministic, no
/// random numbers), as long as the path's importance (path_importance) keeps the render pass
/// reading the cache there (CacheBuildSettings::approximate_importance).
void collect_points(const RenderScene& rs, const CacheRecordKind& kind, const Ray& ray, float path_length,
                    RayFootprint footprint, int depth, const CacheBuildSettings& settings, float importance,
                    RayCounters& counters, std::vector<CachePoint>& out) {
    if (out.size() >= kMaxPointsPerPixel || importance < settings.approximate_importance) return;
    const std::optional<Hit> hit = trace_ray(rs, ray, counters);
    if (!hit) return;
    const SurfaceInteraction si = make_interaction(*rs.scene, *hit, ray.direction);
    const Vec3 wo = -ray.direction;
    const Bsdf bsdf = make_bsdf(rs, si, wo);
    const float length = path_length + hit->t;
    CachePoint point;
    if (kind.wants(bsdf, wo, &point)) {
        point.position = si.p;
        point.normal = glm::dot(si.surface_normal, wo) >= 0.0f ? si.surface_normal : -si.surface_normal;
        point.geometric_normal = glm::dot(si.geometric_normal, wo) >= 0.0f ? si.geometric_normal : -si.geometric_normal;
        point.footprint = footprint.at(length);
        out.push_back(point);
    }
    if (!bsdf.has_delta() || depth >= settings.max_specular_depth) return;
    std::array<BsdfSample, 2> lobes;
    const int count = bsdf.delta_lobes(wo, lobes);
    if (count == 0) return;
    int first = 0, last = count;
    if (depth >= kBranchDepth && count == 2) {
        first = average(lobes[1].weight) > average(lobes[0].weight) ? 1 : 0;
        last = first + 1;
    }
    for (int i = first; i < last; ++i) {
        if (is_black(lobes[i].weight)) continue;
        collect_points(rs, kind, spawn_ray(rs, si, lobes[i].wi), length, footprint, depth + 1, settings,
                       path_importance(importance, lobes[i]), counters, out);
    }
}

/// Irradiance records at the Lambertian points.
class IrradianceRecordKind final : public CacheRecordKind {
public:
    IrradianceRecordKind(const FinalGatherer& gatherer, const CacheBuildSettings& settings)
        : gatherer_(gatherer), settings_(settings) {}
    uint64_t stream_tag() const override { return kRecordStreamTag; }
    bool wants(const Bsdf& bsdf, const Vec3& wo, CachePoint*) const override {
        return max_component(bsdf.diffuse_reflectance(wo)) > 0.0f;
    }
    IrradianceRecord make_record(const CachePoint& point, Rng& rng, RayCounters& counters, std::any*) const override {
        return make_irradiance_record(gatherer_, point, settings_, rng, counters);
    }

private:
    const FinalGatherer& gatherer_;
    const CacheBuildSettings& settings_;
};

}  // namespace

IrradianceRecord make_irradiance_record(const FinalGatherer& gatherer, const DiffusePoint& point,
                                        const CacheBuildSettings& settings, Rng& rng, RayCounters& counters) {
    const GatherResult g = gatherer.gather(point.position, point.normal, point.geometric_normal, rng, counters,
                                           settings.gradients);
    float min_radius = 0.0f, max_radius = 0.0f;
    record_radius_limits(settings, point.footprint, &min_radius, &max_radius);
    IrradianceRecord r;
    r.position = point.position;
    r.normal = point.normal;
    // Tabellion & Lamorlette 2004: the harmonic mean distance, within pixel-space limits.
    r.radius = std::clamp(g.harmonic_mean_distance, min_radius, max_radius);
    r.irradiance = g.irradiance;
    r.rotation_gradient = g.rotation_gradient;
    r.translation_gradient = g.translation_gradient;
    // Gradient limiting: across its domain (distance a R, normal deviation about a) a record may
    // change its irradiance by at most the irradiance itself. Gathers right at an edge see hit
    // distances near zero and return enormous translation gradients; extrapolated over a radius
    // raised to the pixel minimum they would blow up (Krivanek et al. 2006 limit R by the
    // gradient; here R is pinned to the pixel limits, so the gradient yields instead).
    const float reach = settings.accuracy * r.radius;
    for (int c = 0; c < 3; ++c) {
        const float limit = r.irradiance[c];
        const float translation = glm::length(r.translation_gradient[c]) * reach;
        if (translation > limit) r.translation_gradient[c] *= translation > 0.0f ? limit / translation : 0.0f;
        const float rotation = glm::length(r.rotation_gradient[c]) * settings.accuracy;
        if (rotation > limit) r.rotation_gradient[c] *= rotation > 0.0f ? limit / rotation : 0.0f;
    }
    return r;
}

bool start_matches(const IrradianceCache& start, const RenderScene& rs, const CacheBuildSettings& settings) {
    const IrradianceCache empty(rs.scene->bounds, settings.interpolation());
    const IrradianceCache::Node& root = empty.nodes().front();
    const IrradianceCache::Node& start_root = start.nodes().front();
    return start.settings().accuracy == settings.accuracy && start.settings().gradients == settings.gradients &&
           start_root.center == root.center && start_root.half_size == root.half_size;
}

void fill_cache_in_waves(const RenderScene& rs, const Camera& camera, const CacheBuildSettings& settings,
                         CacheRecordKind& kind, IrradianceCache& cache, CacheBuildStatistics* statistics) {
    const auto started = std::chrono::steady_clock::now();
    CacheBuildStatistics stats;
    stats.records_reused = cache.size();
    const PixelRect frame{0, 0, camera.width(), camera.height()};
    const PixelRect area = settings.region ? settings.region->intersect(frame) : frame;
    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);

    // A wave's candidates are handed out in chunks of consecutive pixels; each chunk keeps the
    // records it gathers in candidate order, so merging the chunks in order inserts every record
    // in pixel order, whatever thread made it, at a cost per record rather than per pixel.
    struct PixelCandidate {
        int x, y;
    };
    struct Chunk {
        std::vector<WaveRecord> records;
        RayCounters counters;
        uint64_t points = 0;
    };
    // Chunks of up to 64 candidates, at least 1,024 chunks a wave where there are enough
    // candidates (the first waves are sparse and slow per candidate: with 256 their barriers
    // waited longer for the last chunks), fixed by the wave alone.
    constexpr size_t kMaxCandidatesPerChunk = 64, kMinChunksPerWave = 1024;
    // Waves at steps 32, 16, ..., 1, then a repair wave over every pixel: neighbour clamping in
    // later waves can shrink a record that covered a pixel centre when it was visited.
    struct Wave {
        int step;
        bool repair;
    };
    std::vector<Wave> waves;
    for (int step = kFirstWaveStep; step >= 1; step /= 2) waves.push_back({step, false});
    waves.push_back({1, true});
    using Clock = std::chrono::steady_clock;
    const auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    std::vector<PixelCandidate> candidates;
    std::vector<Chunk> chunks;
    std::vector<WaveRecord> wave_records;
    for (const auto [step, repair] : waves) {
        if (settings.cancel && settings.cancel->load()) break;
        Clock::time_point serial_start = Clock::now();
        // This wave's pixels: multiples of `step` not visited by a coarser wave (all in repair).
        candidates.clear();
        for (int y = area.y0 - area.y0 % step; y < area.y1; y += step) {
            for (int x = area.x0 - area.x0 % step; x < area.x1; x += step) {
                if (x < area.x0 || y < area.y0) continue;
                const bool visited = !repair && step < kFirstWaveStep && x % (2 * step) == 0 && y % (2 * step) == 0;
                if (!visited) candidates.push_back({x, y});
            }
        }
        const size_t per_chunk = std::clamp<size_t>(candidates.size() / kMinChunksPerWave, 1, kMaxCandidatesPerChunk);
        chunks.assign((candidates.size() + per_chunk - 1) / per_chunk, Chunk{});
        WorkLog::Phase* phase = nullptr;
        if (settings.work_log) {
            settings.work_log->phases.push_back({"wave " + std::to_string(step) + (repair ? " repair" : ""),
                                                 std::vector<double>(chunks.size(), 0.0), 0.0});
            phase = &settings.work_log->phases.back();
            phase->serial_seconds = seconds_since(serial_start);
        }
        arena.execute([&] {
            tbb::parallel_for(size_t(0), chunks.size(), [&](size_t chunk_index) {
                enable_flush_denormals();
                const Clock::time_point chunk_start = phase ? Clock::now() : Clock::time_point{};
                Chunk& chunk = chunks[chunk_index];
                const size_t end = std::min(candidates.size(), (chunk_index + 1) * per_chunk);
                std::vector<CachePoint> points;
                for (size_t i = chunk_index * per_chunk; i < end; ++i) {
                    const PixelCandidate& c = candidates[i];
                    const CameraRay ray = camera.generate_ray(c.x + kCandidateX, c.y + kCandidateY);
                    points.clear();
                    collect_points(rs, kind, primary_ray(ray), 0.0f, camera_footprint(ray), 0, settings, 1.0f,
                                   chunk.counters, points);
                    chunk.points += points.size();
                    for (size_t k = 0; k < points.size(); ++k) {
                        Color unused;
                        if (cache.interpolate(points[k].position, points[k].normal, &unused)) continue;
                        const uint64_t pixel = static_cast<uint64_t>(c.y) * camera.width() + c.x;
                        Rng rng = Rng::for_stream(settings.seed, kind.stream_tag(), pixel, k);
                        WaveRecord& added = chunk.records.emplace_back();
                        added.record = kind.make_record(points[k], rng, chunk.counters, &added.payload);
                        float max_radius = 0.0f;
                        record_radius_limits(settings, points[k].footprint, &added.min_radius, &max_radius);
                        // The cache is frozen for the wave: its part of the merge's neighbour
                        // search is done here, in parallel (core/integrators/irradiance_wave_merge.h).
                        if (IrradianceCache::accepts(added.record)) {
                            cache.neighbour_candidates(added.record, &added.cache_candidates);
                            added.candidates_taken = true;
                        }
                    }
                }
                if (phase) phase->item_seconds[chunk_index] = seconds_since(chunk_start);
            });
        });
        serial_start = Clock::now();
        // Merge in candidate order, as if one thread inserted each record in turn.
        wave_records.clear();
        for (Chunk& chunk : chunks) {
            std::move(chunk.records.begin(), chunk.records.end(), std::back_inserter(wave_records));
            stats.counters += chunk.counters;
            stats.candidates += chunk.points;
        }
        WorkLog::Phase* merge_phase = nullptr;
        if (settings.work_log) {
            phase->serial_seconds += seconds_since(serial_start);
            settings.work_log->phases.push_back({phase->name + " merge", {}, 0.0});
            merge_phase = &settings.work_log->phases.back();
        }
        // The records the cache takes, in the order it takes them: their payloads too.
        for (WaveRecord& added : wave_records)
            if (IrradianceCache::accepts(added.record)) kind.accepted(std::move(added.payload));
        merge_wave(cache, wave_records, arena, merge_phase);
        ++stats.waves;
    }
    stats.records = cache.size();
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    if (statistics) *statistics = stats;
}

std::unique_ptr<IrradianceCache> build_irradiance_cache(const RenderScene& rs, const FinalGatherer& gatherer,
                                                        const Camera& camera, const CacheBuildSettings& settings,
                                                        CacheBuildStatistics* statistics, const IrradianceCache* start) {
    auto cache = start ? std::make_unique<IrradianceCache>(*start)
                       : std::make_unique<IrradianceCache>(rs.scene->bounds, settings.interpolation());
    IrradianceRecordKind kind(gatherer, settings);
    fill_cache_in_waves(rs, camera, settings, kind, *cache, statistics);
    return cache;
}

}  // namespace photond
