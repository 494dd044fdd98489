// Photon-map caching: SHA-256, scene content keys, kd-trees adopted in tree order, and the binary
// photon-map format (round trip, corruption, foreign files, versions, keys, atomic writes).
#include "core/photon/photon_map_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <thread>

#include "tests/checked_file_format.h"
#include "core/math/rng.h"
#include "core/photon/photon_tracer.h"
#include "core/scene/builtin_scenes.h"
#include "core/photon/photon_map_key.h"
#include "core/scene/scene_hash.h"
#include "core/util/sha256.h"

namespace photond {
namespace {

std::span<const uint8_t> as_bytes(std::string_view text) {
    return {reinterpret_cast<const uint8_t*>(text.data()), text.size()};
}

std::shared_ptr<EmbreeDevice> device() {
    static std::shared_ptr<EmbreeDevice> d = EmbreeDevice::create().value();
    return d;
}

PhotonTracingSettings small_settings() {
    PhotonTracingSettings settings;
    settings.global_photons = 20000;
    settings.caustic_photons = 10000;
    settings.seed = 7;
    settings.irradiance_stride = 4;  // a precomputed irradiance map too
    return settings;
}

/// The Cornell box's maps, traced once for the whole executable.
const PhotonMaps& cornell_maps() {
    static const PhotonMaps maps = [] {
        auto scene = std::make_shared<const Scene>(make_builtin_scene("cornell-box").value());
        auto render_scene = RenderScene::create(device(), scene).value();
        return trace_photons(*render_scene, small_settings()).value();
    }();
    return maps;
}

const std::string kKey = "pm1-test-key";

const std::vector<uint8_t>& cornell_bytes() {
    static const std::vector<uint8_t> bytes = serialize_photon_maps(cornell_maps(), kKey).value();
    return bytes;
}

/// Rewrites the trailing checksum, so that a deliberate edit reaches the checks behind it.
void reseal(std::vector<uint8_t>& bytes) {
    const Sha256Digest digest = sha256(std::span(bytes).first(bytes.size() - 32));
    std::memcpy(bytes.data() + bytes.size() - 32, digest.data(), 32);
}

bool same_photons(std::span<const Photon> a, std::span<const Photon> b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

/// k_nearest and for_each_in_radius at many points give the same indices and distances.
void expect_same_queries(const PhotonKdTree& a, const PhotonKdTree& b, const Bounds3& region) {
    Rng rng(11, 3);
    KnnResult ra, rb;
    const Vec3 extent = region.extent();
    for (int i = 0; i < 2000; ++i) {
        const Vec3 p =
            region.lower + Vec3(rng.next_float(), rng.next_float(), rng.next_float()) * extent;
        const uint32_t k = 1 + rng.next_u32() % 80;
        const float radius = i % 2 ? std::numeric_limits<float>::infinity() : 0.3f;
        a.k_nearest(p, k, radius, ra);
        b.k_nearest(p, k, radius, rb);
        ASSERT_EQ(ra.size(), rb.size());
        EXPECT_EQ(ra.radius2, rb.radius2);
        for (size_t j = 0; j < ra.size(); ++j) {
            ASSERT_EQ(ra.neighbors[j].index, rb.neighbors[j].index);
            ASSERT_EQ(ra.neighbors[j].dist2, rb.neighbors[j].dist2);
        }
        if (i % 10 == 0) {
            std::vector<std::pair<uint32_t, float>> fa, fb;
            a.for_each_in_radius(p, 0.5f, [&](uint32_t index, float d2) {
                fa.push_back({index, d2});
            });
            b.for_each_in_radius(p, 0.5f, [&](uint32_t index, float d2) {
                fb.push_back({index, d2});
            });
            ASSERT_EQ(fa, fb);
        }
    }
}

// ---- SHA-256 ----------------------------------------------------------------------------------

TEST(Sha256, KnownVectors) {
    // FIPS 180-4 examples.
    EXPECT_EQ(sha256_hex({}), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    EXPECT_EQ(sha256_hex(as_bytes("abc")),
              "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    EXPECT_EQ(sha256_hex(as_bytes("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq")),
              "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, ChunkedUpdatesEqualOneUpdate) {
    std::vector<uint8_t> data(300000);
    Rng rng(1, 2);
    for (uint8_t& b : data) b = uint8_t(rng.next_u32());
    Sha256 chunked;
    size_t position = 0;
    while (position < data.size()) {
        // Sizes around the internal buffer's: tiny, medium and larger than it.
        const size_t size = std::min<size_t>(data.size() - position, rng.next_u32() % 3000);
        chunked.update(std::span(data).subspan(position, size));
        position += size;
    }
    EXPECT_EQ(chunked.finish(), sha256(data));
    // finish() starts over: the hasher can be reused.
    chunked.update(as_bytes("abc"));
    EXPECT_EQ(Sha256::hex(chunked.finish()),
              "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Sha256, LengthPrefixesSeparateConcatenations) {
    Sha256 a, b;
    a.update_string("ab");
    a.update_string("c");
    b.update_string("a");
    b.update_string("bc");
    EXPECT_NE(a.finish(), b.finish());
    // Values are hashed little-endian.
    Sha256 c;
    c.update_value(uint32_t(0x64636261));  // "abcd" in little-endian
    EXPECT_EQ(c.finish(), sha256(as_bytes("abcd")));
}

// ---- Scene keys -------------------------------------------------------------------------------

TEST(SceneHash, CamerasAndNamesDoNotChangeTheKey) {
    Scene scene = make_builtin_scene("cornell-box").value();
    const PhotonTracingSettings settings = small_settings();
    const std::string key = photon_map_key(scene, settings);
    EXPECT_EQ(key.size(), 4u + 64u);
    EXPECT_EQ(key.rfind("pm1-", 0), 0u);

    Scene other_view = scene;
    ASSERT_FALSE(other_view.cameras.empty());
    other_view.cameras[0].position += Vec3(1.0f, 0.5f, 0.0f);
    other_view.cameras[0].vfov_deg = 60.0f;
    other_view.cameras.push_back(other_view.cameras[0]);
    other_view.name = "renamed";
    other_view.materials[0].name = "renamed material";
    EXPECT_EQ(photon_map_key(other_view, settings), key);

    PhotonTracingSettings other_run = settings;
    other_run.threads = 3;
    std::atomic<bool> cancel{false};
    other_run.cancel = &cancel;
    EXPECT_EQ(photon_map_key(scene, other_run), key);

    // -0.0 and 0.0 are the same geometry.
    Scene negative_zero = scene;
    Scene positive_zero = scene;
    negative_zero.positions[0].x = -0.0f;
    positive_zero.positions[0].x = 0.0f;
    EXPECT_EQ(scene_content_hash(negative_zero), scene_content_hash(positive_zero));
}

TEST(SceneHash, LightTransportChangesTheKey) {
    const Scene scene = make_builtin_scene("cornell-box").value();
    const PhotonTracingSettings settings = small_settings();
    const std::string key = photon_map_key(scene, settings);

    const auto with_settings = [&](auto&& edit) {
        PhotonTracingSettings changed = settings;
        edit(changed);
        return photon_map_key(scene, changed);
    };
    EXPECT_NE(with_settings([](auto& s) { s.seed = 8; }), key);
    EXPECT_NE(with_settings([](auto& s) { s.global_photons = 20001; }), key);
    EXPECT_NE(with_settings([](auto& s) { s.caustic_photons = 0; }), key);
    EXPECT_NE(with_settings([](auto& s) { s.max_bounces = 63; }), key);
    EXPECT_NE(with_settings([](auto& s) { s.max_emitted_per_stored = 999; }), key);
    EXPECT_NE(with_settings([](auto& s) { s.irradiance_stride += 1; }), key);
    EXPECT_NE(with_settings([](auto& s) { s.k_irradiance += 1; }), key);

    const auto with_scene = [&](auto&& edit) {
        Scene changed = scene;
        edit(changed);
        return photon_map_key(changed, settings);
    };
    EXPECT_NE(with_scene([](Scene& s) { s.materials[0].base_color.y += 0.01f; }), key);
    EXPECT_NE(with_scene([](Scene& s) { s.materials[0].roughness = 0.5f; }), key);
    EXPECT_NE(with_scene([](Scene& s) { s.materials[0].double_sided ^= true; }), key);
    EXPECT_NE(with_scene([](Scene& s) { s.positions[3].y += 1e-6f; }), key);
    EXPECT_NE(with_scene([](Scene& s) { s.normals[3] = -s.normals[3]; }), key);
    EXPECT_NE(with_scene([](Scene& s) { s.uvs[3].x += 0.5f; }), key);
    EXPECT_NE(with_scene([](Scene& s) { std::swap(s.triangles[0].x, s.triangles[0].y); }), key);
    EXPECT_NE(with_scene([](Scene& s) { s.triangle_materials[0] ^= 1; }), key);
    EXPECT_NE(with_scene([](Scene& s) {
                  Texture t;
                  t.width = t.height = 1;
                  t.texels = {Color(0.5f)};
                  s.textures.push_back(std::make_shared<const Texture>(t));
              }),
              key);
    // Light intensity: an emissive material here, a punctual light in "caustic".
    EXPECT_NE(with_scene([](Scene& s) {
                  for (Material& m : s.materials) {
                      if (m.is_emissive()) m.emission *= 1.01f;
                  }
              }),
              key);
    const Scene caustic = make_builtin_scene("caustic").value();
    ASSERT_FALSE(caustic.lights.empty());
    Scene brighter = caustic;
    brighter.lights[0].intensity *= 1.01f;
    EXPECT_NE(photon_map_key(brighter, settings), photon_map_key(caustic, settings));
    Scene renamed_light = caustic;
    renamed_light.lights[0].name = "another name";
    EXPECT_EQ(photon_map_key(renamed_light, settings), photon_map_key(caustic, settings));
}

// ---- kd-tree in tree order --------------------------------------------------------------------

std::vector<Photon> random_photons(size_t count, uint64_t seed) {
    Rng rng(seed, 1);
    std::vector<Photon> photons;
    for (size_t i = 0; i < count; ++i) {
        // Coarse coordinates, so that many photons share a coordinate (ties in the splits).
        const Vec3 p(float(rng.next_u32() % 50) * 0.1f, rng.next_float(),
                     float(rng.next_u32() % 7) - 3.0f);
        photons.push_back(make_photon(p, Vec3(0, 0, 1), Color(1.0f), uint8_t(i % 4)));
    }
    return photons;
}

TEST(PhotonKdTreeFromTreeOrder, AdoptsABuiltTreeAndAnswersIdentically) {
    const PhotonKdTree built(random_photons(20000, 5));
    const std::vector<Photon> order(built.photons().begin(), built.photons().end());
    Expected<PhotonKdTree> adopted = PhotonKdTree::from_tree_order(order);
    ASSERT_TRUE(adopted) << adopted.error().message;
    EXPECT_TRUE(same_photons(adopted->photons(), built.photons()));
    EXPECT_EQ(adopted->bounds().lower, built.bounds().lower);
    EXPECT_EQ(adopted->bounds().upper, built.bounds().upper);
    expect_same_queries(built, *adopted, built.bounds());

    for (size_t n : {0u, 1u, 16u, 17u, 33u}) {
        const PhotonKdTree small(random_photons(n, 9));
        Expected<PhotonKdTree> again = PhotonKdTree::from_tree_order(
            std::vector<Photon>(small.photons().begin(), small.photons().end()));
        ASSERT_TRUE(again) << n << ": " << again.error().message;
        EXPECT_EQ(again->size(), n);
    }
}

TEST(PhotonKdTreeFromTreeOrder, RefusesBrokenTrees) {
    const PhotonKdTree built(random_photons(5000, 6));
    const std::vector<Photon> order(built.photons().begin(), built.photons().end());
    const uint32_t root = uint32_t(order.size() / 2);

    std::vector<Photon> nan = order;
    nan[123].position.y = std::numeric_limits<float>::quiet_NaN();
    Expected<PhotonKdTree> result = PhotonKdTree::from_tree_order(nan);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("non-finite"), std::string::npos)
        << result.error().message;

    // An unsorted array: a photon of the far left moved to the far right of the root's split.
    std::vector<Photon> unsorted = order;
    const uint32_t axis = order[root].split_axis();
    const auto lowest = std::min_element(
        unsorted.begin(), unsorted.begin() + root,
        [&](const Photon& a, const Photon& b) { return a.position[axis] < b.position[axis]; });
    const auto highest = std::max_element(
        unsorted.begin() + root + 1, unsorted.end(),
        [&](const Photon& a, const Photon& b) { return a.position[axis] < b.position[axis]; });
    ASSERT_LT(lowest->position[axis], highest->position[axis]);
    std::swap(lowest->position, highest->position);
    result = PhotonKdTree::from_tree_order(unsorted);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("subtree reaches"), std::string::npos)
        << result.error().message;

    // Split axes: a leaf-marked inner node, an inner-marked leaf photon.
    std::vector<Photon> photons = random_photons(2, 1);
    const Photon leaf_flagged = photons[0];  // make_photon marks photons as leaves (axis 3)
    std::vector<Photon> bad_inner = order;
    std::memcpy(&bad_inner[root], &leaf_flagged, sizeof(Photon));
    bad_inner[root].position = order[root].position;
    result = PhotonKdTree::from_tree_order(bad_inner);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("inner node " + std::to_string(root)), std::string::npos)
        << result.error().message;

    std::vector<Photon> bad_leaf = order;
    bad_leaf[0] = order[root];  // carries an inner node's split axis
    result = PhotonKdTree::from_tree_order(bad_leaf);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("leaf photon 0"), std::string::npos)
        << result.error().message;
}

// ---- The format -------------------------------------------------------------------------------

TEST(PhotonMapIo, RoundTripIsExact) {
    const PhotonMaps& maps = cornell_maps();
    ASSERT_TRUE(maps.global && maps.caustic);
    ASSERT_GT(maps.caustic->size(), 1000u);
    const std::vector<uint8_t>& bytes = cornell_bytes();
    EXPECT_EQ(read_photon_map_key(bytes), kKey);

    Expected<PhotonMaps> loaded = deserialize_photon_maps(bytes, kKey);
    ASSERT_TRUE(loaded) << loaded.error().message;
    ASSERT_TRUE(loaded->global && loaded->caustic);
    EXPECT_TRUE(same_photons(loaded->global->tree().photons(), maps.global->tree().photons()));
    EXPECT_TRUE(same_photons(loaded->caustic->tree().photons(), maps.caustic->tree().photons()));
    EXPECT_EQ(loaded->global->emitted(), maps.global->emitted());
    EXPECT_EQ(loaded->caustic->emitted(), maps.caustic->emitted());
    ASSERT_TRUE(maps.irradiance && loaded->irradiance);
    EXPECT_TRUE(
        same_photons(loaded->irradiance->tree().photons(), maps.irradiance->tree().photons()));
    EXPECT_EQ(loaded->irradiance->emitted(), maps.irradiance->emitted());
    ASSERT_TRUE(maps.caustic_irradiance && loaded->caustic_irradiance);
    EXPECT_TRUE(same_photons(loaded->caustic_irradiance->tree().photons(),
                             maps.caustic_irradiance->tree().photons()));
    const PhotonTracingStatistics &a = loaded->statistics, &b = maps.statistics;
    EXPECT_TRUE(b.caustic_tested);
    EXPECT_GT(b.caustic_peak_ratio, kInvisibleCausticRatio);
    EXPECT_EQ(a.caustic_tested, b.caustic_tested);
    EXPECT_EQ(a.caustic_peak_ratio, b.caustic_peak_ratio);
    EXPECT_EQ(a.caustic_dropped, b.caustic_dropped);
    EXPECT_EQ(a.emitted, b.emitted);
    EXPECT_EQ(a.emitted_global, b.emitted_global);
    EXPECT_EQ(a.emitted_caustic, b.emitted_caustic);
    EXPECT_EQ(a.stored_global, b.stored_global);
    EXPECT_EQ(a.stored_caustic, b.stored_caustic);
    EXPECT_EQ(a.emitted_volume, b.emitted_volume);
    EXPECT_EQ(a.stored_volume, b.stored_volume);
    EXPECT_EQ(a.volume_complete, b.volume_complete);
    EXPECT_EQ(a.rays, b.rays);
    EXPECT_EQ(a.tracing_seconds, b.tracing_seconds);
    EXPECT_EQ(a.build_seconds, b.build_seconds);
    EXPECT_EQ(a.irradiance_seconds, b.irradiance_seconds);
    EXPECT_EQ(a.irradiance_photons, b.irradiance_photons);
    EXPECT_EQ(a.global_complete, b.global_complete);
    EXPECT_EQ(a.caustic_complete, b.caustic_complete);
    // Serialising the loaded maps gives the same bytes.
    EXPECT_EQ(serialize_photon_maps(*loaded, kKey).value(), bytes);

    expect_same_queries(maps.global->tree(), loaded->global->tree(), maps.global->tree().bounds());
    expect_same_queries(maps.caustic->tree(), loaded->caustic->tree(),
                        maps.caustic->tree().bounds());
    expect_same_queries(maps.irradiance->tree(), loaded->irradiance->tree(),
                        maps.irradiance->tree().bounds());
    Rng rng(4, 4);
    for (int i = 0; i < 200; ++i) {
        const Vec3 p(rng.next_float() * 5.5f - 2.75f, 0.0f, rng.next_float() * 5.5f - 2.75f);
        const Vec3 up(0.0f, 1.0f, 0.0f);
        EXPECT_EQ(loaded->global->estimate_irradiance(p, up, 50, 0.0f),
                  maps.global->estimate_irradiance(p, up, 50, 0.0f));
    }
}

TEST(PhotonMapIo, AbsentAndEmptyMapsRoundTrip) {
    PhotonMaps maps;
    maps.global = cornell_maps().global;
    maps.statistics.rays = 42;
    maps.statistics.caustic_complete = false;
    Expected<PhotonMaps> loaded =
        deserialize_photon_maps(serialize_photon_maps(maps, "k").value(), "k");
    ASSERT_TRUE(loaded) << loaded.error().message;
    EXPECT_TRUE(loaded->global);
    EXPECT_FALSE(loaded->caustic);
    EXPECT_FALSE(loaded->irradiance);
    EXPECT_EQ(loaded->statistics.rays, 42u);
    EXPECT_FALSE(loaded->statistics.caustic_complete);

    PhotonMaps empty;
    empty.caustic = std::make_shared<const PhotonMap>(std::vector<Photon>(), 5);
    loaded = deserialize_photon_maps(serialize_photon_maps(empty, "").value(), "");
    ASSERT_TRUE(loaded) << loaded.error().message;
    EXPECT_FALSE(loaded->global);
    ASSERT_TRUE(loaded->caustic);
    EXPECT_TRUE(loaded->caustic->empty());
    EXPECT_EQ(loaded->caustic->emitted(), 5u);

    EXPECT_FALSE(serialize_photon_maps(maps, std::string(kMaxPhotonMapKey + 1, 'k')));
}

TEST(PhotonMapIo, EveryFlippedByteIsRefused) {
    const std::vector<uint8_t>& original = cornell_bytes();
    std::vector<size_t> positions;
    for (size_t i = 0; i < 160; ++i) positions.push_back(i);  // the header and the map headers
    Rng rng(21, 0);
    for (int i = 0; i < 40; ++i) positions.push_back(rng.next_u32() % original.size());
    for (size_t i = original.size() - 32; i < original.size(); ++i) positions.push_back(i);
    photond::test::expect_every_flip_refused(original, positions, [](std::span<const uint8_t> bytes) {
        return deserialize_photon_maps(bytes, kKey);
    });
}

TEST(PhotonMapIo, EveryTruncationIsRefused) {
    const std::vector<uint8_t>& original = cornell_bytes();
    photond::test::expect_every_truncation_refused(original, 4099, [](std::span<const uint8_t> bytes) {
        return deserialize_photon_maps(bytes, kKey);
    });
}

TEST(PhotonMapIo, ForeignDataIsRefused) {
    std::vector<uint8_t> random(100000);
    Rng rng(3, 3);
    for (uint8_t& b : random) b = uint8_t(rng.next_u32());
    // An OpenEXR file's start: magic 76 2f 31 01, version 2, then the header attributes.
    const std::vector<uint8_t> exr = {0x76, 0x2f, 0x31, 0x01, 0x02, 0x00, 0x00, 0x00, 'c', 'h',
                                      'a',  'n',  'n',  'e',  'l',  's',  0x00, 'c',  'h', 'l',
                                      'i',  's',  't',  0x00, 0x37, 0x00, 0x00, 0x00};
    for (const std::vector<uint8_t>& foreign : {random, exr, std::vector<uint8_t>()}) {
        Expected<PhotonMaps> result = deserialize_photon_maps(foreign, "");
        ASSERT_FALSE(result);
        EXPECT_NE(result.error().message.find("not a photon-map file"), std::string::npos)
            << result.error().message;
        EXPECT_EQ(read_photon_map_key(foreign), "");
    }
    // A photon-map magic followed by garbage.
    std::vector<uint8_t> magic_then_garbage(cornell_bytes().begin(), cornell_bytes().begin() + 8);
    magic_then_garbage.insert(magic_then_garbage.end(), random.begin(), random.end());
    EXPECT_FALSE(deserialize_photon_maps(magic_then_garbage, ""));
    EXPECT_EQ(read_photon_map_key(magic_then_garbage), "");
}

TEST(PhotonMapIo, OtherVersionsAndPhotonSizesAreRefused) {
    // Version 1 stored 20-byte photons without a normal; version 2 had no caustic visibility
    // test and no precomputed caustic irradiance; version 3 no volume map.
    for (uint32_t version : {0u, 1u, 2u, 3u, 5u, 1000u}) {
        std::vector<uint8_t> bytes = cornell_bytes();
        for (int i = 0; i < 4; ++i) bytes[8 + i] = uint8_t(version >> (8 * i));
        reseal(bytes);  // a well-formed file of that version
        Expected<PhotonMaps> result = deserialize_photon_maps(bytes, kKey);
        ASSERT_FALSE(result);
        EXPECT_EQ(result.error().message, "unsupported photon-map format version " +
                                              std::to_string(version) + " (this build reads 4)");
        EXPECT_EQ(read_photon_map_key(bytes), "");
    }
    std::vector<uint8_t> bytes = cornell_bytes();
    bytes[16] = 20;  // photon size: version 1's
    reseal(bytes);
    Expected<PhotonMaps> result = deserialize_photon_maps(bytes, kKey);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("20-byte photons"), std::string::npos);
}

TEST(PhotonMapIo, KeysMustMatchUnlessImporting) {
    const std::vector<uint8_t>& bytes = cornell_bytes();
    Expected<PhotonMaps> result = deserialize_photon_maps(bytes, "pm1-other");
    ASSERT_FALSE(result);
    EXPECT_EQ(result.error().message, "photon map is for key " + kKey + ", expected pm1-other");
    EXPECT_TRUE(deserialize_photon_maps(bytes, ""));  // an import takes any key
    EXPECT_TRUE(deserialize_photon_maps(bytes, kKey));
}

TEST(PhotonMapIo, AResealedBrokenTreeIsRefused) {
    // The checksum is not a signature: a rewritten file with a valid checksum but an unsorted
    // tree still reaches the kd-tree checks and is refused.
    std::vector<uint8_t> bytes = cornell_bytes();
    // Header and key, the statistics (10 u64, 3 flags, 1 u64, 1 flag, 2 u64, 1 flag), the global
    // map's present flag, emitted and count.
    const size_t photons_start = 24 + kKey.size() + 82 + 10 + 17 + 17;
    const PhotonKdTree& tree = cornell_maps().global->tree();
    const uint32_t root = tree.size() / 2;
    const uint32_t axis = tree.photon(root).split_axis();
    // Moves the first photon (in the left subtree) far beyond the root's split.
    Vec3 position = tree.photon(0).position;
    position[axis] = tree.bounds().upper[axis] + 1.0f;
    std::memcpy(bytes.data() + photons_start, &position, sizeof(position));
    reseal(bytes);
    Expected<PhotonMaps> result = deserialize_photon_maps(bytes, kKey);
    ASSERT_FALSE(result);
    EXPECT_NE(result.error().message.find("global map: photon kd-tree"), std::string::npos)
        << result.error().message;
}

// ---- Files ------------------------------------------------------------------------------------

class PhotonMapFileTest : public photond::test::ScratchDirectoryTest {};

TEST_F(PhotonMapFileTest, WritesAndReadsBack) {
    const std::filesystem::path path = directory_ / "maps.pm";
    ASSERT_TRUE(write_photon_maps_file(path, cornell_maps(), kKey));
    EXPECT_EQ(files_in_directory(), 1u);  // no temporary left behind
    Expected<PhotonMaps> loaded = read_photon_maps_file(path, kKey);
    ASSERT_TRUE(loaded) << loaded.error().message;
    EXPECT_EQ(serialize_photon_maps(*loaded, kKey).value(), cornell_bytes());

    // Overwriting replaces the file.
    PhotonMaps only_global;
    only_global.global = cornell_maps().global;
    ASSERT_TRUE(write_photon_maps_file(path, only_global, "pm1-second"));
    loaded = read_photon_maps_file(path, "pm1-second");
    ASSERT_TRUE(loaded) << loaded.error().message;
    EXPECT_FALSE(loaded->caustic);
    EXPECT_EQ(files_in_directory(), 1u);

    // Errors name the path.
    Expected<PhotonMaps> missing = read_photon_maps_file(directory_ / "missing.pm", "");
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().message.find("missing.pm"), std::string::npos);
    Status no_directory = write_photon_maps_file(directory_ / "no" / "maps.pm", only_global, "");
    ASSERT_FALSE(no_directory);
    EXPECT_NE(no_directory.error().message.find("maps.pm"), std::string::npos);
    Expected<PhotonMaps> directory = read_photon_maps_file(directory_, "");
    EXPECT_FALSE(directory);

