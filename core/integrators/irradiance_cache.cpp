#include "core/integrators/irradiance_cache.h"

#include <limits>

namespace photond {
namespace {

/// A record whose centre lies this far in front of P (in units of R_i) sees another hemisphere.
constexpr float kFrontTolerance = 0.01f;
/// Smallest eps used in the weight, so that a record exactly at P has a finite weight.
constexpr float kMinEpsilon = 1e-4f;

}  // namespace

IrradianceCache::IrradianceCache(const Bounds3& scene_bounds, const IrradianceCacheSettings& settings)
    : settings_(settings) {
    const Vec3 center = scene_bounds.empty() ? Vec3(0.0f) : scene_bounds.center();
    const float half = scene_bounds.empty() ? 1.0f : 0.5f * max_component(scene_bounds.extent()) * 1.01f + 1e-6f;
    Node root{center, half, {}, {}};
    root.children.fill(-1);
    nodes_.push_back(std::move(root));
}

template <typename F>
void IrradianceCache::for_each_candidate(const Vec3& p, float domain_scale, float reach, F&& f) const {
    // A node's records have their centre inside it and a validity radius at most its half size,
    // so only nodes whose box grown by half its size (times domain_scale, plus `reach`) contains
    // p can matter. The
    // root is always visited: it also keeps records placed outside its box.
    const auto reaches = [&](const Node& node) {
        return max_component(glm::abs(p - node.center)) <= (1.0f + domain_scale) * node.half_size + reach;
    };
    int32_t stack[8 * 64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes_[static_cast<size_t>(stack[--top])];
        for (uint32_t r : node.records) f(r);
        for (int32_t c : node.children) {
            if (c >= 0 && top < static_cast<int>(std::size(stack)) && reaches(nodes_[static_cast<size_t>(c)]))
                stack[top++] = c;
        }
    }
}

bool IrradianceCache::interpolate(const Vec3& p, const Vec3& n, Color* irradiance, float accuracy_scale) const {
    if (records_.empty()) return false;
    const float a = settings_.accuracy * accuracy_scale;
    double weight_sum = 0.0;
    DVec3 sum(0.0);
    for_each_candidate(p, accuracy_scale, 0.0f, [&](uint32_t index) {
        const IrradianceRecord& r = records_[index];
        const Vec3 offset = p - r.position;
        const float distance = glm::length(offset);
        const float cos_normals = std::min(1.0f, glm::dot(n, r.normal));
        const float epsilon = distance / r.radius + safe_sqrt(1.0f - cos_normals);
        if (!(epsilon < a)) return;
        // In front of P: the record sees a different hemisphere (Ward et al. 1988).
        if (glm::dot(offset, 0.5f * (n + r.normal)) < -kFrontTolerance * r.radius) return;
        const double w = 1.0 / std::max(epsilon, kMinEpsilon) - 1.0 / a;
        if (!(w > 0.0)) return;
        Color e = r.irradiance;
        if (settings_.gradients) {
            const Vec3 axis = glm::cross(r.normal, n);
            for (int c = 0; c < 3; ++c)
                e[c] += glm::dot(axis, r.rotation_gradient[c]) + glm::dot(offset, r.translation_gradient[c]);
        }
        // Gradient extrapolation may not push a record's estimate below zero.
        sum += w * DVec3(glm::max(e, Color(0.0f)));
        weight_sum += w;
    });
    if (!(weight_sum > 0.0)) return false;
    *irradiance = Color(sum / weight_sum);
    return true;
}

int32_t IrradianceCache::child_for(int32_t node_index, const Vec3& p) {
    const Node node = nodes_[static_cast<size_t>(node_index)];
    const int octant = (p.x > node.center.x ? 1 : 0) | (p.y > node.center.y ? 2 : 0) | (p.z > node.center.z ? 4 : 0);
    int32_t child = node.children[static_cast<size_t>(octant)];
    if (child < 0) {
        const float h = 0.5f * node.half_size;
        const Vec3 c = node.center + Vec3(octant & 1 ? h : -h, octant & 2 ? h : -h, octant & 4 ? h : -h);
        Node n{c, h, {}, {}};
        n.children.fill(-1);
        child = static_cast<int32_t>(nodes_.size());
        nodes_.push_back(std::move(n));
        nodes_[static_cast<size_t>(node_index)].children[static_cast<size_t>(octant)] = child;
    }
    return child;
}

void IrradianceCache::insert(IrradianceRecord record, float min_radius) {
    const float a = settings_.accuracy;
    if (!(record.radius > 0.0f) || !std::isfinite(record.radius) || !is_finite(record.irradiance)) return;
    // Neighbour clamping: R_i <= R_j + |P_i - P_j| for every record whose domain overlaps.
    const uint32_t new_index = static_cast<uint32_t>(records_.size());
    std::vector<uint32_t> neighbours;
    for_each_candidate(record.position, 1.0f, a * record.radius, [&](uint32_t j) {
        const IrradianceRecord& r = records_[j];
        const float d = glm::length(record.position - r.position);
        if (d < a * (record.radius + r.radius) && glm::dot(record.normal, r.normal) > 0.0f) neighbours.push_back(j);
    });
    for (uint32_t j : neighbours) {
        const float d = glm::length(record.position - records_[j].position);
        record.radius = std::max(min_radius, std::min(record.radius, records_[j].radius + d));
    }
    for (uint32_t j : neighbours) {
        IrradianceRecord& r = records_[j];
        r.radius = std::min(r.radius, record.radius + glm::length(record.position - r.position));
    }
    // The deepest node whose half size still holds the validity radius a R_i.
    const float validity = a * record.radius;
    int32_t node = 0;
    const Node& root = nodes_[0];
    if (max_component(glm::abs(record.position - root.center)) <= root.half_size) {
        while (0.5f * nodes_[static_cast<size_t>(node)].half_size >= validity &&
               nodes_[static_cast<size_t>(node)].half_size > 1e-30f) {
            node = child_for(node, record.position);
        }
    }
    nodes_[static_cast<size_t>(node)].records.push_back(new_index);
    records_.push_back(record);
}

}  // namespace photond
