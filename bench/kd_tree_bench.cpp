// Photon kd-tree: build time of 1M photons with 1 and 2 threads and k = 50 query time, for
// PhotonKdTree (median split, implicit in-order layout with leaf buckets) and, as the reference
// it must beat, Jensen's left-balanced heap ("Realistic Image Synthesis Using Photon Mapping",
// 2001, appendix B) built and queried the same way. Prints bytes per photon.
#include <benchmark/benchmark.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/math/rng.h"
#include "core/photon/kd_tree.h"

namespace photond {
namespace {

constexpr uint32_t kPhotonCount = 1u << 20;
constexpr uint32_t kQueryCount = 1u << 14;
constexpr uint32_t kK = 50;
constexpr float kMaxRadius = 0.05f;  // in a unit box; the 50th photon is nearer on average

/// The search radius for k photons: kMaxRadius grown as the k-th photon's distance grows on the
/// Cornell planes (sqrt k; faster than in the box's volume, cbrt k).
float max_radius_for(uint32_t k) { return kMaxRadius * std::sqrt(float(k) / float(kK)); }

// Scene 0: uniform in the unit box. Scene 1: a Cornell box, photons on five walls of the unit
// cube (floor, ceiling, back, left, right), as a global photon map stores them.
Vec3 scene_point(int scene, Rng& rng) {
    const float u = rng.next_float(), v = rng.next_float();
    if (scene == 0) return {u, v, rng.next_float()};
    switch (rng.next_u32() % 5) {
        case 0:
            return {u, 0.0f, v};
        case 1:
            return {u, 1.0f, v};
        case 2:
            return {u, v, 0.0f};
        case 3:
            return {0.0f, u, v};
        default:
            return {1.0f, u, v};
    }
}

struct Data {
    std::vector<Photon> photons;
    std::vector<Vec3> queries;  // where lookups happen: points of the same distribution

    static const Data& get(int scene) {
        static const Data data[2] = {make(0), make(1)};
        return data[scene];
    }
    static Data make(int scene) {
        Data d;
        Rng rng(2024, uint64_t(scene));
        for (uint32_t i = 0; i < kPhotonCount; ++i) {
            d.photons.push_back(make_photon(scene_point(scene, rng), Vec3(0, -1, 0), Color(1)));
        }
        for (uint32_t i = 0; i < kQueryCount; ++i) d.queries.push_back(scene_point(scene, rng));
        return d;
    }
};

// ---- Reference: Jensen's left-balanced kd-tree in a heap-ordered array (node i has children
// 2i and 2i + 1), 20 bytes per photon, built with the same parallel nth_element scheme. ----

struct JensenPhoton {
    Vec3 position;
    uint32_t flux;
    uint8_t theta, phi;
    uint16_t axis;
};
static_assert(sizeof(JensenPhoton) == 20);

struct BuildItem {
    Vec3 position;
    uint32_t index;
};

class JensenKdTree {
public:
    explicit JensenKdTree(const std::vector<Photon>& photons) : input_(&photons) {
        const uint32_t n = uint32_t(photons.size());
        std::vector<BuildItem> items(n);
        for (uint32_t i = 0; i < n; ++i) items[i] = {photons[i].position, i};
        heap_.resize(n + 1);  // 1-based
        balance(items.data(), 0, n, 1);
        input_ = nullptr;
    }

    void k_nearest(const Vec3& p, uint32_t k, float max_radius, KnnResult& out) const {
        out.clear();
        out.neighbors.reserve(k);
        Search s{p, k, max_radius * max_radius, false, &out};
        locate(s, 1);
        out.radius2 = s.full ? out.neighbors[0].dist2 : 0.0f;
    }
    size_t bytes() const { return heap_.capacity() * sizeof(JensenPhoton); }

private:
    struct Search {
        Vec3 p;
        uint32_t k;
        float r2;
        bool full;
        KnnResult* out;
    };

    static bool closer(const KnnNeighbor& a, const KnnNeighbor& b) {
        return a.dist2 < b.dist2 || (a.dist2 == b.dist2 && a.index < b.index);
    }

    // Jensen's median for a left-balanced tree over [lo, hi) (appendix B, balance_segment).
    static uint32_t left_balanced_median(uint32_t lo, uint32_t hi) {
        const uint32_t n = hi - lo;
        uint32_t median = 1;
        while (4 * median <= n) median += median;
        if (3 * median <= n) return lo + 2 * median - 1;
        return hi - median;
    }

