// The photon map's kd-tree (Jensen, "Realistic Image Synthesis Using Photon Mapping", 2001,
// section 6.3): a balanced tree over the photons themselves, stored implicitly in one array.
#pragma once

#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "core/photon/photon.h"
#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

/// One photon found by a query: its index in the tree (PhotonKdTree::photon) and its squared
/// distance to the query point.
struct KnnNeighbor {
    uint32_t index = 0;
    float dist2 = 0.0f;
};

namespace knn_detail {
// (dist2, index) order of the k-nearest max-heap: the result is the k smallest in this order.
// A function object, not a function: std::make_heap and std::sort inline it, where a function
// pointer was called for every comparison.
inline constexpr auto closer = [](const KnnNeighbor& a, const KnnNeighbor& b) {
    return a.dist2 < b.dist2 || (a.dist2 == b.dist2 && a.index < b.index);
};

// Replaces the root of the max-heap heap[0, n) and restores the heap property.
inline void replace_heap_top(KnnNeighbor* heap, size_t n, KnnNeighbor value) {
    size_t i = 0;
    for (;;) {
        size_t child = 2 * i + 1;
        if (child >= n) break;
        if (child + 1 < n && closer(heap[child], heap[child + 1])) ++child;
        if (!closer(value, heap[child])) break;
        heap[i] = heap[child];
        i = child;
    }
    heap[i] = value;
}

}  // namespace knn_detail

/// The result of PhotonKdTree::k_nearest. Keep one per thread and pass it to every query: its
/// buffer is reused, so queries do not allocate once it has grown to k.
struct KnnResult {
    /// Up to k photons, in max-heap order of (dist2, index) (deterministic, not sorted; see
    /// sort_by_distance).
    std::vector<KnnNeighbor> neighbors;
    /// Squared distance of the farthest photon returned: the radius actually used when k
    /// photons were found (may be 0, e.g. coincident photons: never divide by it unchecked);
    /// 0 when none was found. When fewer than k were found, the region searched was the
    /// max_radius ball.
    float radius2 = 0.0f;
    /// Whether k photons were found: `neighbors` is then a max-heap (the farthest first).
    bool full = false;

    size_t size() const { return neighbors.size(); }
    bool empty() const { return neighbors.empty(); }
    void clear() {
        neighbors.clear();
        radius2 = 0.0f;
        full = false;
    }
    /// Orders neighbors by increasing (dist2, index).
    void sort_by_distance();
    /// The index in `neighbors` of the farthest by (dist2, index): the heap's top when full (no
    /// search), else found by a scan. Not for an empty result.
    size_t farthest() const;
};

/// A kd-tree over photons, built once and then only read.
///
/// Thread safety: immutable after construction; every const member may be called concurrently
/// from any number of threads (queries keep their state on the stack and in the caller's
/// KnnResult). Share it as std::shared_ptr<const PhotonKdTree>.
///
/// Layout: the photons, reordered, in one array that is the tree in implicit in-order form: the
/// subtree of index range [lo, hi) has its split photon at mid = lo + (hi - lo) / 2 (split axis
/// in the photon's flags, split value its coordinate), left subtree [lo, mid), right subtree
/// [mid + 1, hi); ranges of at most kLeafSize photons are leaves scanned linearly. Each subtree
/// is contiguous in memory and no pointers or extra node records are stored: 24 bytes per photon,
/// like Jensen's left-balanced heap, and faster to query (bench/kd_tree_bench.cpp measures both).
/// Split axis: the largest extent of the subtree's bounding box, taken from at most about 1,024
/// of its photons (lowest axis on ties); split at the median coordinate.
///
/// Build: in place in the photons' own array (no memory beyond them), parallel over subtrees
/// with oneTBB in the current task arena; the tree depends only on the input order, not on the
/// number of threads. Photons with a non-finite position are dropped, so
/// size() may be less than the input's size. Indices are positions in the tree's order, not in
/// the input vector.
class PhotonKdTree {
public:
    static constexpr uint32_t kLeafSize = 16;

    /// An empty tree: every query returns nothing.
    PhotonKdTree() = default;
    /// Builds the tree; takes the photons (at most 2^32 - 2 are kept).
    explicit PhotonKdTree(std::vector<Photon> photons);

    /// Adopts photons already in tree order (photons() of a built tree, e.g. read back from a
    /// file) without rebuilding. Checks in O(n) what queries rely on: finite positions, split
    /// axes 0..2 on inner nodes and 3 on leaf photons, and every inner node's split separating
    /// its subtrees (left <= split <= right on its axis); recomputes the bounds. The Error names
    /// the first violation found. The result answers every query exactly as the original did.
    static Expected<PhotonKdTree> from_tree_order(std::vector<Photon> photons);