    const std::filesystem::path empty = directory_ / "empty.pm";
    std::ofstream(empty).close();
    Expected<PhotonMaps> from_empty = read_photon_maps_file(empty, "");
    ASSERT_FALSE(from_empty);
    EXPECT_NE(from_empty.error().message.find("empty.pm: not a photon-map file"), std::string::npos)
        << from_empty.error().message;
}

TEST_F(PhotonMapFileTest, ConcurrentWritersNeverExposeAPartialFile) {
    const std::filesystem::path path = directory_ / "shared.pm";
    // Two versions with the same key, told apart by their statistics.
    PhotonMaps first = cornell_maps(), second = cornell_maps();
    second.statistics.rays += 1;
    const std::vector<uint8_t> first_bytes = serialize_photon_maps(first, kKey).value();
    const std::vector<uint8_t> second_bytes = serialize_photon_maps(second, kKey).value();
    ASSERT_TRUE(write_photon_maps_file(path, first, kKey));

    std::atomic<int> writers_running{4};
    std::atomic<int> write_failures{0}, read_failures{0}, reads{0}, mismatches{0};
    std::string first_error;
    std::mutex error_mutex;
    std::vector<std::thread> threads;
    for (int w = 0; w < 4; ++w) {
        threads.emplace_back([&, w] {
            for (int i = 0; i < 25; ++i) {
                Status s = write_photon_maps_file(path, (i + w) % 2 ? first : second, kKey);
                if (!s) {
                    ++write_failures;
                    std::lock_guard lock(error_mutex);
                    if (first_error.empty()) first_error = s.error().message;
                }
            }
            --writers_running;
        });
    }
    for (int r = 0; r < 4; ++r) {
        threads.emplace_back([&] {
            do {
                Expected<PhotonMaps> maps = read_photon_maps_file(path, kKey);
                ++reads;
                if (!maps) {
                    ++read_failures;
                    std::lock_guard lock(error_mutex);
                    if (first_error.empty()) first_error = maps.error().message;
                    continue;
                }
                const std::vector<uint8_t> again = serialize_photon_maps(*maps, kKey).value();
                if (again != first_bytes && again != second_bytes) ++mismatches;
            } while (writers_running > 0);
        });
    }
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(write_failures, 0) << first_error;
    EXPECT_EQ(read_failures, 0) << first_error;
    EXPECT_EQ(mismatches, 0);
    EXPECT_GE(reads, 4);
    EXPECT_EQ(files_in_directory(), 1u);  // every temporary was renamed into place
}

}  // namespace
}  // namespace photond
