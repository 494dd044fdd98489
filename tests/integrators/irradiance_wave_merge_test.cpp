// The prepass's wave merge (core/integrators/irradiance_wave_merge.h): its parallel neighbour
// search and serial inserts leave the cache exactly as inserting the wave's records one by one,
// for any thread count; and the prepass's cache is the same for 1, 2 and 7 threads.
#include "core/integrators/irradiance_wave_merge.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "core/integrators/photon_mapping.h"
#include "core/math/rng.h"
#include "core/scene/builtin_scenes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

/// Byte-for-byte equality of two caches' records and octrees.
void expect_same_cache(const IrradianceCache& a, const IrradianceCache& b, const std::string& what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    ASSERT_EQ(0, std::memcmp(a.records().data(), b.records().data(), a.size() * sizeof(IrradianceRecord))) << what;
    ASSERT_EQ(a.nodes().size(), b.nodes().size()) << what;
    for (size_t i = 0; i < a.nodes().size(); ++i) {
        const IrradianceCache::Node &x = a.nodes()[i], &y = b.nodes()[i];
        ASSERT_TRUE(x.center == y.center && x.half_size == y.half_size && x.children == y.children &&
                    x.records == y.records)
            << what << ", node " << i;
    }
}

/// Records on three walls of the unit box with radii over two orders of magnitude (several
/// grid levels), clustered so that records of one wave overlap each other, plus records insert
/// refuses and one larger than the whole cache.
std::vector<WaveRecord> random_wave(Rng& rng, size_t count) {
    std::vector<WaveRecord> wave;
    for (size_t i = 0; i < count; ++i) {
        WaveRecord w;
        const int wall = int(rng.next_float() * 3.0f) % 3;
        const float u = 2.0f * rng.next_float() - 1.0f, v = 2.0f * rng.next_float() - 1.0f;
        w.record.position = wall == 0 ? Vec3(u, v, -1.0f) : wall == 1 ? Vec3(-1.0f, u, v) : Vec3(u, -1.0f, v);
        w.record.normal = wall == 0 ? Vec3(0, 0, 1) : wall == 1 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
        w.record.radius = 0.01f * std::pow(100.0f, rng.next_float() * rng.next_float());
        w.record.irradiance = Color(rng.next_float(), rng.next_float(), rng.next_float());
        w.record.translation_gradient[0] = Vec3(rng.next_float());
        w.min_radius = 0.3f * w.record.radius;
        wave.push_back(w);
    }
    wave[count / 3].record.radius = 0.0f;                                          // refused
    wave[count / 2].record.irradiance.y = std::numeric_limits<float>::quiet_NaN();  // refused
    wave[count - 2].record.radius = 50.0f;  // wider than the root: its level is the whole cache
    return wave;
}

IrradianceCache sequential(const IrradianceCache& start, const std::vector<WaveRecord>& wave) {
    IrradianceCache cache = start;
    for (const WaveRecord& w : wave) cache.insert(w.record, w.min_radius);
    return cache;
}

TEST(IrradianceWaveMerge, EqualsInsertingOneByOneForAnyThreadCount) {
    IrradianceCacheSettings settings;
    settings.accuracy = 0.3f;
    Bounds3 bounds;
    bounds.extend(Vec3(-1.0f));
    bounds.extend(Vec3(1.0f));
    IrradianceCache start(bounds, settings);
    Rng rng(11, 12);
    for (const WaveRecord& w : random_wave(rng, 300)) start.insert(w.record, w.min_radius);

    for (int round = 0; round < 3; ++round) {
        const std::vector<WaveRecord> wave = random_wave(rng, 1500);
        const IrradianceCache expected = sequential(start, wave);

        // The merge must see the wave's own neighbours: with only the cache's candidates (what
        // the wave's gathering sees) the result differs.
        std::vector<uint32_t> candidates;
        IrradianceCache frozen_only = start;
        for (const WaveRecord& w : wave) {
            start.neighbour_candidates(w.record, &candidates);
            frozen_only.insert(w.record, w.min_radius, candidates);
        }
        ASSERT_NE(0, std::memcmp(expected.records().data(), frozen_only.records().data(),
                                 expected.size() * sizeof(IrradianceRecord)));

        for (int threads : {1, 2, 7}) {
            for (bool taken : {false, true}) {
                std::vector<WaveRecord> records = wave;
                if (taken) {  // as the builder does, while the cache is frozen
                    for (WaveRecord& w : records) {
                        if (!IrradianceCache::accepts(w.record)) continue;
                        start.neighbour_candidates(w.record, &w.cache_candidates);
                        w.candidates_taken = true;
                    }
                }
                IrradianceCache merged = start;
                tbb::task_arena arena(threads);
                WorkLog::Phase phase{"merge", {}, 0.0};
                merge_wave(merged, records, arena, &phase);
                expect_same_cache(expected, merged,
                                  "round " + std::to_string(round) + ", " + std::to_string(threads) + " threads");
                // The model sees the merge: parallel items and a serial part, all timed.
                EXPECT_GE(phase.item_seconds.size(), 256u);
                EXPECT_GT(phase.serial_seconds, 0.0);
            }
        }
        start = expected;
    }
    EXPECT_GT(start.size(), 4000u);
}

TEST(IrradianceWaveMerge, PrepassCacheIsTheSameForOneTwoAndSevenThreads) {
    const auto rs = test_support::make_render_scene(make_builtin_scene("cornell-box").value());
    PhotonTracingSettings photons;
    photons.global_photons = 20000;
    photons.caustic_photons = 10000;
    auto maps = std::make_shared<const PhotonMaps>(trace_photons(*rs, photons).value());
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 64, 48).value();
    GatherSettings gather;
    gather.rays = 32;
    const FinalGatherer gatherer(rs, maps, gather);
    const auto build = [&](int threads) {
        CacheBuildSettings settings;
        settings.threads = threads;
        WorkLog log;
        settings.work_log = &log;
        CacheBuildStatistics statistics;
        auto cache = build_irradiance_cache(*rs, gatherer, camera, settings, &statistics);
        // Every wave is a gathering phase and a merge phase.
        EXPECT_EQ(log.phases.size(), 2u * size_t(statistics.waves));
        return cache;
    };
    const auto one = build(1);
    ASSERT_GT(one->size(), 100u);
    expect_same_cache(*one, *build(2), "2 threads");
    expect_same_cache(*one, *build(7), "7 threads");
}

}  // namespace
}  // namespace photond
