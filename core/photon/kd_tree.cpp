#include "core/photon/kd_tree.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace photond {
namespace {

// Subtrees at least this large are built as separate tasks.
constexpr uint32_t kParallelThreshold = 1u << 14;
constexpr uint8_t kLeafAxis = 3;

// The photons are partitioned where they lie: no index array, no reordered copy, so the build
// needs no memory beyond the photons themselves (at 10M photons the old build's 16-byte index
// items and reordered copy took 1.7 times the map's bytes on top of it). Equal coordinates need
// no tie-break: std::nth_element is a deterministic function of the range it is given, and each
// subtree's range depends only on its parent's, never on timing.
//
// Large ranges first split around two pivots taken from an evenly spaced sample, at its
// quantiles 0.5 -+ kPivotQuantileMargin: one pass (and a half) puts the photons below, between
// and above them in order, and the median, which the sample places between them but for about
// one range in a hundred thousand, is then selected in the middle part alone (about a tenth of
// the range). std::nth_element by itself moves every photon two to three times over.
constexpr uint32_t kPivotSampleMin = 1u << 16;  // ranges at least this large take pivots
constexpr uint32_t kPivotSamples = 1023;
constexpr float kPivotQuantileMargin = 0.06f;     // about 4 standard deviations of the sample's median rank

template <int kAxis>
void select_median(Photon* first, Photon* median, Photon* last) {
    const auto below = [](const Photon& a, const Photon& b) { return a.position[kAxis] < b.position[kAxis]; };
    const size_t n = static_cast<size_t>(last - first);
    if (n >= kPivotSampleMin) {
        std::array<float, kPivotSamples> sample;
        const size_t step = n / kPivotSamples;
        for (uint32_t i = 0; i < kPivotSamples; ++i) sample[i] = first[i * step].position[kAxis];
        std::sort(sample.begin(), sample.end());
        const float low = sample[size_t((0.5f - kPivotQuantileMargin) * kPivotSamples)];
        const float high = sample[size_t((0.5f + kPivotQuantileMargin) * kPivotSamples)];
        Photon* const middle_begin =
            std::partition(first, last, [low](const Photon& p) { return p.position[kAxis] < low; });
        Photon* const middle_end =
            std::partition(middle_begin, last, [high](const Photon& p) { return p.position[kAxis] <= high; });
        // Every photon of a part lies below every one of the next: selecting inside the part
        // that holds the median's place selects the median of all.
        if (median < middle_begin) {
            last = middle_begin;
        } else if (median < middle_end) {
            first = middle_begin;
            last = middle_end;
        } else {
            first = middle_end;
        }
    }
    std::nth_element(first, median, last, below);
}

// The axis of the largest extent of the photons [lo, hi), from at most about kAxisSamples of
// them, evenly spaced: the split's own pass over a large range is what the build costs, and a
// sample tells the widest axis as well as every photon does (photons on a wall have no extent
// across it in either). Any axis keeps the queries exact; the choice only shapes the tree.
constexpr uint32_t kAxisSamples = 1024;

uint8_t widest_axis(const Photon* photons, uint32_t lo, uint32_t hi) {
    Vec3 lower = photons[lo].position, upper = photons[lo].position;
    const uint32_t step = std::max<uint32_t>(1, (hi - lo) / kAxisSamples);
    for (uint64_t i = uint64_t(lo) + step; i < hi; i += step) {
        lower = glm::min(lower, photons[i].position);
        upper = glm::max(upper, photons[i].position);
    }
    const Vec3 e = upper - lower;
    if (e.x >= e.y && e.x >= e.z) return 0;
    return e.y >= e.z ? 1 : 2;
}

}  // namespace