    /// The (at most) k photons nearest to p within max_radius (distance <= max_radius), the
    /// nearest by (squared distance, index): ties are broken by the smaller index, so the result
    /// is exactly that of a brute-force search. Empty for k = 0, an empty tree, a non-finite p,
    /// or a negative or NaN max_radius; max_radius may be +infinity.
    void k_nearest(const Vec3& p, uint32_t k, float max_radius, KnnResult& out) const;

    /// k_nearest in a disc instead of a sphere (Jensen 2001, section 7.2: the search sphere
    /// compressed along the surface normal): distances are disc_distance2's, an ellipsoid whose
    /// axis along the unit `normal` is 1 / flattening of the others (flattening >= 1; 1 is
    /// k_nearest). The same guarantees: ties by index, exactly a brute-force search.
    void k_nearest_in_disc(const Vec3& p, const Vec3& normal, float flattening, uint32_t k,
                           float max_radius, KnnResult& out) const;

    /// k_nearest among the photons whose user flags hold all of `required_flags` and none of
    /// `excluded_flags` (the others are not candidates: the k found are k of those). The same
    /// guarantees as k_nearest.
    void k_nearest_flagged(const Vec3& p, uint32_t k, float max_radius, uint8_t required_flags,
                           uint8_t excluded_flags, KnnResult& out) const;

    /// The k nearest to p within max_radius by `distance2_to(position)` (which must never be
    /// below distance2(p, position): the tree prunes by it) among the photons that
    /// `accept(photon)` takes, with k_nearest's guarantees. `accept` is asked only of a photon
    /// that would enter the result as things stand (within the radius, and nearer than the
    /// farthest once k are found), so a costly test (a decoded normal) runs for few of the
    /// photons a search meets; it must depend on the photon alone.
    template <class Distance2, class Accept>
    void k_nearest_where(const Vec3& p, uint32_t k, float max_radius, KnnResult& out, Distance2 distance2_to,
                         Accept accept) const;

    /// Calls f(uint32_t index, float dist2) for every photon with distance <= radius to p, in a
    /// deterministic order. Nothing for a non-finite p or a negative or NaN radius.
    template <class F>
    void for_each_in_radius(const Vec3& p, float radius, F&& f) const;

    const Photon& photon(uint32_t index) const { return photons_[index]; }
    std::span<const Photon> photons() const { return photons_; }
    uint32_t size() const { return uint32_t(photons_.size()); }
    bool empty() const { return photons_.empty(); }
    /// Memory held by the tree (the photon array's capacity).
    size_t bytes() const { return photons_.capacity() * sizeof(Photon); }
    /// Bounds of the photon positions (empty for an empty tree).
    const Bounds3& bounds() const { return bounds_; }

    /// The squared distance every query uses (one expression, so tests can reproduce it).
    static float distance2(const Vec3& a, const Vec3& b) {
        const float dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
        return dx * dx + dy * dy + dz * dz;
    }
    /// The squared disc distance of k_nearest_in_disc: |a - b|^2 + (f^2 - 1) ((a - b) . n)^2,
    /// given stretch2 = f^2 - 1 >= 0. Never below distance2, which keeps the tree's pruning valid.
    static float disc_distance2(const Vec3& a, const Vec3& b, const Vec3& normal, float stretch2) {
        const float dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
        const float along = dx * normal.x + dy * normal.y + dz * normal.z;
        return dx * dx + dy * dy + dz * dz + stretch2 * (along * along);
    }

private:
    static void build_subtree(Photon* photons, uint32_t lo, uint32_t hi);

    // Deeper than any balanced tree over < 2^32 photons (depth <= 32).
    static constexpr int kMaxStackDepth = 64;

    std::vector<Photon> photons_;
    Bounds3 bounds_;
};

