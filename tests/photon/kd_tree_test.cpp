// The photon kd-tree: k-nearest and radius queries equal a brute-force search (same photons,
// same distances, ties by index) on random, coincident, collinear and grid points; the tree does
// not depend on the thread count; degenerate inputs.
#include "core/photon/kd_tree.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <limits>
#include <tuple>
#include <vector>

#include "core/math/rng.h"
#include "core/math/sampling.h"

namespace photond {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::vector<Photon> photons_at(const std::vector<Vec3>& positions) {
    std::vector<Photon> photons;
    photons.reserve(positions.size());
    for (const Vec3& p : positions) photons.push_back(make_photon(p, Vec3(0, 0, -1), Color(1)));
    return photons;
}

std::vector<Vec3> random_points(uint32_t n, uint64_t seed) {
    Rng rng(seed, 1);
    std::vector<Vec3> points(n);
    for (Vec3& p : points) p = Vec3(rng.next_float(), rng.next_float(), rng.next_float());
    return points;
}

bool closer(const KnnNeighbor& a, const KnnNeighbor& b) {
    return a.dist2 < b.dist2 || (a.dist2 == b.dist2 && a.index < b.index);
}

// The k nearest by (dist2, index) within max_radius, over the tree's photons.
std::vector<KnnNeighbor> brute_force_knn(const PhotonKdTree& tree, const Vec3& p, uint32_t k,
                                         float max_radius) {
    std::vector<KnnNeighbor> all;
    const float r2 = max_radius * max_radius;
    for (uint32_t i = 0; i < tree.size(); ++i) {
        const float d2 = PhotonKdTree::distance2(p, tree.photon(i).position);
        if (d2 <= r2) all.push_back({i, d2});
    }
    std::sort(all.begin(), all.end(), closer);
    if (all.size() > k) all.resize(k);
    return all;
}

// Checks k_nearest against brute force; returns the number of neighbours found.
size_t expect_knn_matches(const PhotonKdTree& tree, const Vec3& p, uint32_t k, float max_radius,
                          KnnResult& result) {
    tree.k_nearest(p, k, max_radius, result);
    const std::vector<KnnNeighbor> expected = brute_force_knn(tree, p, k, max_radius);
    float farthest = 0.0f;
    for (const KnnNeighbor& n : result.neighbors) farthest = std::max(farthest, n.dist2);
    EXPECT_EQ(result.radius2, farthest);
    result.sort_by_distance();
    EXPECT_EQ(result.size(), expected.size()) << "at " << p.x << " " << p.y << " " << p.z;
    for (size_t i = 0; i < std::min(result.size(), expected.size()); ++i) {
        EXPECT_EQ(result.neighbors[i].index, expected[i].index) << "neighbour " << i;
        EXPECT_EQ(result.neighbors[i].dist2, expected[i].dist2) << "neighbour " << i;
    }
    return result.size();
}

void expect_radius_matches(const PhotonKdTree& tree, const Vec3& p, float radius) {
    std::vector<KnnNeighbor> found;
    tree.for_each_in_radius(p, radius, [&](uint32_t i, float d2) { found.push_back({i, d2}); });
    std::sort(found.begin(), found.end(), closer);
    const std::vector<KnnNeighbor> expected = brute_force_knn(tree, p, tree.size(), radius);
    ASSERT_EQ(found.size(), expected.size());
    for (size_t i = 0; i < found.size(); ++i) {
        EXPECT_EQ(found[i].index, expected[i].index);
        EXPECT_EQ(found[i].dist2, expected[i].dist2);
    }
}

TEST(PhotonKdTree, RandomPointsMatchBruteForce) {
    const PhotonKdTree tree(photons_at(random_points(100000, 1)));
    ASSERT_EQ(tree.size(), 100000u);
    Rng rng(2, 3);
    KnnResult result;
    size_t full = 0, total = 0;
    for (int q = 0; q < 300; ++q) {
        // Queries inside and slightly outside the box.
        const Vec3 p(1.2f * rng.next_float() - 0.1f, 1.2f * rng.next_float() - 0.1f,
                     1.2f * rng.next_float() - 0.1f);
        const uint32_t k = 1 + rng.next_u32() % 100;
        const float max_radius = q % 3 == 0 ? kInf : 0.1f * rng.next_float();
        const size_t found = expect_knn_matches(tree, p, k, max_radius, result);
        full += found == k;
        total += found;
        if (q % 10 == 0) expect_radius_matches(tree, p, 0.05f * rng.next_float());
        if (HasFailure()) return;
    }
    // Both regimes were exercised: heaps filled up and searches cut by max_radius.
    EXPECT_GT(full, 150u);
    EXPECT_LT(full, 300u);
    EXPECT_GT(total, 0u);
}

TEST(PhotonKdTree, DiscQueriesMatchBruteForce) {
    // k_nearest_in_disc: the same search with the flattened distance, against brute force.
    const PhotonKdTree tree(photons_at(random_points(50000, 21)));
    Rng rng(22, 23);
    KnnResult result;
    size_t full = 0;
    for (int q = 0; q < 200; ++q) {
        const Vec3 p(rng.next_float(), rng.next_float(), rng.next_float());
        const Vec3 n = sample_uniform_sphere(rng.next_vec2());
        const float flattening = q % 4 == 0 ? 1.0f : 1.0f + 9.0f * rng.next_float();
        const uint32_t k = 1 + rng.next_u32() % 100;
        const float max_radius = q % 3 == 0 ? kInf : 0.15f * rng.next_float();
        tree.k_nearest_in_disc(p, n, flattening, k, max_radius, result);
        const float stretch2 = flattening * flattening - 1.0f;
        std::vector<KnnNeighbor> expected;
        for (uint32_t i = 0; i < tree.size(); ++i) {
            const float d2 = PhotonKdTree::disc_distance2(p, tree.photon(i).position, n, stretch2);
            if (d2 <= max_radius * max_radius) expected.push_back({i, d2});
        }
        std::sort(expected.begin(), expected.end(), closer);
        if (expected.size() > k) expected.resize(k);
        result.sort_by_distance();
        ASSERT_EQ(result.size(), expected.size()) << q;
        for (size_t i = 0; i < expected.size(); ++i) {
            ASSERT_EQ(result.neighbors[i].index, expected[i].index) << q << " neighbour " << i;
            ASSERT_EQ(result.neighbors[i].dist2, expected[i].dist2) << q << " neighbour " << i;
        }
        full += result.size() == k;
    }
    EXPECT_GT(full, 100u);
    EXPECT_LT(full, 200u);

    // Photons on two parallel planes 0.1 apart: a sphere of radius 0.2 reads both, a disc
    // flattened 5 times (its half-thickness 0.04) only the query's own plane.
    std::vector<Vec3> planes;
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 40; ++j)
            for (const float y : {0.0f, 0.1f}) planes.push_back(Vec3(0.025f * i, y, 0.025f * j));
    const PhotonKdTree layered(photons_at(planes));
    const Vec3 p(0.5f, 0.0f, 0.5f), up(0.0f, 1.0f, 0.0f);
    layered.k_nearest(p, 1000, 0.2f, result);
    const auto count_above = [&] {
        size_t count = 0;
        for (const KnnNeighbor& n : result.neighbors)
            count += layered.photon(n.index).position.y > 0.0f;
        return count;
    };
    const size_t above = count_above();
    EXPECT_GT(above, 50u);
    layered.k_nearest_in_disc(p, up, 5.0f, 1000, 0.2f, result);
    EXPECT_GT(result.size(), 150u);
    EXPECT_EQ(count_above(), 0u);
    // A flattening of 1 is the sphere; a non-finite normal finds nothing.
    layered.k_nearest_in_disc(p, up, 1.0f, 1000, 0.2f, result);
    EXPECT_EQ(count_above(), above);
    layered.k_nearest_in_disc(p, Vec3(kNaN, 1.0f, 0.0f), 5.0f, 10, kInf, result);
    EXPECT_TRUE(result.empty());
}

