// PhotonMapCache on its own: concurrent requests for one key trace once, the memory budget
// evicts the least recently used maps (which stay on disk), files are written atomically and a
// corrupt one is set aside.
#include "server/photon_map_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <barrier>
#include <thread>

#include "core/photon/photon_map_io.h"
#include "core/util/file_io.h"
#include "tests/server/daemon_harness.h"

namespace photond::service {
namespace {

namespace fs = std::filesystem;

std::string key_of(char digit) { return "pm1-" + std::string(64, digit); }

/// Maps of `count` photons in a line, different per `seed`.
PhotonMaps make_maps(size_t count, float seed) {
    std::vector<Photon> photons;
    for (size_t i = 0; i < count; ++i)
        photons.push_back(make_photon(Vec3(float(i), seed, 0.5f * float(i % 7)), Vec3(0, -1, 0),
                                      Color(0.25f, 0.5f, seed), photon_flags::kDirect));
    PhotonMaps maps;
    maps.global = std::make_shared<const PhotonMap>(std::move(photons), count * 2);
    maps.statistics.emitted = count * 2;
    maps.statistics.stored_global = count;
    return maps;
}

class PhotonMapCacheTest : public ::testing::Test {
protected:
    test::TempDir dir_{"photon_map_cache"};
};

TEST_F(PhotonMapCacheTest, ConcurrentRequestsForOneKeyTraceOnce) {
    PhotonMapCache cache(dir_.path(), size_t{64} << 20);
    constexpr int kThreads = 8;
    std::atomic<int> builds{0};
    std::atomic<int> hits{0};
    std::vector<std::shared_ptr<const PhotonMaps>> results(kThreads);
    std::barrier start(kThreads);
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
        threads.emplace_back([&, t] {
            start.arrive_and_wait();
            bool hit = false;
            auto maps = cache.get_or_build(
                key_of('a'),
                [&]() -> Expected<PhotonMaps> {
                    ++builds;
                    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // a slow trace
                    return make_maps(1000, 1.0f);
                },
                &hit);
            ASSERT_TRUE(maps.has_value());
            results[t] = *maps;
            hits += hit;
        });
    }
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(builds.load(), 1);
    EXPECT_EQ(hits.load(), kThreads - 1);
    for (const auto& maps : results) EXPECT_EQ(maps.get(), results[0].get());
    const auto counters = cache.counters();
    EXPECT_EQ(counters.misses, 1u);
    EXPECT_EQ(counters.hits, uint64_t(kThreads - 1));
    EXPECT_TRUE(fs::exists(dir_.path() / (key_of('a') + ".pm")));
}

TEST_F(PhotonMapCacheTest, AFailedBuildIsNotCachedAndTheNextCallerTriesAgain) {
    PhotonMapCache cache(dir_.path(), size_t{64} << 20);
    bool hit = true;
    auto failed = cache.get_or_build(
        key_of('b'), [] { return Expected<PhotonMaps>(Error{"photon pass: cancelled"}); }, &hit);
    ASSERT_FALSE(failed.has_value());
    EXPECT_EQ(failed.error().message, "photon pass: cancelled");
    EXPECT_FALSE(hit);
    EXPECT_FALSE(fs::exists(dir_.path() / (key_of('b') + ".pm")));
    auto built = cache.get_or_build(
        key_of('b'), [] { return Expected<PhotonMaps>(make_maps(10, 2.0f)); }, &hit);
    ASSERT_TRUE(built.has_value());
    EXPECT_FALSE(hit);
}

TEST_F(PhotonMapCacheTest, MemoryBudgetEvictsLeastRecentlyUsedButDiskKeepsThem) {
    const size_t one = make_maps(1000, 0.0f).bytes();
    PhotonMapCache cache(dir_.path(), 2 * one + one / 2);  // room for two sets
    bool hit = false;
    for (char key : {'1', '2'})
        ASSERT_TRUE(cache.get_or_build(
            key_of(key), [&] { return Expected<PhotonMaps>(make_maps(1000, 1.0f)); }, &hit));
    ASSERT_TRUE(cache.get_or_build(
        key_of('1'), [] { return Expected<PhotonMaps>(Error{"must not trace"}); }, &hit));
    EXPECT_TRUE(hit);  // '1' is now the most recently used
    ASSERT_TRUE(cache.get_or_build(
        key_of('3'), [&] { return Expected<PhotonMaps>(make_maps(1000, 3.0f)); }, &hit));
    auto counters = cache.counters();
    EXPECT_EQ(counters.memory_entries, 2u);
    EXPECT_EQ(counters.memory_bytes, 2 * one);

    // '2' left memory but not the disk: still a hit, read back from its file.
    auto from_disk = cache.get_or_build(
        key_of('2'), [] { return Expected<PhotonMaps>(Error{"must not trace"}); }, &hit);
    ASSERT_TRUE(from_disk.has_value()) << from_disk.error().message;
    EXPECT_TRUE(hit);
    EXPECT_EQ((*from_disk)->global->size(), 1000u);
    EXPECT_LE(cache.counters().memory_bytes, 2 * one + one / 2);

    // A budget of zero keeps nothing in memory, everything on disk.
    PhotonMapCache disk_only(dir_.path(), 0);
    auto read = disk_only.get_or_build(
        key_of('3'), [] { return Expected<PhotonMaps>(Error{"must not trace"}); }, &hit);
    ASSERT_TRUE(read.has_value());
    EXPECT_TRUE(hit);
    EXPECT_EQ(disk_only.counters().memory_bytes, 0u);
    EXPECT_EQ(disk_only.keys().size(), 3u);
}

TEST_F(PhotonMapCacheTest, CorruptFileIsMovedAsideAndTracedAgain) {
    {
        PhotonMapCache cache(dir_.path(), size_t{64} << 20);
        bool hit = false;
        ASSERT_TRUE(cache.get_or_build(
            key_of('d'), [] { return Expected<PhotonMaps>(make_maps(500, 1.0f)); }, &hit));
    }
    const fs::path file = dir_.path() / (key_of('d') + ".pm");
    std::string bytes = test::read_file(file);
    bytes[bytes.size() / 2] ^= 1;
    test::write_file(file, bytes);

    std::vector<std::string> log;
    PhotonMapCache cache(dir_.path(), size_t{64} << 20,
                         [&](const std::string& line) { log.push_back(line); });
    bool hit = true;
    int builds = 0;
    auto maps = cache.get_or_build(
        key_of('d'),
        [&] {
            ++builds;
            return Expected<PhotonMaps>(make_maps(500, 1.0f));
        },
        &hit);
    ASSERT_TRUE(maps.has_value());
    EXPECT_FALSE(hit);
    EXPECT_EQ(builds, 1);
    EXPECT_TRUE(fs::exists(file.string() + ".corrupt"));
    EXPECT_EQ(cache.counters().corrupt_files, 1u);
    ASSERT_EQ(log.size(), 1u);
    EXPECT_NE(log[0].find(file.string()), std::string::npos) << log[0];
    EXPECT_TRUE(read_photon_maps_file(file, key_of('d')).has_value());
    // No temporary files are left behind.
    for (const auto& entry : fs::directory_iterator(dir_.path()))
        EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST_F(PhotonMapCacheTest, ImportChecksKeyAndContent) {
    PhotonMapCache cache(dir_.path(), size_t{64} << 20);
    const PhotonMaps maps = make_maps(300, 5.0f);
    auto bytes = serialize_photon_maps(maps, key_of('e'));
    ASSERT_TRUE(bytes.has_value());
    EXPECT_FALSE(cache.import_maps(key_of('f'), *bytes).has_value());  // another key
    EXPECT_FALSE(cache.import_maps("../../etc/passwd", *bytes).has_value());
    std::vector<uint8_t> corrupt = *bytes;
    corrupt[corrupt.size() - 1] ^= 0xff;
    EXPECT_FALSE(cache.import_maps(key_of('e'), corrupt).has_value());
    auto imported = cache.import_maps(key_of('e'), *bytes);
    ASSERT_TRUE(imported.has_value()) << imported.error().message;
    EXPECT_TRUE(*imported);
    EXPECT_EQ(cache.export_maps(key_of('e')), *bytes);
    EXPECT_FALSE(cache.export_maps(key_of('f')).has_value());
    EXPECT_TRUE(PhotonMapCache::is_valid_key(key_of('e')));
    EXPECT_FALSE(PhotonMapCache::is_valid_key("pm1-../x"));
    EXPECT_FALSE(PhotonMapCache::is_valid_key(key_of('E')));
}

}  // namespace
}  // namespace photond::service