// Builds the subtree [lo, hi): its median on the widest axis goes to the middle, the rest to
// either side (Jensen 2001, section 6.3, with a median split instead of the left-balanced one).
// Every step depends only on the contents of [lo, hi), never on timing.
void PhotonKdTree::build_subtree(Photon* photons, uint32_t lo, uint32_t hi) {
    if (hi - lo <= kLeafSize) return;
    const uint8_t axis = widest_axis(photons, lo, hi);
    const uint32_t mid = lo + (hi - lo) / 2;
    switch (axis) {
        case 0:
            select_median<0>(photons + lo, photons + mid, photons + hi);
            break;
        case 1:
            select_median<1>(photons + lo, photons + mid, photons + hi);
            break;
        default:
            select_median<2>(photons + lo, photons + mid, photons + hi);
            break;
    }
    photons[mid].set_split_axis(axis);
    if (hi - lo >= kParallelThreshold) {
        tbb::parallel_invoke([=] { build_subtree(photons, lo, mid); }, [=] { build_subtree(photons, mid + 1, hi); });
    } else {
        build_subtree(photons, lo, mid);
        build_subtree(photons, mid + 1, hi);
    }
}

namespace {

// (dist2, index) order of the k-nearest max-heap: the result is the k smallest in this order.
// A function object, not a function: std::make_heap and std::sort inline it, where a function
// pointer was called for every comparison.
constexpr auto closer = [](const KnnNeighbor& a, const KnnNeighbor& b) {
    return a.dist2 < b.dist2 || (a.dist2 == b.dist2 && a.index < b.index);
};

// Replaces the root of the max-heap heap[0, n) and restores the heap property.
void replace_heap_top(KnnNeighbor* heap, size_t n, KnnNeighbor value) {
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

}  // namespace

void KnnResult::sort_by_distance() { std::sort(neighbors.begin(), neighbors.end(), closer); }

size_t KnnResult::farthest() const {
    return full ? 0 : static_cast<size_t>(std::max_element(neighbors.begin(), neighbors.end(), closer) - neighbors.begin());
}

PhotonKdTree::PhotonKdTree(std::vector<Photon> photons) : photons_(std::move(photons)) {
    // Photons with a non-finite position go (the rest keep their order); every photon starts as
    // a leaf, and the build marks the inner nodes.
    const size_t max_photons = std::numeric_limits<uint32_t>::max() - 1;
    size_t kept = 0;
    for (size_t i = 0; i < photons_.size() && kept < max_photons; ++i) {
        if (!is_finite(photons_[i].position)) continue;
        photons_[kept] = photons_[i];
        photons_[kept].set_split_axis(kLeafAxis);
        bounds_.extend(photons_[kept].position);
        ++kept;
    }
    photons_.resize(kept);
    // Spare capacity beyond an eighth (a vector grown by push_back, photons dropped) is given
    // back; less is not worth a copy of the whole array.
    if (photons_.capacity() - kept > kept / 8) photons_.shrink_to_fit();
    if (kept == 0) return;
    build_subtree(photons_.data(), 0, uint32_t(kept));
}

namespace {

std::string format_float(float value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.9g", double(value));
    return text;
}

// Checks the subtree [lo, hi) of an adopted tree-order array and returns its bounds; stops at
// the first violation, which it describes in `error`. Recursion depth <= 32 (balanced tree).
Bounds3 validate_subtree(const Photon* photons, uint32_t lo, uint32_t hi, std::string& error) {
    Bounds3 bounds;
    if (hi - lo <= PhotonKdTree::kLeafSize) {
        for (uint32_t i = lo; i < hi && error.empty(); ++i) {
            if (!is_finite(photons[i].position)) {
                error = "photon " + std::to_string(i) + " has a non-finite position";
            } else if (photons[i].split_axis() != kLeafAxis) {
                error = "leaf photon " + std::to_string(i) + " has split axis " +
                        std::to_string(photons[i].split_axis()) + " (leaf photons have 3)";
            }
            bounds.extend(photons[i].position);
        }
        return bounds;
    }
    const uint32_t mid = lo + (hi - lo) / 2;
    const Photon& node = photons[mid];
    const std::string node_name = "inner node " + std::to_string(mid) + " (photons [" +
                                  std::to_string(lo) + ", " + std::to_string(hi) + "))";
    if (!is_finite(node.position)) {
        error = node_name + " has a non-finite position";
        return bounds;
    }
    const uint32_t axis = node.split_axis();
    if (axis > 2) {
        error = node_name + " has split axis " + std::to_string(axis) + " (must be 0, 1 or 2)";
        return bounds;
    }
    const Bounds3 left = validate_subtree(photons, lo, mid, error);
    if (!error.empty()) return bounds;
    const Bounds3 right = validate_subtree(photons, mid + 1, hi, error);
    if (!error.empty()) return bounds;
    const float split = node.position[axis];
    if (!(left.upper[axis] <= split)) {
        error = node_name + " splits axis " + std::to_string(axis) + " at " + format_float(split) +
                " but its left subtree reaches " + format_float(left.upper[axis]);
    } else if (!(right.lower[axis] >= split)) {
        error = node_name + " splits axis " + std::to_string(axis) + " at " + format_float(split) +
                " but its right subtree reaches " + format_float(right.lower[axis]);
    }
    bounds = left;
    bounds.extend(right.lower);
    bounds.extend(right.upper);
    bounds.extend(node.position);
    return bounds;
}

}  // namespace

Expected<PhotonKdTree> PhotonKdTree::from_tree_order(std::vector<Photon> photons) {
    if (photons.size() > size_t(std::numeric_limits<uint32_t>::max()) - 1) {
        return Error{"photon kd-tree: " + std::to_string(photons.size()) +
                     " photons in tree order, more than a tree holds (2^32 - 2)"};
    }
    PhotonKdTree tree;
    if (photons.empty()) return tree;
    std::string error;
    tree.bounds_ = validate_subtree(photons.data(), 0, uint32_t(photons.size()), error);
    if (!error.empty()) return Error{"photon kd-tree: " + error};
    tree.photons_ = std::move(photons);
    return tree;
}

void PhotonKdTree::k_nearest(const Vec3& p, uint32_t k, float max_radius, KnnResult& out) const {
    k_nearest_impl(p, k, max_radius, out, [p](const Vec3& q) { return distance2(p, q); },
                   [](const Photon&) { return true; });
}

void PhotonKdTree::k_nearest_flagged(const Vec3& p, uint32_t k, float max_radius, uint8_t required_flags,
                                     uint8_t excluded_flags, KnnResult& out) const {
    k_nearest_impl(p, k, max_radius, out, [p](const Vec3& q) { return distance2(p, q); },
                   [required_flags, excluded_flags](const Photon& photon) {
                       const uint8_t flags = photon.user_flags();
                       return (flags & required_flags) == required_flags && (flags & excluded_flags) == 0;
                   });
}

void PhotonKdTree::k_nearest_in_disc(const Vec3& p, const Vec3& normal, float flattening,
                                     uint32_t k, float max_radius, KnnResult& out) const {
    const float stretch2 = flattening > 1.0f ? flattening * flattening - 1.0f : 0.0f;
    if (!is_finite(normal) || !std::isfinite(stretch2)) {
        out.clear();
        return;
    }
    k_nearest_impl(p, k, max_radius, out, [p, normal, stretch2](const Vec3& q) {
        return disc_distance2(p, q, normal, stretch2);
    }, [](const Photon&) { return true; });
}

template <class Distance2, class Accept>
void PhotonKdTree::k_nearest_impl(const Vec3& p, uint32_t k, float max_radius, KnnResult& out,
                                  Distance2 distance2_to, Accept accept) const {
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
        if (!full) {
            heap.push_back({index, d2});
            farthest2 = std::max(farthest2, d2);
            if (heap.size() == capacity) {
                std::make_heap(heap.begin(), heap.end(), closer);
                full = true;
                r2 = heap[0].dist2;
            }
        } else if (closer({index, d2}, heap[0])) {
            replace_heap_top(heap.data(), heap.size(), {index, d2});
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
            if (accept(node)) consider(mid, distance2_to(node.position));
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
        for (uint32_t i = lo; i < hi; ++i)
            if (accept(photons_[i])) consider(i, distance2_to(photons_[i].position));
    }
    out.radius2 = full ? heap[0].dist2 : farthest2;
    out.full = full;
}

}  // namespace photond