TEST(PhotonKdTree, QueriesOnThePhotonsThemselves) {
    const PhotonKdTree tree(photons_at(random_points(20000, 9)));
    KnnResult result;
    for (uint32_t i = 0; i < tree.size(); i += 97) {
        const Vec3 p = tree.photon(i).position;
        expect_knn_matches(tree, p, 10, kInf, result);
        EXPECT_EQ(result.neighbors[0].index, i);
        EXPECT_EQ(result.neighbors[0].dist2, 0.0f);
    }
}

TEST(PhotonKdTree, MaxRadiusCutsTheSearch) {
    const PhotonKdTree tree(photons_at(random_points(50000, 4)));
    KnnResult result;
    const Vec3 center(0.5f);
    for (float radius : {0.0f, 0.001f, 0.01f, 0.02f, 0.05f}) {
        expect_knn_matches(tree, center, 1000, radius, result);
        EXPECT_LT(result.size(), 1000u);
        for (const KnnNeighbor& n : result.neighbors) EXPECT_LE(n.dist2, radius * radius);
    }
    // Far away from every photon: nothing within the radius.
    tree.k_nearest(Vec3(10.0f), 50, 1.0f, result);
    EXPECT_TRUE(result.empty());
    EXPECT_EQ(result.radius2, 0.0f);
    // Without a limit, the farthest corner still finds k.
    expect_knn_matches(tree, Vec3(10.0f), 50, kInf, result);
    EXPECT_EQ(result.size(), 50u);
}

