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

void KnnResult::sort_by_distance() { std::sort(neighbors.begin(), neighbors.end(), knn_detail::closer); }

size_t KnnResult::farthest() const {
    return full ? 0 : static_cast<size_t>(std::max_element(neighbors.begin(), neighbors.end(), knn_detail::closer) - neighbors.begin());
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
    k_nearest_where(p, k, max_radius, out, [p](const Vec3& q) { return distance2(p, q); },
                    [](const Photon&) { return true; });
}

void PhotonKdTree::k_nearest_flagged(const Vec3& p, uint32_t k, float max_radius, uint8_t required_flags,
                                     uint8_t excluded_flags, KnnResult& out) const {
    k_nearest_where(p, k, max_radius, out, [p](const Vec3& q) { return distance2(p, q); },
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
    k_nearest_where(p, k, max_radius, out,
                    [p, normal, stretch2](const Vec3& q) { return disc_distance2(p, q, normal, stretch2); },
                    [](const Photon&) { return true; });
}

}  // namespace photond