template <class Distance2, class Accept>
void PhotonKdTree::k_nearest_where(const Vec3& p, uint32_t k, float max_radius, KnnResult& out,
                                   Distance2 distance2_to, Accept accept) const {
    using knn_detail::closer;
    // distance2_to(q) >= distance2(p, q) for every q: a subtree whose cell lies beyond the
    // current radius holds no closer photon in either metric.
    out.clear();
    if (k == 0 || photons_.empty() || !is_finite(p) || !(max_radius >= 0.0f)) return;
    std::vector<KnnNeighbor>& heap = out.neighbors;
    const size_t capacity = std::min<size_t>(k, photons_.size());
    if (heap.capacity() < capacity) heap.reserve(capacity);

    // Until the heap is full, r2 is the max_radius ball; then the heap top's distance (Jensen
    // 2001, section 6.3.1). Subtrees whose cell distance equals r2 are still visited, since
    // they may hold a photon at the same distance with a smaller index.
    float r2 = max_radius * max_radius;
    float farthest2 = 0.0f;
    bool full = false;
    const auto consider = [&](uint32_t index, float d2) {
        if (d2 > r2) return;
        if (full && !closer({index, d2}, heap[0])) return;
        if (!accept(photons_[index])) return;
        if (!full) {
            heap.push_back({index, d2});
            farthest2 = std::max(farthest2, d2);
            if (heap.size() == capacity) {
                std::make_heap(heap.begin(), heap.end(), closer);
                full = true;
                r2 = heap[0].dist2;
            }
        } else {
            knn_detail::replace_heap_top(heap.data(), heap.size(), {index, d2});
            r2 = heap[0].dist2;
        }
    };

    // A subtree is skipped when its cell (the slabs of the splits above it) lies beyond r2, not
    // only its nearest splitting plane (Arya and Mount 1993, "Algorithms for fast vector
    // quantization": incremental distance): per axis, the squared distance from p to the cell's
    // slab, and their sum in distance2's order. Every photon of the cell is at least as far on
    // each axis and rounding is monotonic, so the sum never exceeds its distance2 (nor its disc
    // distance): no subtree that holds a candidate is skipped.
    struct Entry {
        uint32_t lo, hi;
        Vec3 slab2;  // squared distance from p to the cell's slab on each axis (0: p inside)
        float cell2;  // (slab2.x + slab2.y) + slab2.z
    };
    Entry stack[kMaxStackDepth];
    int top = 0;
    stack[top++] = {0, size(), Vec3(0.0f), 0.0f};
    while (top > 0) {
        const Entry entry = stack[--top];
        if (entry.cell2 > r2) continue;
        uint32_t lo = entry.lo, hi = entry.hi;
        while (hi - lo > kLeafSize) {
            const uint32_t mid = lo + (hi - lo) / 2;
            const Photon& node = photons_[mid];
            consider(mid, distance2_to(node.position));
            const uint32_t axis = node.split_axis();
            const float plane = p[axis] - node.position[axis];
            // The far side's slab on this axis begins at the plane, no nearer than the one
            // above (the near side keeps this cell's slabs).
            Vec3 far_slab2 = entry.slab2;
            far_slab2[axis] = plane * plane;
            const float far2 = far_slab2.x + far_slab2.y + far_slab2.z;
            if (plane <= 0.0f) {  // near side first; the far side waits on the stack
                if (far2 <= r2) stack[top++] = {mid + 1, hi, far_slab2, far2};
                hi = mid;
            } else {
                if (far2 <= r2) stack[top++] = {lo, mid, far_slab2, far2};
                lo = mid + 1;
            }
        }
        for (uint32_t i = lo; i < hi; ++i) consider(i, distance2_to(photons_[i].position));
    }
    out.radius2 = full ? heap[0].dist2 : farthest2;
    out.full = full;
}

template <class F>
void PhotonKdTree::for_each_in_radius(const Vec3& p, float radius, F&& f) const {
    if (photons_.empty() || !is_finite(p) || !(radius >= 0.0f)) return;
    const float r2 = radius * radius;
    struct Range {
        uint32_t lo, hi;
    };
    Range stack[kMaxStackDepth];
    int top = 0;
    stack[top++] = {0, size()};
    while (top > 0) {
        --top;
        uint32_t lo = stack[top].lo, hi = stack[top].hi;
        while (hi - lo > kLeafSize) {
            const uint32_t mid = lo + (hi - lo) / 2;
            const Photon& node = photons_[mid];
            const float d2 = distance2(p, node.position);
            if (d2 <= r2) f(mid, d2);
            const uint32_t axis = node.split_axis();
            const float plane = p[axis] - node.position[axis];
            if (plane <= 0.0f) {  // p on the left side: the right one only if the ball crosses
                if (plane * plane <= r2) stack[top++] = {mid + 1, hi};
                hi = mid;
            } else {
                if (plane * plane <= r2) stack[top++] = {lo, mid};
                lo = mid + 1;
            }
        }
        for (uint32_t i = lo; i < hi; ++i) {
            const float d2 = distance2(p, photons_[i].position);
            if (d2 <= r2) f(i, d2);
        }
    }
}

}  // namespace photond