TEST(PhotonKdTree, KLargerThanSize) {
    const PhotonKdTree tree(photons_at(random_points(37, 5)));
    KnnResult result;
    EXPECT_EQ(expect_knn_matches(tree, Vec3(0.3f), 1000, kInf, result), 37u);
    EXPECT_EQ(expect_knn_matches(tree, Vec3(0.3f), 37, kInf, result), 37u);
    EXPECT_EQ(expect_knn_matches(tree, Vec3(0.3f), 36, kInf, result), 36u);
    tree.k_nearest(Vec3(0.3f), 0, kInf, result);
    EXPECT_TRUE(result.empty());
}

TEST(PhotonKdTree, AllCoincident) {
    const std::vector<Vec3> points(5000, Vec3(1.0f, 2.0f, 3.0f));
    const PhotonKdTree tree(photons_at(points));
    KnnResult result;
    // At the point: distance 0, radius 0; ties broken by index: the k smallest indices.
    EXPECT_EQ(expect_knn_matches(tree, Vec3(1, 2, 3), 50, kInf, result), 50u);
    EXPECT_EQ(result.radius2, 0.0f);
    for (uint32_t i = 0; i < 50; ++i) EXPECT_EQ(result.neighbors[i].index, i);
    EXPECT_EQ(expect_knn_matches(tree, Vec3(1, 2, 3), 50, 0.0f, result), 50u);
    expect_knn_matches(tree, Vec3(1.5f, 2.0f, 3.0f), 50, kInf, result);
    EXPECT_EQ(result.radius2, 0.25f);
    expect_radius_matches(tree, Vec3(1, 2, 3), 0.0f);
    expect_radius_matches(tree, Vec3(1.5f, 2.0f, 3.0f), 0.4f);
    EXPECT_EQ(tree.bounds().lower, Vec3(1, 2, 3));
    EXPECT_EQ(tree.bounds().upper, Vec3(1, 2, 3));
}

TEST(PhotonKdTree, AllOnALine) {
    std::vector<Vec3> points;
    Rng rng(6, 7);
    const Vec3 direction = glm::normalize(Vec3(1, 2, -0.5f));
    for (int i = 0; i < 20000; ++i) {
        // Repeated parameters too: equal positions on the line.
        const float t = float(rng.next_u32() % 5000) * 0.01f;
        points.push_back(Vec3(0.5f, -1.0f, 2.0f) + t * direction);
    }
    const PhotonKdTree tree(photons_at(points));
    KnnResult result;
    for (int q = 0; q < 100; ++q) {
        const float t = 60.0f * rng.next_float() - 5.0f;
        const Vec3 off_line(rng.next_float() * 0.1f, 0.0f, 0.0f);
        const Vec3 p = Vec3(0.5f, -1.0f, 2.0f) + t * direction + (q % 2 ? off_line : Vec3(0));
        expect_knn_matches(tree, p, 1 + q % 60, q % 4 ? kInf : 0.3f, result);
        if (q % 5 == 0) expect_radius_matches(tree, p, 0.2f);
        if (HasFailure()) return;
    }
}

