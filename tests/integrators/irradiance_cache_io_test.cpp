// The irradiance-cache file format: a cache read back interpolates bit for bit as the one written
// (records and octree restored exactly, not re-inserted), and corrupt, truncated, foreign,
// other-key and resealed-but-broken files are refused with a message naming the problem.
#include "core/integrators/irradiance_cache_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "tests/checked_file_format.h"
#include "core/integrators/irradiance_cache_builder.h"
#include "core/math/rng.h"
#include "core/scene/builtin_scenes.h"
#include "core/scene/interaction.h"
#include "core/util/sha256.h"

namespace photond {
namespace {

constexpr int kImageSize = 24;
const std::string kKey = "rc1-test-key";

struct BuiltCache {
    std::shared_ptr<const RenderScene> scene;
    std::unique_ptr<Camera> camera;
    std::unique_ptr<IrradianceCache> cache;
};

/// A real cache: the prepass of a small cornell-box-diffuse view, built once per executable.
const BuiltCache& cornell_cache() {
    static const BuiltCache built = [] {
        BuiltCache b;
        auto scene =
            std::make_shared<const Scene>(make_builtin_scene("cornell-box-diffuse").value());
        b.scene = RenderScene::create(EmbreeDevice::create().value(), scene).value();
        PhotonTracingSettings photons;
        photons.global_photons = 20000;
        photons.caustic_photons = 0;
        auto maps = std::make_shared<const PhotonMaps>(trace_photons(*b.scene, photons).value());
        b.camera = std::make_unique<Camera>(
            Camera::create(b.scene->scene->cameras.at(0), kImageSize, kImageSize).value());
        GatherSettings gather;
        gather.rays = 64;
        const FinalGatherer gatherer(b.scene, maps, gather);
        CacheBuildSettings settings;
        settings.accuracy = 0.2f;
        settings.threads = 2;
        CacheBuildStatistics statistics;
        b.cache = build_irradiance_cache(*b.scene, gatherer, *b.camera, settings, &statistics);
        return b;
    }();
    return built;
}

const std::vector<uint8_t>& cornell_bytes() {
    static const std::vector<uint8_t> bytes =
        serialize_irradiance_cache(*cornell_cache().cache, kKey).value();
    return bytes;
}

/// Rewrites the trailing checksum, so that a deliberate edit reaches the checks behind it.
void reseal(std::vector<uint8_t>& bytes) {
    const Sha256Digest digest = sha256(std::span(bytes).first(bytes.size() - 32));
    std::memcpy(bytes.data() + bytes.size() - 32, digest.data(), 32);
}

/// Where the fields of a file (with kKey) lie, following the layout in irradiance_cache_io.h.
struct Layout {
    size_t accuracy = 0, gradients = 0, record_count = 0, node_count = 0, records = 0;
    std::vector<size_t> nodes;  // each node's first byte
    static constexpr size_t kRecordSize = 112, kNodeSize = 52;
    static constexpr size_t kRadius = 24;       // offset of IrradianceRecord::radius
    static constexpr size_t kChildren = 16;     // offset of a node's children
    static constexpr size_t kNodeRecords = 48;  // offset of a node's record count
};

uint64_t read_le(const std::vector<uint8_t>& bytes, size_t at, int size) {
    uint64_t value = 0;
    for (int i = size - 1; i >= 0; --i) value = value << 8 | bytes[at + size_t(i)];
    return value;
}

void write_le(std::vector<uint8_t>& bytes, size_t at, int size, uint64_t value) {
    for (int i = 0; i < size; ++i) bytes[at + size_t(i)] = uint8_t(value >> (8 * i));
}

Layout layout_of(const std::vector<uint8_t>& bytes) {
    Layout l;
    const size_t key_size = read_le(bytes, 20, 4);
    l.accuracy = 24 + key_size;
    l.gradients = l.accuracy + 4;
    l.record_count = l.gradients + 1;
    l.node_count = l.record_count + 8;
    l.records = l.node_count + 16;
    size_t at = l.records + read_le(bytes, l.record_count, 8) * Layout::kRecordSize;
    for (uint64_t n = read_le(bytes, l.node_count, 8); n > 0; --n) {
        l.nodes.push_back(at);
        at += Layout::kNodeSize + 4 * read_le(bytes, at + Layout::kNodeRecords, 4);
    }
    EXPECT_EQ(at + 32, bytes.size());
    return l;
}

/// The exact result of one lookup: found or not, and the colour's bits.
struct Lookup {
    bool found = false;
    std::array<uint32_t, 3> bits{};
    bool operator==(const Lookup&) const = default;
};

Lookup lookup(const IrradianceCache& cache, const Vec3& p, const Vec3& n, float accuracy_scale) {
    Color e(-1.0f);
    Lookup result;
    result.found = cache.interpolate(p, n, &e, accuracy_scale);
    result.bits = {std::bit_cast<uint32_t>(e.x), std::bit_cast<uint32_t>(e.y),
                   std::bit_cast<uint32_t>(e.z)};
    return result;
}

struct QueryPoint {
    Vec3 position;
    Vec3 normal;
};

/// Several thousand points where the cache is asked: near every record (with its normal, a tilted
/// one and the opposite one) and on the surfaces the camera sees at random sub-pixel positions.
std::vector<QueryPoint> query_points(const BuiltCache& b) {
    std::vector<QueryPoint> points;
    Rng rng(17, 4);
    const float a = b.cache->settings().accuracy;
    for (const IrradianceRecord& r : b.cache->records()) {
        for (int i = 0; i < 4; ++i) {
            const Vec3 offset =
                Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - Vec3(0.5f);
            const Vec3 tilt =
                0.2f * (Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - Vec3(0.5f));
            const Vec3 normal = i == 2   ? glm::normalize(r.normal + tilt)
                                : i == 3 ? -r.normal
                                         : r.normal;
            points.push_back({r.position + offset * (a * r.radius), normal});
        }
    }
    for (int i = 0; i < 3000; ++i) {
        const CameraRay ray =
            b.camera->generate_ray(kImageSize * rng.next_float(), kImageSize * rng.next_float());
        const auto hit = b.scene->tracer->intersect(Ray{ray.origin, ray.direction});
        if (!hit) continue;
        const SurfaceInteraction si = make_interaction(*b.scene->scene, *hit, ray.direction);
        const Vec3 n = glm::dot(si.shading_normal, ray.direction) <= 0.0f ? si.shading_normal
                                                                          : -si.shading_normal;
        points.push_back({si.p, n});
    }
    return points;
}

TEST(IrradianceCacheIo, RoundTripInterpolatesBitIdentically) {
    const BuiltCache& b = cornell_cache();
    const IrradianceCache& cache = *b.cache;
    ASSERT_GT(cache.size(), 50u);
    ASSERT_GT(cache.nodes().size(), 8u);
    const std::vector<uint8_t>& bytes = cornell_bytes();
    EXPECT_EQ(read_irradiance_cache_key(bytes), kKey);

    Expected<std::unique_ptr<IrradianceCache>> loaded = deserialize_irradiance_cache(bytes, kKey);
    ASSERT_TRUE(loaded) << loaded.error().message;
    const IrradianceCache& copy = **loaded;
    ASSERT_EQ(copy.size(), cache.size());
    EXPECT_EQ(std::memcmp(copy.records().data(), cache.records().data(),
                          cache.size() * sizeof(IrradianceRecord)),
              0);
    EXPECT_EQ(copy.settings().accuracy, cache.settings().accuracy);
    EXPECT_EQ(copy.settings().gradients, cache.settings().gradients);
    ASSERT_EQ(copy.nodes().size(), cache.nodes().size());
    for (size_t i = 0; i < cache.nodes().size(); ++i) {
        EXPECT_EQ(copy.nodes()[i].children, cache.nodes()[i].children) << i;
        EXPECT_EQ(copy.nodes()[i].records, cache.nodes()[i].records) << i;
    }
    // Serialising what was read gives the same bytes.
    EXPECT_EQ(serialize_irradiance_cache(copy, kKey).value(), bytes);

    const std::vector<QueryPoint> points = query_points(b);
    ASSERT_GT(points.size(), 3000u);
    size_t found = 0, missed = 0;
    for (const QueryPoint& q : points) {
        for (float scale : {1.0f, 1.5f}) {  // the path lookup and the widened candidate search
            const Lookup expected = lookup(cache, q.position, q.normal, scale);
            ASSERT_EQ(lookup(copy, q.position, q.normal, scale), expected)
                << q.position.x << " " << scale;
            (expected.found ? found : missed) += 1;
        }
    }
    std::printf("%zu records, %zu nodes, %zu bytes; %zu lookups found, %zu not\n", cache.size(),
                cache.nodes().size(), bytes.size(), found, missed);
    // Both answers occur, so that the comparison means something.
    EXPECT_GT(found, points.size());
    EXPECT_GT(missed, 0u);
}

TEST(IrradianceCacheIo, FromStateRestoresAndReinsertingDoesNot) {
    const IrradianceCache& cache = *cornell_cache().cache;
    Expected<std::unique_ptr<IrradianceCache>> restored =
        IrradianceCache::from_state(cache.state());
    ASSERT_TRUE(restored) << restored.error().message;
    EXPECT_EQ(serialize_irradiance_cache(**restored, kKey).value(), cornell_bytes());
    // Why the state is stored: inserting the records again clamps their radii again.
    IrradianceCache reinserted(cornell_cache().scene->scene->bounds, cache.settings());
    for (const IrradianceRecord& r : cache.records()) reinserted.insert(r, 0.0f);
    EXPECT_NE(serialize_irradiance_cache(reinserted, kKey).value(), cornell_bytes());
}

TEST(IrradianceCacheIo, AnEmptyCacheRoundTrips) {
    Bounds3 bounds;
    bounds.extend(Vec3(-1.0f, 0.0f, 2.0f));
    bounds.extend(Vec3(1.0f, 3.0f, 5.0f));
    IrradianceCacheSettings settings;
    settings.accuracy = 1.0f;
    settings.gradients = false;
    const IrradianceCache empty(bounds, settings);
    const std::vector<uint8_t> bytes = serialize_irradiance_cache(empty, "").value();
    Expected<std::unique_ptr<IrradianceCache>> loaded = deserialize_irradiance_cache(bytes, "");
    ASSERT_TRUE(loaded) << loaded.error().message;
    EXPECT_EQ((*loaded)->size(), 0u);
    EXPECT_FALSE((*loaded)->settings().gradients);
    Color e(0.0f);
    EXPECT_FALSE((*loaded)->interpolate(Vec3(0.0f, 1.0f, 3.0f), Vec3(0, 1, 0), &e));
    EXPECT_EQ(serialize_irradiance_cache(**loaded, "").value(), bytes);

    EXPECT_FALSE(serialize_irradiance_cache(empty, std::string(kMaxIrradianceCacheKey + 1, 'k')));
    EXPECT_TRUE(serialize_irradiance_cache(empty, std::string(kMaxIrradianceCacheKey, 'k')));
}

TEST(IrradianceCacheIo, EveryFlippedByteIsRefused) {
    const std::vector<uint8_t>& original = cornell_bytes();
    const Layout layout = layout_of(original);
    std::vector<size_t> positions;
    // The header and the first record, the root node, random bytes and the checksum.
    for (size_t i = 0; i < layout.records + 16; ++i) positions.push_back(i);
    for (size_t i = 0; i < 60; ++i) positions.push_back(layout.nodes[0] + i);
    Rng rng(21, 0);
    for (int i = 0; i < 60; ++i) positions.push_back(rng.next_u32() % original.size());
    for (size_t i = original.size() - 32; i < original.size(); ++i) positions.push_back(i);
    photond::test::expect_every_flip_refused(original, positions, [](std::span<const uint8_t> bytes) {
        return deserialize_irradiance_cache(bytes, "");
    });
}

TEST(IrradianceCacheIo, EveryTruncationIsRefused) {
    const std::vector<uint8_t>& original = cornell_bytes();
    photond::test::expect_every_truncation_refused(original, 997, [](std::span<const uint8_t> bytes) {
        return deserialize_irradiance_cache(bytes, kKey);
    });
}

TEST(IrradianceCacheIo, ForeignDataAndOtherVersionsAreRefused) {
    std::vector<uint8_t> random(20000);
    Rng rng(3, 3);
    for (uint8_t& b : random) b = uint8_t(rng.next_u32());
    std::vector<uint8_t> photon_map = {'P', 'H', 'O', 'T', 'O', 'N', 'M', 'P',
                                       2,   0,   0,   0,   4,   3,   2,   1};
    for (const std::vector<uint8_t>& foreign : {random, photon_map, std::vector<uint8_t>()}) {
        Expected<std::unique_ptr<IrradianceCache>> result =
            deserialize_irradiance_cache(foreign, "");
        ASSERT_FALSE(result);
        EXPECT_EQ(result.error().message, "not an irradiance-cache file (no \"IRRCACHE\" magic)");
        EXPECT_EQ(read_irradiance_cache_key(foreign), "");
    }
    for (uint32_t version : {0u, 2u, 1000u}) {
        std::vector<uint8_t> bytes = cornell_bytes();
        write_le(bytes, 8, 4, version);
        reseal(bytes);  // a well-formed file of that version
        Expected<std::unique_ptr<IrradianceCache>> result =
            deserialize_irradiance_cache(bytes, kKey);
        ASSERT_FALSE(result);
        EXPECT_EQ(result.error().message, "unsupported irradiance-cache format version " +
                                              std::to_string(version) + " (this build reads 1)");
        EXPECT_EQ(read_irradiance_cache_key(bytes), "");
    }
    std::vector<uint8_t> bytes = cornell_bytes();
    std::swap(bytes[12], bytes[15]);  // the byte-order marker of the other endianness
    reseal(bytes);
    Expected<std::unique_ptr<IrradianceCache>> result = deserialize_irradiance_cache(bytes, kKey);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("another byte order"), std::string::npos)
        << result.error().message;
    bytes = cornell_bytes();
    write_le(bytes, 16, 4, 100);  // record size
    reseal(bytes);
    result = deserialize_irradiance_cache(bytes, kKey);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("100-byte records"), std::string::npos)
        << result.error().message;
}