    void balance(BuildItem* items, uint32_t lo, uint32_t hi, uint32_t node) {
        if (lo >= hi) return;
        Vec3 lower = items[lo].position, upper = lower;
        for (uint32_t i = lo + 1; i < hi; ++i) {
            lower = glm::min(lower, items[i].position);
            upper = glm::max(upper, items[i].position);
        }
        const Vec3 e = upper - lower;
        const int axis = (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
        const uint32_t median = left_balanced_median(lo, hi);
        std::nth_element(items + lo, items + median, items + hi,
                         [axis](const BuildItem& a, const BuildItem& b) {
                             return a.position[axis] < b.position[axis] ||
                                    (a.position[axis] == b.position[axis] && a.index < b.index);
                         });
        const Photon& photon = (*input_)[items[median].index];
        heap_[node] = {photon.position, photon.flux_mantissas(), photon.theta_bin(),
                       photon.phi_bin(), uint16_t(axis)};
        if (hi - lo >= (1u << 14)) {
            tbb::parallel_invoke([=, this] { balance(items, lo, median, 2 * node); },
                                 [=, this] { balance(items, median + 1, hi, 2 * node + 1); });
        } else {
            balance(items, lo, median, 2 * node);
            balance(items, median + 1, hi, 2 * node + 1);
        }
    }

    void consider(Search& s, uint32_t node) const {
        const float d2 = PhotonKdTree::distance2(s.p, heap_[node].position);
        if (d2 > s.r2) return;
        std::vector<KnnNeighbor>& heap = s.out->neighbors;
        if (!s.full) {
            heap.push_back({node, d2});
            if (heap.size() == s.k) {
                std::make_heap(heap.begin(), heap.end(), closer);
                s.full = true;
                s.r2 = heap[0].dist2;
            }
        } else if (closer({node, d2}, heap[0])) {
            std::pop_heap(heap.begin(), heap.end(), closer);
            heap.back() = {node, d2};
            std::push_heap(heap.begin(), heap.end(), closer);
            s.r2 = heap[0].dist2;
        }
    }

    // Jensen's locate_photons (section 6.3.1): recursive, near child first.
    void locate(Search& s, uint32_t node) const {
        const uint32_t n = uint32_t(heap_.size() - 1);
        const JensenPhoton& photon = heap_[node];
        if (2 * node <= n) {
            const float plane = s.p[photon.axis] - photon.position[photon.axis];
            const uint32_t near = plane > 0.0f ? 2 * node + 1 : 2 * node;
            const uint32_t far = near ^ 1u;
            if (near <= n) locate(s, near);
            if (far <= n && plane * plane <= s.r2) locate(s, far);
        }
        consider(s, node);
    }

    const std::vector<Photon>* input_;
    std::vector<JensenPhoton> heap_;
};

// ---- Benchmarks. Arguments: scene (0 box, 1 Cornell planes), threads. ----

template <class Tree>
void BM_Build(benchmark::State& state) {
    const Data& data = Data::get(int(state.range(0)));
    tbb::task_arena arena(int(state.range(1)));
    size_t bytes = 0;
    for (auto _ : state) {
        state.PauseTiming();
        std::vector<Photon> photons = data.photons;
        state.ResumeTiming();
        arena.execute([&] {
            const Tree tree(std::move(photons));
            bytes = tree.bytes();
            benchmark::DoNotOptimize(bytes);
        });
    }
    state.counters["bytes_per_photon"] = double(bytes) / kPhotonCount;
    state.counters["photons_per_s"] =
        benchmark::Counter(double(kPhotonCount) * state.iterations(), benchmark::Counter::kIsRate);
}

template <class Tree>
void BM_KNearest(benchmark::State& state) {
    const Data& data = Data::get(int(state.range(0)));
    const Tree tree(data.photons);
    const auto k = uint32_t(state.range(1));
    const float max_radius = max_radius_for(k);
    KnnResult result;
    uint64_t found = 0, queries = 0;
    size_t q = 0;
    for (auto _ : state) {
        tree.k_nearest(data.queries[q], k, max_radius, result);
        found += result.size();
        ++queries;
        q = (q + 1) % data.queries.size();
        benchmark::DoNotOptimize(result.radius2);
    }
    state.counters["avg_found"] = double(found) / double(std::max<uint64_t>(queries, 1));
    state.counters["queries_per_s"] =
        benchmark::Counter(double(queries), benchmark::Counter::kIsRate);
    state.counters["bytes_per_photon"] = double(tree.bytes()) / kPhotonCount;
}

BENCHMARK(BM_Build<PhotonKdTree>)
    ->ArgNames({"scene", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);
BENCHMARK(BM_Build<JensenKdTree>)
    ->ArgNames({"scene", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);
// k: the estimates' (k_global 50, k_caustic 100, k_volume 100; 400 in `reference`) and the
// irradiance sites' 4; 200 for scale.
BENCHMARK(BM_KNearest<PhotonKdTree>)
    ->ArgNames({"scene", "k"})
    ->ArgsProduct({{0, 1}, {4, 50, 100, 200}});
BENCHMARK(BM_KNearest<JensenKdTree>)
    ->ArgNames({"scene", "k"})
    ->ArgsProduct({{0, 1}, {4, 50, 100, 200}});

}  // namespace
}  // namespace photond

BENCHMARK_MAIN();
