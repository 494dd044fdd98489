#include "core/light/light_tree.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace photond {

namespace {

constexpr uint64_t kNotInTree = ~uint64_t(0);
/// Below this depth the tree splits by cost; from it on by count, so that no path is longer than
/// 64 choices (a trail's bits) for up to 2^32 lights.
constexpr int kCostSplitDepth = 32;
constexpr int kBuckets = 12;
// Subtrees of this many lights or more build their two halves in parallel.
constexpr size_t kParallelBuildLights = 4096;
constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

/// cos(max(0, a - b)) and sin(max(0, a - b)) from the sines and cosines of a and b (pbrt-v4,
/// `LightBounds::Importance`).
float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    if (cos_a > cos_b) return 1.0f;  // a < b
    return cos_a * cos_b + sin_a * sin_b;
}
float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    if (cos_a > cos_b) return 0.0f;
    return sin_a * cos_b - cos_a * sin_b;
}

float angle_between(const Vec3& a, const Vec3& b) {
    // Precise for nearly equal or opposite vectors, unlike acos of the dot product.
    if (glm::dot(a, b) < 0.0f) return kPi - 2.0f * std::asin(std::min(1.0f, 0.5f * glm::length(a + b)));
    return 2.0f * std::asin(std::min(1.0f, 0.5f * glm::length(b - a)));
}

/// The split cost of a set of lights (pbrt-v4 `BVHLightSampler::EvaluateCost`): its intensity
/// times the solid angle its cones can reach (M_omega) times its bounds' area, stretched by how
/// thin the bounds are along the split axis (K_r). `min_side` keeps the area of a point positive.
float split_cost(const LightBounds& b, int axis, float min_side) {
    const float theta_o = std::acos(std::clamp(b.cos_theta_o, -1.0f, 1.0f));
    const float theta_e = std::acos(std::clamp(b.cos_theta_e, -1.0f, 1.0f));
    const float theta_w = std::min(theta_o + theta_e, kPi);
    const float sin_o = safe_sqrt(1.0f - b.cos_theta_o * b.cos_theta_o);
    const float m_omega = 2.0f * kPi * (1.0f - b.cos_theta_o) +
                          0.5f * kPi * (2.0f * theta_w * sin_o - std::cos(theta_o - 2.0f * theta_w) -
                                        2.0f * theta_o * sin_o + b.cos_theta_o);
    const Vec3 d = glm::max(b.bounds.extent(), Vec3(min_side));
    const float k_r = max_component(d) / d[axis];
    const float area = 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
    return b.intensity * m_omega * k_r * area;
}

}  // namespace

LightBounds light_bounds_union(const LightBounds& a, const LightBounds& b) {
    if (!(a.intensity > 0.0f)) return b;
    if (!(b.intensity > 0.0f)) return a;
    LightBounds u;
    u.bounds = a.bounds;
    u.bounds.extend(b.bounds.lower);
    u.bounds.extend(b.bounds.upper);
    u.intensity = a.intensity + b.intensity;
    u.cos_theta_e = std::min(a.cos_theta_e, b.cos_theta_e);
    u.two_sided = a.two_sided || b.two_sided;
    // A single direction well inside a's cone (most of a build's unions): a's cone, as the exact
    // test below finds (the margin, far above its rounding, keeps the two from disagreeing), but
    // without its inverse cosines.
    if (b.cos_theta_o >= 1.0f && glm::dot(a.w, b.w) >= a.cos_theta_o + 1e-5f) {
        u.w = a.w;
        u.cos_theta_o = a.cos_theta_o;
        return u;
    }
    // The cone around both cones (pbrt-v4 `DirectionCone::Union`).
    const float theta_a = std::acos(std::clamp(a.cos_theta_o, -1.0f, 1.0f));
    const float theta_b = std::acos(std::clamp(b.cos_theta_o, -1.0f, 1.0f));
    const float theta_d = angle_between(a.w, b.w);
    if (std::min(theta_d + theta_b, kPi) <= theta_a) {
        u.w = a.w;
        u.cos_theta_o = a.cos_theta_o;
        return u;
    }
    if (std::min(theta_d + theta_a, kPi) <= theta_b) {
        u.w = b.w;
        u.cos_theta_o = b.cos_theta_o;
        return u;
    }
    // A little wider than the exact union, so that rounding in the rotation below cannot leave
    // a child's direction outside.
    const float theta_o = 0.5f * (theta_a + theta_d + theta_b) + 1e-4f;
    const Vec3 axis = glm::cross(a.w, b.w);
    const float axis_length = glm::length(axis);
    if (theta_o >= kPi || !(axis_length > 0.0f)) {
        u.w = a.w;
        u.cos_theta_o = -1.0f;  // the whole sphere
        return u;
    }
    // a.w turned towards b.w by theta_o - theta_a about their common normal (Rodrigues' formula;
    // a.w is perpendicular to the axis).
    const float theta_r = theta_o - theta_a;
    const Vec3 k = axis / axis_length;
    u.w = glm::normalize(a.w * std::cos(theta_r) + glm::cross(k, a.w) * std::sin(theta_r));
    u.cos_theta_o = std::cos(theta_o);
    return u;
}