TEST(IrradianceCacheIo, KeysMustMatchUnlessImporting) {
    const std::vector<uint8_t>& bytes = cornell_bytes();
    Expected<std::unique_ptr<IrradianceCache>> result =
        deserialize_irradiance_cache(bytes, "rc1-other");
    ASSERT_FALSE(result);
    EXPECT_EQ(result.error().message,
              "irradiance cache is for key " + kKey + ", expected rc1-other");
    EXPECT_TRUE(deserialize_irradiance_cache(bytes, ""));  // an import takes any key
    EXPECT_TRUE(deserialize_irradiance_cache(bytes, kKey));
    // The header is enough to read the key.
    EXPECT_EQ(read_irradiance_cache_key(std::span(bytes).first(24 + kKey.size())), kKey);
}

/// Edits a copy of the file, reseals it and returns the message it is refused with.
template <typename Edit>
std::string refusal(Edit&& edit) {
    std::vector<uint8_t> bytes = cornell_bytes();
    edit(bytes, layout_of(bytes));
    reseal(bytes);
    Expected<std::unique_ptr<IrradianceCache>> result = deserialize_irradiance_cache(bytes, kKey);
    return result ? "accepted" : result.error().message;
}

TEST(IrradianceCacheIo, AResealedBrokenStructureIsRefused) {
    // The checksum is not a signature: a rewritten file with a valid checksum reaches the checks
    // of the structure behind it.
    const size_t node_count = cornell_cache().cache->nodes().size();
    const size_t record_count = cornell_cache().cache->size();
    EXPECT_EQ(refusal([](auto&, const Layout&) {}), "accepted");

    EXPECT_EQ(refusal([&](std::vector<uint8_t>& b, const Layout& l) {
                  write_le(b, l.nodes[0] + Layout::kChildren + 4 * 5, 4, node_count + 7);
              }),
              "octree node 0 child 5 is node " + std::to_string(node_count + 7) +
                  " (the octree has " + std::to_string(node_count) + " nodes)");
    EXPECT_EQ(refusal([&](std::vector<uint8_t>& b, const Layout& l) {
                  write_le(b, l.nodes[0] + Layout::kChildren, 4, uint32_t(-2));
              }),
              "octree node 0 child 0 is node -2 (the octree has " + std::to_string(node_count) +
                  " nodes)");

    // The first node that files a record files one past the last.
    const Layout layout = layout_of(cornell_bytes());
    size_t filing = 0;
    while (read_le(cornell_bytes(), layout.nodes[filing] + Layout::kNodeRecords, 4) == 0) ++filing;
    EXPECT_EQ(refusal([&](std::vector<uint8_t>& b, const Layout& l) {
                  write_le(b, l.nodes[filing] + Layout::kNodeSize, 4, record_count);
              }),
              "octree node " + std::to_string(filing) + " files record " +
                  std::to_string(record_count) + " (the cache has " + std::to_string(record_count) +
                  " records)");

    EXPECT_EQ(refusal([](std::vector<uint8_t>& b, const Layout& l) {
                  const float nan = std::numeric_limits<float>::quiet_NaN();
                  std::memcpy(b.data() + l.records + 3 * Layout::kRecordSize + Layout::kRadius,
                              &nan, 4);
              }),
              "irradiance record 3: radius nan is not finite and positive");
    EXPECT_EQ(refusal([](std::vector<uint8_t>& b, const Layout& l) {
                  write_le(b, l.accuracy, 4, std::bit_cast<uint32_t>(1.5f));
              }),
              "irradiance cache accuracy 1.5 is not in (0, 1]");
    EXPECT_EQ(refusal([](std::vector<uint8_t>& b, const Layout& l) { b[l.gradients] = 2; }),
              "settings.gradients is 2 (must be 0 or 1)");
    EXPECT_NE(refusal([](std::vector<uint8_t>& b, const Layout& l) {
                  write_le(b, l.record_count, 8, read_le(b, l.record_count, 8) + 1);
              }).find("do not fill the"),
              std::string::npos);
    EXPECT_NE(refusal([](std::vector<uint8_t>& b, const Layout& l) {
                  write_le(b, l.node_count, 8, uint64_t(1) << 62);
              }).find("do not fill the"),
              std::string::npos);
    // A child pointing back at the root: a cycle.
    EXPECT_NE(refusal([&](std::vector<uint8_t>& b, const Layout& l) {
                  for (size_t octant = 0; octant < 8; ++octant) {
                      const auto child =
                          int32_t(read_le(b, l.nodes[0] + Layout::kChildren + 4 * octant, 4));
                      if (child <= 0) continue;
                      write_le(b, l.nodes[size_t(child)] + Layout::kChildren + 4 * octant, 4, 0);
                  }
              }).find("not a later node"),
              std::string::npos);
}