// Ranges of at least 2^16 photons are split around pivots from a sample before the median is
// selected (kd_tree.cpp): large inputs with runs of equal coordinates, a plane, a sorted order
// and samples that miss the median, checked by the adopting validator (every split separates
// its subtrees) and queries.
TEST(PhotonKdTree, LargeRangesWithEqualCoordinatesSplitAtTheirMedian) {
    Rng rng(21, 22);
    std::vector<std::vector<Vec3>> inputs(5);
    // The pivot sample (every 146th photon of 150,000) all at one end: the median then lies
    // above or below both pivots, and is selected in the part beyond them.
    for (int i = 0; i < 150000; ++i) {
        const bool sampled = i % (150000 / 1023) == 0 && i / (150000 / 1023) < 1023;
        const float spread = float(i % 1000) * 1e-3f;
        inputs[3].push_back(Vec3(sampled ? 0.0f : 1.0f + spread, 0.0f, 0.0f));
        inputs[4].push_back(Vec3(sampled ? 3.0f : spread, 0.0f, 0.0f));
    }
    for (int i = 0; i < 150000; ++i) {
        // Coordinates from 7 values on x: whole ranges of equal ones around every pivot.
        inputs[0].push_back(Vec3(float(rng.next_u32() % 7), rng.next_float(), float(rng.next_u32() % 3)));
        inputs[1].push_back(Vec3(rng.next_float(), 0.25f, rng.next_float()));  // a plane: y all equal
        inputs[2].push_back(Vec3(float(i) * 1e-5f, 0.5f * rng.next_float(), 0.0f));  // sorted along x
    }
    for (const std::vector<Vec3>& points : inputs) {
        const PhotonKdTree tree(photons_at(points));
        ASSERT_EQ(tree.size(), points.size());
        const std::vector<Photon> order(tree.photons().begin(), tree.photons().end());
        const Expected<PhotonKdTree> adopted = PhotonKdTree::from_tree_order(order);
        ASSERT_TRUE(adopted.has_value()) << adopted.error().message;
        KnnResult result;
        for (int q = 0; q < 40; ++q) {
            const Vec3 p = points[rng.next_u32() % points.size()] + Vec3(0.01f * rng.next_float(), 0.0f, 0.0f);
            expect_knn_matches(tree, p, 1 + q % 50, kInf, result);
            if (HasFailure()) return;
        }
    }
}

TEST(PhotonKdTree, GridWithManyEqualDistances) {
    std::vector<Vec3> points;
    for (int y = 0; y < 150; ++y) {
        for (int x = 0; x < 150; ++x) points.push_back(Vec3(float(x), float(y), 0.0f));
    }
    const PhotonKdTree tree(photons_at(points));
    KnnResult result;
    Rng rng(8, 9);
    for (int q = 0; q < 200; ++q) {
        // On grid points and at cell centres: many photons at exactly the same distance.
        const float offset = q % 2 ? 0.5f : 0.0f;
        const Vec3 p(float(rng.next_u32() % 150) + offset, float(rng.next_u32() % 150) + offset,
                     q % 3 == 0 ? 1.0f : 0.0f);
        const uint32_t k = 1 + rng.next_u32() % 60;
        expect_knn_matches(tree, p, k, q % 4 ? kInf : 2.0f, result);
        if (q % 10 == 0) expect_radius_matches(tree, p, 3.0f);
        if (HasFailure()) return;
    }
}

TEST(PhotonKdTree, EmptyTreeAndInvalidQueries) {
    KnnResult result;
    result.neighbors.push_back({7, 1.0f});
    result.radius2 = 1.0f;
    const PhotonKdTree empty;
    empty.k_nearest(Vec3(0), 10, kInf, result);
    EXPECT_TRUE(result.empty());
    EXPECT_EQ(result.radius2, 0.0f);
    EXPECT_TRUE(empty.bounds().empty());
    EXPECT_EQ(PhotonKdTree(std::vector<Photon>{}).size(), 0u);

    const PhotonKdTree tree(photons_at(random_points(1000, 10)));
    int calls = 0;
    for (const Vec3& bad : {Vec3(kNaN, 0, 0), Vec3(0, kNaN, 0), Vec3(0, 0, kInf)}) {
        tree.k_nearest(bad, 10, kInf, result);
        EXPECT_TRUE(result.empty());
        tree.for_each_in_radius(bad, kInf, [&](uint32_t, float) { ++calls; });
    }
    tree.k_nearest(Vec3(0.5f), 10, kNaN, result);
    EXPECT_TRUE(result.empty());
    tree.k_nearest(Vec3(0.5f), 10, -1.0f, result);
    EXPECT_TRUE(result.empty());
    tree.for_each_in_radius(Vec3(0.5f), kNaN, [&](uint32_t, float) { ++calls; });
    tree.for_each_in_radius(Vec3(0.5f), -1.0f, [&](uint32_t, float) { ++calls; });
    EXPECT_EQ(calls, 0);
    // An infinite radius visits everything.
    tree.for_each_in_radius(Vec3(0.5f), kInf, [&](uint32_t, float) { ++calls; });
    EXPECT_EQ(calls, 1000);
}

TEST(PhotonKdTree, NonFinitePhotonsAreDropped) {
    std::vector<Vec3> points = random_points(100, 11);
    points[3] = Vec3(kNaN, 0, 0);
    points[50] = Vec3(0, kInf, 0);
    const PhotonKdTree tree(photons_at(points));
    EXPECT_EQ(tree.size(), 98u);
    for (uint32_t i = 0; i < tree.size(); ++i) EXPECT_TRUE(is_finite(tree.photon(i).position));
    EXPECT_TRUE(is_finite(tree.bounds().lower) && is_finite(tree.bounds().upper));
    KnnResult result;
    expect_knn_matches(tree, Vec3(0.5f), 20, kInf, result);
}