ImportanceBounds::ImportanceBounds(const LightBounds& b)
    : center(b.bounds.center()),
      radius2(0.25f * glm::dot(b.bounds.extent(), b.bounds.extent())),
      radius(std::sqrt(radius2)),
      intensity(b.intensity),
      w(b.w),
      cos_theta_o(std::clamp(b.cos_theta_o, -1.0f, 1.0f)),
      sin_theta_o(safe_sqrt(1.0f - cos_theta_o * cos_theta_o)),
      cos_theta_e(b.cos_theta_e),
      two_sided(b.two_sided) {}

float light_importance(const LightBounds& b, const Vec3& p) { return light_importance(ImportanceBounds(b), p); }

float light_importance(const ImportanceBounds& b, const Vec3& p) {
    const Vec3 to_p = p - b.center;
    const float d2 = glm::dot(to_p, to_p);
    // Closer than the bounding sphere's radius, every light inside may be that close.
    const float distance2 = std::max({d2, b.radius2, std::numeric_limits<float>::min()});
    // A cone of every direction (point lights) reaches p at full strength: theta' = 0.
    if (b.cos_theta_o <= -1.0f) return b.intensity / distance2;
    const float inv_d = d2 > 0.0f ? 1.0f / std::sqrt(d2) : 0.0f;
    float cos_w = d2 > 0.0f ? glm::dot(b.w, to_p) * inv_d : 1.0f;
    if (b.two_sided) cos_w = std::abs(cos_w);
    cos_w = std::clamp(cos_w, -1.0f, 1.0f);
    // p's direction inside the cone: theta' = 0.
    if (cos_w >= b.cos_theta_o) return b.intensity / distance2;
    const float sin_w = safe_sqrt(1.0f - cos_w * cos_w);
    // theta_b: the half-angle of the bounding sphere seen from p (everything, from inside it).
    const bool outside = d2 > b.radius2;
    const float sin_b = outside ? std::min(b.radius * inv_d, 1.0f) : 0.0f;
    const float cos_b = outside ? safe_sqrt(1.0f - sin_b * sin_b) : -1.0f;
    // theta' = max(0, theta_w - theta_o - theta_b): the angle from the cone to p's direction.
    const float cos_x = cos_sub_clamped(sin_w, cos_w, b.sin_theta_o, b.cos_theta_o);
    const float sin_x = sin_sub_clamped(sin_w, cos_w, b.sin_theta_o, b.cos_theta_o);
    const float cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if (cos_p <= b.cos_theta_e) return 0.0f;
    return b.intensity * cos_p / distance2;
}

LightTree::LightTree(std::span<const LightBounds> lights) {
    trails_.assign(lights.size(), kNotInTree);
    std::vector<uint32_t> indices;
    for (uint32_t i = 0; i < lights.size(); ++i) {
        if (lights[i].intensity > 0.0f && std::isfinite(lights[i].intensity)) indices.push_back(i);
    }
    light_count_ = indices.size();
    if (indices.empty()) return;
    nodes_.resize(2 * indices.size() - 1);
    depth_ = build(lights, indices, 0, indices.size(), 0, 0, 0);
}