TEST(IrradianceCacheIo, FromStateRefusesBrokenTrees) {
    const IrradianceCache::State good = cornell_cache().cache->state();
    const auto refused = [&](auto&& edit) {
        IrradianceCache::State state = good;
        edit(state);
        Expected<std::unique_ptr<IrradianceCache>> result =
            IrradianceCache::from_state(std::move(state));
        return result ? std::string("accepted") : result.error().message;
    };
    ASSERT_EQ(refused([](auto&) {}), "accepted");
    // Two of the root's children, the later one made the earlier one's child too (a shared node).
    int32_t first = -1, second = -1, first_octant = -1;
    for (int octant = 0; octant < 8; ++octant) {
        const int32_t child = good.nodes[0].children[size_t(octant)];
        if (child < 0) continue;
        if (first < 0 || child < first) {
            second = std::max(second, first);
            first = child;
            first_octant = octant;
        } else {
            second = std::max(second, child);
        }
    }
    ASSERT_GT(second, first);
    EXPECT_NE(refused([&](auto& s) {
                  s.nodes[size_t(first)].children[0] = second;
              }).find("already the child of node 0"),
              std::string::npos);
    EXPECT_NE(refused([&](auto& s) {
                  s.nodes[0].children[size_t(first_octant)] = -1;
              }).find("is no other node's child"),
              std::string::npos);
    EXPECT_NE(refused([&](auto& s) {
                  s.nodes[size_t(first)].half_size *= 1.0001f;
              }).find("not its parent's octant"),
              std::string::npos);
    EXPECT_NE(refused([&](auto& s) {
                  s.nodes[size_t(first)].center.y += 1e-3f;
              }).find("not its parent's octant"),
              std::string::npos);
    EXPECT_EQ(refused([](auto& s) { s.nodes.clear(); }),
              "irradiance cache octree has no root node");
    EXPECT_NE(refused([](auto& s) { s.nodes[0].half_size = 0.0f; }).find("octree root"),
              std::string::npos);
    EXPECT_NE(refused([](auto& s) {
                  s.records[0].normal.z = std::numeric_limits<float>::infinity();
              }).find("irradiance record 0: normal"),
              std::string::npos);
    EXPECT_NE(refused([](auto& s) {
                  s.records[1].irradiance.y = std::numeric_limits<float>::quiet_NaN();
              }).find("irradiance record 1: irradiance"),
              std::string::npos);
    EXPECT_NE(refused([](auto& s) {
                  s.records[2].translation_gradient[1].x = std::numeric_limits<float>::infinity();
              }).find("irradiance record 2: translation gradient"),
              std::string::npos);
    EXPECT_NE(refused([](auto& s) {
                  s.records[2].radius = -1.0f;
              }).find("irradiance record 2: radius -1"),
              std::string::npos);
    EXPECT_EQ(refused([](auto& s) { s.settings.accuracy = 0.0f; }),
              "irradiance cache accuracy 0 is not in (0, 1]");
    // Record lists: ascending, and every record filed somewhere.
    size_t filing = 0;
    while (good.nodes[filing].records.size() < 2) ++filing;
    EXPECT_NE(refused([&](auto& s) {
                  std::swap(s.nodes[filing].records[0], s.nodes[filing].records[1]);
              }).find("(must be ascending)"),
              std::string::npos);
    EXPECT_NE(refused([](auto& s) {
                  s.records.push_back(s.records.back());
              }).find("is in no octree node"),
              std::string::npos);

    // A chain deeper than the cache ever builds.
    IrradianceCache::State deep;
    deep.nodes.push_back({Vec3(0.0f), 1.0f, {}, {}});
    for (int level = 0; level <= IrradianceCache::kMaxDepth; ++level) {
        IrradianceCache::Node& parent = deep.nodes.back();
        parent.children.fill(-1);
        parent.children[7] = int32_t(deep.nodes.size());
        const float h = 0.5f * parent.half_size;
        deep.nodes.push_back({parent.center + Vec3(h), h, {}, {}});
    }
    deep.nodes.back().children.fill(-1);
    Expected<std::unique_ptr<IrradianceCache>> result = IrradianceCache::from_state(deep);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("deeper than 48 levels"), std::string::npos)
        << result.error().message;
    deep.nodes.pop_back();
    deep.nodes.back().children.fill(-1);
    EXPECT_TRUE(IrradianceCache::from_state(deep));
}