TEST(PhotonKdTree, KeepsPhotonDataAndReportsMemory) {
    std::vector<Photon> photons;
    Rng rng(12, 13);
    for (int i = 0; i < 5000; ++i) {
        const Vec3 p(rng.next_float(), rng.next_float(), rng.next_float());
        // The flux and flags encode the position, to check they travel with it.
        photons.push_back(make_photon(p, sample_uniform_sphere(rng.next_vec2()), Color(p.x + 1),
                                      uint8_t(i % 64)));
    }
    std::vector<Photon> sorted_input = photons;
    const PhotonKdTree tree(std::move(photons));
    EXPECT_EQ(tree.bytes(), 5000u * sizeof(Photon));
    Bounds3 bounds;
    for (const Photon& p : sorted_input) bounds.extend(p.position);
    EXPECT_EQ(tree.bounds().lower, bounds.lower);
    EXPECT_EQ(tree.bounds().upper, bounds.upper);

    // Same multiset of photons (ignoring the split axis bits) in a new order.
    const auto key = [](const Photon& p) {
        return std::tuple(p.position.x, p.position.y, p.position.z, p.flux_mantissas(),
                          p.flux_exponent(), p.theta_bin(), p.phi_bin(), p.user_flags());
    };
    std::vector<decltype(key(sorted_input[0]))> in, out;
    for (const Photon& p : sorted_input) in.push_back(key(p));
    for (const Photon& p : tree.photons()) out.push_back(key(p));
    std::sort(in.begin(), in.end());
    std::sort(out.begin(), out.end());
    EXPECT_EQ(in, out);
}

std::vector<Photon> build_with_threads(const std::vector<Photon>& photons, int threads) {
    tbb::task_arena arena(threads);
    std::vector<Photon> result;
    arena.execute([&] {
        const PhotonKdTree tree(photons);
        result.assign(tree.photons().begin(), tree.photons().end());
    });
    return result;
}

TEST(PhotonKdTree, SameTreeForAnyThreadCount) {
    // Many duplicate coordinates: equal ones must land alike at every thread count.
    std::vector<Vec3> points = random_points(300000, 14);
    for (size_t i = 0; i < points.size(); i += 3) points[i].x = std::floor(points[i].x * 16.0f);
    for (size_t i = 0; i < points.size(); i += 7) points[i] = points[i / 2];
    std::vector<Photon> photons = photons_at(points);
    const std::vector<Photon> one = build_with_threads(photons, 1);
    const std::vector<Photon> two = build_with_threads(photons, 2);
    ASSERT_EQ(one.size(), points.size());
    ASSERT_EQ(two.size(), one.size());
    EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(Photon)), 0);
    // The tree is not just the input order.
    EXPECT_NE(std::memcmp(one.data(), photons.data(), one.size() * sizeof(Photon)), 0);
}

TEST(PhotonKdTree, ConcurrentQueriesAgree) {
    const PhotonKdTree tree(photons_at(random_points(100000, 15)));
    const std::vector<Vec3> queries = random_points(2000, 16);
    std::vector<std::vector<KnnNeighbor>> serial(queries.size());
    KnnResult result;
    for (size_t q = 0; q < queries.size(); ++q) {
        tree.k_nearest(queries[q], 50, 0.1f, result);
        serial[q] = result.neighbors;
    }
    std::atomic<int> mismatches{0};
    tbb::parallel_for(size_t(0), queries.size(), [&](size_t q) {
        thread_local KnnResult local;
        tree.k_nearest(queries[q], 50, 0.1f, local);
        if (local.neighbors.size() != serial[q].size() ||
            !std::equal(local.neighbors.begin(), local.neighbors.end(), serial[q].begin(),
                        [](const KnnNeighbor& a, const KnnNeighbor& b) {
                            return a.index == b.index && a.dist2 == b.dist2;
                        })) {
            ++mismatches;
        }
    });
    EXPECT_EQ(mismatches.load(), 0);
}

TEST(PhotonKdTree, ResultBufferIsReused) {
    const PhotonKdTree tree(photons_at(random_points(10000, 17)));
    KnnResult result;
    tree.k_nearest(Vec3(0.5f), 50, kInf, result);
    const KnnNeighbor* buffer = result.neighbors.data();
    for (const Vec3& p : random_points(100, 18)) {
        tree.k_nearest(p, 50, kInf, result);
        ASSERT_EQ(result.size(), 50u);
        ASSERT_EQ(result.neighbors.data(), buffer);
    }
}

}  // namespace
}  // namespace photond