int LightTree::build(std::span<const LightBounds> all, std::vector<uint32_t>& lights, size_t begin, size_t end,
                     uint32_t index, uint64_t trail, int depth) {
    if (end - begin == 1) {
        nodes_[index].bounds = ImportanceBounds(all[lights[begin]]);
        nodes_[index].leaf = true;
        nodes_[index].light = lights[begin];
        trails_[lights[begin]] = trail;
        return depth;
    }
    LightBounds node_bounds;
    Bounds3 centroids;
    for (size_t i = begin; i < end; ++i) {
        node_bounds = light_bounds_union(node_bounds, all[lights[i]]);
        centroids.extend(all[lights[i]].bounds.center());
    }
    const Vec3 extent = centroids.extent();
    size_t middle = begin;
    if (depth < kCostSplitDepth && max_component(extent) > 0.0f) {
        // Buckets along each axis; the split between buckets of least cost.
        const float min_side = 1e-3f * max_component(node_bounds.bounds.extent());
        float best_cost = std::numeric_limits<float>::infinity();
        int best_axis = -1, best_bucket = -1;
        const auto bucket_of = [&](uint32_t light, int axis) {
            const float t = (all[light].bounds.center()[axis] - centroids.lower[axis]) / extent[axis];
            return std::clamp(static_cast<int>(t * kBuckets), 0, kBuckets - 1);
        };
        for (int axis = 0; axis < 3; ++axis) {
            if (!(extent[axis] > 0.0f)) continue;
            std::array<LightBounds, kBuckets> buckets{};
            for (size_t i = begin; i < end; ++i) {
                LightBounds& bucket = buckets[bucket_of(lights[i], axis)];
                bucket = light_bounds_union(bucket, all[lights[i]]);
            }
            for (int split = 0; split < kBuckets - 1; ++split) {
                LightBounds below, above;
                for (int b = 0; b <= split; ++b) below = light_bounds_union(below, buckets[b]);
                for (int b = split + 1; b < kBuckets; ++b) above = light_bounds_union(above, buckets[b]);
                if (!(below.intensity > 0.0f) || !(above.intensity > 0.0f)) continue;
                const float cost = split_cost(below, axis, min_side) + split_cost(above, axis, min_side);
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = axis;
                    best_bucket = split;
                }
            }
        }
        if (best_axis >= 0) {
            const auto it = std::stable_partition(lights.begin() + begin, lights.begin() + end,
                                                  [&](uint32_t l) { return bucket_of(l, best_axis) <= best_bucket; });
            middle = static_cast<size_t>(it - lights.begin());
        }
    }
    if (middle == begin || middle == end) {
        // Halves by count along the widest axis of the centroids (ties by index, deterministic).
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
        middle = begin + (end - begin) / 2;
        std::nth_element(lights.begin() + begin, lights.begin() + middle, lights.begin() + end,
                         [&](uint32_t a, uint32_t b) {
                             const float ca = all[a].bounds.center()[axis], cb = all[b].bounds.center()[axis];
                             return ca < cb || (ca == cb && a < b);
                         });
    }
    nodes_[index].bounds = ImportanceBounds(node_bounds);
    // The subtrees own disjoint ranges of `lights`, of nodes_ and of trails_: the tree is the same
    // built in parallel or not.
    const uint32_t second = index + 2 * static_cast<uint32_t>(middle - begin);
    nodes_[index].second_child = second;
    int first_depth = 0, second_depth = 0;
    const auto first_subtree = [&] { first_depth = build(all, lights, begin, middle, index + 1, trail, depth + 1); };
    const auto second_subtree = [&] {
        second_depth = build(all, lights, middle, end, second, trail | (uint64_t(1) << depth), depth + 1);
    };
    if (end - begin >= kParallelBuildLights) {
        tbb::parallel_invoke(first_subtree, second_subtree);
    } else {
        first_subtree();
        second_subtree();
    }
    return std::max(first_depth, second_depth);
}

void LightTree::child_probabilities(const Node& node, uint32_t index, const Vec3& p, float* p0, float* p1) const {
    const float i0 = light_importance(nodes_[index + 1].bounds, p);
    const float i1 = light_importance(nodes_[node.second_child].bounds, p);
    const float sum = i0 + i1;
    if (std::isfinite(sum)) {
        *p0 = sum > 0.0f ? i0 / sum : 0.0f;
        *p1 = sum > 0.0f ? i1 / sum : 0.0f;
        return;
    }
    // A light at p itself: the infinite importance wins (halves when both are).
    *p0 = std::isinf(i0) ? (std::isinf(i1) ? 0.5f : 1.0f) : 0.0f;
    *p1 = 1.0f - *p0;
}

std::optional<uint32_t> LightTree::sample(const Vec3& p, float u, float* pmf) const {
    *pmf = 0.0f;
    if (nodes_.empty()) return std::nullopt;
    uint32_t index = 0;
    float probability = 1.0f;
    while (!nodes_[index].leaf) {
        const Node& node = nodes_[index];
        float p0 = 0.0f, p1 = 0.0f;
        child_probabilities(node, index, p, &p0, &p1);
        if (!(p0 > 0.0f) && !(p1 > 0.0f)) return std::nullopt;
        if (u < p0) {
            u = std::min(u / p0, kOneMinusEpsilon);
            probability *= p0;
            index = index + 1;
        } else {
            u = std::clamp((u - p0) / p1, 0.0f, kOneMinusEpsilon);
            probability *= p1;
            index = node.second_child;
        }
    }
    *pmf = probability;
    return nodes_[index].light;
}

float LightTree::pmf(const Vec3& p, uint32_t light) const {
    if (light >= trails_.size() || trails_[light] == kNotInTree) return 0.0f;
    uint64_t trail = trails_[light];
    uint32_t index = 0;
    float probability = 1.0f;
    while (!nodes_[index].leaf) {
        const Node& node = nodes_[index];
        float p0 = 0.0f, p1 = 0.0f;
        child_probabilities(node, index, p, &p0, &p1);
        if (trail & 1) {
            probability *= p1;
            index = node.second_child;
        } else {
            probability *= p0;
            index = index + 1;
        }
        if (!(probability > 0.0f)) return 0.0f;
        trail >>= 1;
    }
    return probability;
}

}  // namespace photond