TEST(IrradianceCacheIo, MemoryBytesCountsRecordsAndNodes) {
    const IrradianceCache& cache = *cornell_cache().cache;
    size_t filed = 0;
    for (const IrradianceCache::Node& node : cache.nodes()) filed += node.records.size();
    const size_t least = cache.size() * sizeof(IrradianceRecord) +
                         cache.nodes().size() * sizeof(IrradianceCache::Node) +
                         filed * sizeof(uint32_t);
    EXPECT_GE(cache.memory_bytes(), least);
    EXPECT_LT(cache.memory_bytes(), 3 * least);
    IrradianceCache empty(cornell_cache().scene->scene->bounds, cache.settings());
    EXPECT_LT(empty.memory_bytes(), 1024u);
}

// ---- Files ------------------------------------------------------------------------------------

class IrradianceCacheFileTest : public photond::test::ScratchDirectoryTest {};

TEST_F(IrradianceCacheFileTest, WritesAndReadsBack) {
    const std::filesystem::path path = directory_ / "view.irc";
    const IrradianceCache& cache = *cornell_cache().cache;
    ASSERT_TRUE(write_irradiance_cache_file(path, cache, kKey));
    EXPECT_EQ(files_in_directory(), 1u);  // no temporary left behind
    Expected<std::unique_ptr<IrradianceCache>> loaded = read_irradiance_cache_file(path, kKey);
    ASSERT_TRUE(loaded) << loaded.error().message;
    EXPECT_EQ(serialize_irradiance_cache(**loaded, kKey).value(), cornell_bytes());

    // Overwriting replaces the file.
    const IrradianceCache empty(cornell_cache().scene->scene->bounds, cache.settings());
    ASSERT_TRUE(write_irradiance_cache_file(path, empty, "rc1-second"));
    loaded = read_irradiance_cache_file(path, "rc1-second");
    ASSERT_TRUE(loaded) << loaded.error().message;
    EXPECT_EQ((*loaded)->size(), 0u);
    EXPECT_EQ(files_in_directory(), 1u);
    loaded = read_irradiance_cache_file(path, kKey);
    ASSERT_FALSE(loaded);
    EXPECT_EQ(loaded.error().message,
              path.string() + ": irradiance cache is for key rc1-second, expected " + kKey);

    // Errors name the path.
    Expected<std::unique_ptr<IrradianceCache>> missing =
        read_irradiance_cache_file(directory_ / "missing.irc", "");
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().message.rfind((directory_ / "missing.irc").string() + ": ", 0), 0u);
    Status no_directory = write_irradiance_cache_file(directory_ / "no" / "view.irc", empty, "");
    ASSERT_FALSE(no_directory);
    EXPECT_NE(no_directory.error().message.find("view.irc"), std::string::npos);
    EXPECT_FALSE(read_irradiance_cache_file(directory_, ""));
    EXPECT_FALSE(
        write_irradiance_cache_file(path, empty, std::string(kMaxIrradianceCacheKey + 1, 'k')));
    EXPECT_EQ(files_in_directory(), 1u);

    const std::filesystem::path empty_file = directory_ / "empty.irc";
    std::ofstream(empty_file).close();
    Expected<std::unique_ptr<IrradianceCache>> from_empty =
        read_irradiance_cache_file(empty_file, "");
    ASSERT_FALSE(from_empty);
    EXPECT_EQ(from_empty.error().message,
              empty_file.string() + ": not an irradiance-cache file (no \"IRRCACHE\" magic)");
}

}  // namespace
}  // namespace photond
