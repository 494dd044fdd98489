#include "core/integrators/irradiance_cache.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <string>

namespace photond {
namespace {

/// A record whose centre lies this far in front of P (in units of R_i) sees another hemisphere.
constexpr float kFrontTolerance = 0.01f;
/// Smallest eps used in the weight, so that a record exactly at P has a finite weight.
constexpr float kMinEpsilon = 1e-4f;

/// The centre of a node's child in `octant` (x, y, z bits: the upper half on that axis).
Vec3 octant_center(const Vec3& center, float half_size, int octant) {
    const float h = 0.5f * half_size;
    return center + Vec3(octant & 1 ? h : -h, octant & 2 ? h : -h, octant & 4 ? h : -h);
}

bool finite(float x) { return std::isfinite(x); }

std::string describe(float x) {
    char text[32];
    std::snprintf(text, sizeof(text), "%g", double(x));
    return text;
}

std::string describe(const Vec3& v) {
    char text[96];
    std::snprintf(text, sizeof(text), "(%g, %g, %g)", double(v.x), double(v.y), double(v.z));
    return text;
}

/// Empty when the record can be interpolated from; otherwise what is wrong with it.
std::string record_problem(const IrradianceRecord& r) {
    if (!is_finite(r.position)) return "position " + describe(r.position) + " is not finite";
    if (!is_finite(r.normal)) return "normal " + describe(r.normal) + " is not finite";
    if (!finite(r.radius) || !(r.radius > 0.0f)) return "radius " + describe(r.radius) + " is not finite and positive";
    if (!is_finite(r.irradiance)) return "irradiance " + describe(r.irradiance) + " is not finite";
    for (const Vec3& g : r.rotation_gradient) {
        if (!is_finite(g)) return "rotation gradient " + describe(g) + " is not finite";
    }
    for (const Vec3& g : r.translation_gradient) {
        if (!is_finite(g)) return "translation gradient " + describe(g) + " is not finite";
    }
    return {};
}

}  // namespace

IrradianceCache::IrradianceCache(const Bounds3& scene_bounds, const IrradianceCacheSettings& settings)
    : settings_(settings) {
    const Vec3 center = scene_bounds.empty() ? Vec3(0.0f) : scene_bounds.center();
    const float half = scene_bounds.empty() ? 1.0f : 0.5f * max_component(scene_bounds.extent()) * 1.01f + 1e-6f;
    Node root{center, half, {}, {}};
    root.children.fill(-1);
    nodes_.push_back(std::move(root));
}

IrradianceCache::IrradianceCache(State state)
    : settings_(state.settings), records_(std::move(state.records)), nodes_(std::move(state.nodes)) {
    spheres_.reserve(records_.size());
    for (const IrradianceRecord& r : records_) spheres_.emplace_back(r.position, r.radius);
}

Expected<std::unique_ptr<IrradianceCache>> IrradianceCache::from_state(State state) {
    const float a = state.settings.accuracy;
    if (!(a > 0.0f && a <= 1.0f)) return Error{"irradiance cache accuracy " + describe(a) + " is not in (0, 1]"};
    for (size_t i = 0; i < state.records.size(); ++i) {
        if (std::string problem = record_problem(state.records[i]); !problem.empty()) {
            return Error{"irradiance record " + std::to_string(i) + ": " + problem};
        }
    }
    if (state.records.size() > size_t(std::numeric_limits<uint32_t>::max())) {
        return Error{"irradiance cache of " + std::to_string(state.records.size()) + " records (at most 2^32 - 1)"};
    }
    const std::vector<Node>& nodes = state.nodes;
    if (nodes.empty()) return Error{"irradiance cache octree has no root node"};
    if (nodes.size() > size_t(std::numeric_limits<int32_t>::max())) {
        return Error{"irradiance cache octree of " + std::to_string(nodes.size()) + " nodes (at most 2^31 - 1)"};
    }
    const Node& root = nodes[0];
    if (!is_finite(root.center) || !finite(root.half_size) || !(root.half_size > 0.0f)) {
        return Error{"octree root: centre " + describe(root.center) + ", half size " + describe(root.half_size) +
                     " (must be finite, the half size positive)"};
    }
    // Parents come before their children (insert appends a child after its parent), so one pass
    // in index order sees every node's parent first: a node without one is unreachable, a node
    // with two makes a lookup visit it twice (and a chain of them, exponentially often).
    std::vector<int32_t> parent(nodes.size(), -1);
    std::vector<uint8_t> depth(nodes.size(), 0);
    std::vector<uint8_t> filed(state.records.size(), 0);
    for (size_t i = 0; i < nodes.size(); ++i) {
        const Node& node = nodes[i];
        // Messages are built only on failure: a large cache has many nodes.
        const auto name = [&] { return "octree node " + std::to_string(i); };
        if (i > 0 && parent[i] < 0) return Error{name() + " is no other node's child"};
        for (int octant = 0; octant < 8; ++octant) {
            const int32_t child = node.children[size_t(octant)];
            if (child == -1) continue;
            const auto slot = [&] {
                return name() + " child " + std::to_string(octant) + " is node " + std::to_string(child);
            };
            if (child < 0 || size_t(child) >= nodes.size()) {
                return Error{slot() + " (the octree has " + std::to_string(nodes.size()) + " nodes)"};
            }
            if (size_t(child) <= i) return Error{slot() + ", not a later node (a cycle or a shared node)"};
            if (parent[size_t(child)] >= 0) {
                return Error{slot() + ", already the child of node " + std::to_string(parent[size_t(child)])};
            }
            if (depth[i] >= kMaxDepth) return Error{slot() + ", deeper than " + std::to_string(kMaxDepth) + " levels"};
            // The exact cube child_for makes, so that lookups descend exactly as they did.
            const Node& c = nodes[size_t(child)];
            const Vec3 center = octant_center(node.center, node.half_size, octant);
            const float half = 0.5f * node.half_size;
            if (c.center != center || c.half_size != half || !is_finite(center) || !(half > 0.0f)) {
                return Error{slot() + ", the cube at " + describe(c.center) + " with half size " +
                             describe(c.half_size) + ", not its parent's octant at " + describe(center) +
                             " with half size " + describe(half)};
            }
            parent[size_t(child)] = int32_t(i);
            depth[size_t(child)] = uint8_t(depth[i] + 1);
        }
        for (size_t k = 0; k < node.records.size(); ++k) {
            const uint32_t r = node.records[k];
            if (r >= state.records.size()) {
                return Error{name() + " files record " + std::to_string(r) + " (the cache has " +
                             std::to_string(state.records.size()) + " records)"};
            }
            if (k > 0 && r <= node.records[k - 1]) {
                return Error{name() + " files record " + std::to_string(r) + " after record " +
                             std::to_string(node.records[k - 1]) + " (must be ascending)"};
            }
            filed[r] = 1;
        }
    }
    if (const auto lost = std::find(filed.begin(), filed.end(), 0); lost != filed.end()) {
        return Error{"irradiance record " + std::to_string(lost - filed.begin()) + " is in no octree node"};
    }
    return std::unique_ptr<IrradianceCache>(new IrradianceCache(std::move(state)));
}

size_t IrradianceCache::memory_bytes() const {
    size_t bytes = sizeof(*this) + records_.capacity() * sizeof(IrradianceRecord) + nodes_.capacity() * sizeof(Node) +
                   spheres_.capacity() * sizeof(glm::vec4);
    for (const Node& node : nodes_) bytes += node.records.capacity() * sizeof(uint32_t);
    return bytes;
}

template <typename F>
void IrradianceCache::for_each_candidate(const Vec3& p, float domain_scale, float reach, F&& f) const {
    // A record is filed in the nodes of its level that its domain's bounding cube overlaps; a
    // node's records lie within its half size of it (scaled by domain_scale, plus `reach`).
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

template <typename F>
void IrradianceCache::for_each_unique_candidate(const Vec3& p, float domain_scale, float reach, F&& f) const {
    // Records filed in several nodes would be seen several times: report each once.
    thread_local std::vector<uint32_t> seen;
    seen.clear();
    for_each_candidate(p, domain_scale, reach, [&](uint32_t r) { seen.push_back(r); });
    std::sort(seen.begin(), seen.end());
    seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
    for (uint32_t r : seen) f(r);
}

template <typename F>
void IrradianceCache::for_each_on_path(const Vec3& p, F&& f) const {
    int32_t node = 0;
    while (node >= 0) {
        const Node& n = nodes_[static_cast<size_t>(node)];
        for (uint32_t r : n.records) f(r);
        const int octant = (p.x > n.center.x ? 1 : 0) | (p.y > n.center.y ? 2 : 0) | (p.z > n.center.z ? 4 : 0);
        node = n.children[static_cast<size_t>(octant)];
    }
}

double IrradianceCache::weight(const IrradianceRecord& r, const Vec3& p, const Vec3& n, float a) {
    const Vec3 offset = p - r.position;
    // Cheap rejections first: eps < a needs both |P - P_i| < a R_i and 1 - n.n_i < a^2.
    const float reach = a * r.radius;
    const float distance2 = glm::dot(offset, offset);
    if (!(distance2 < reach * reach)) return 0.0;
    const float cos_normals = std::min(1.0f, glm::dot(n, r.normal));
    if (!(1.0f - cos_normals < a * a)) return 0.0;
    const float epsilon = std::sqrt(distance2) / r.radius + safe_sqrt(1.0f - cos_normals);
    if (!(epsilon < a)) return 0.0;
    // In front of P: the record sees a different hemisphere (Ward et al. 1988).
    if (glm::dot(offset, 0.5f * (n + r.normal)) < -kFrontTolerance * r.radius) return 0.0;
    const double w = 1.0 / std::max(epsilon, kMinEpsilon) - 1.0 / a;
    return w > 0.0 ? w : 0.0;
}

template <typename F>
void IrradianceCache::for_each_weight(const Vec3& p, const Vec3& n, float accuracy_scale, F&& f) const {
    const float a = settings_.accuracy * accuracy_scale;
    // weight()'s first test, on the compact spheres: most candidates end there.
    const auto within = [&](uint32_t index) {
        const glm::vec4& s = spheres_[index];
        const Vec3 offset = p - Vec3(s);
        const float reach = a * s.w;
        return glm::dot(offset, offset) < reach * reach;
    };
    const auto add = [&](uint32_t index) {
        if (!within(index)) return;
        if (const double w = weight(records_[index], p, n, a); w > 0.0) f(index, w);
    };
    if (accuracy_scale <= 1.0f) {
        // Every record whose domain holds p is filed in the node on p's root-to-leaf path.
        for_each_on_path(p, add);
    } else {
        // Records filed in several nodes are met several times. Sorting only those that weigh
        // (a few among the candidates) visits each once, in index order, as sorting all would.
        thread_local std::vector<std::pair<uint32_t, double>> weighed;
        weighed.clear();
        for_each_candidate(p, accuracy_scale, 0.0f, [&](uint32_t index) {
            if (!within(index)) return;
            if (const double w = weight(records_[index], p, n, a); w > 0.0) weighed.emplace_back(index, w);
        });
        std::sort(weighed.begin(), weighed.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
        for (size_t i = 0; i < weighed.size(); ++i)
            if (i == 0 || weighed[i].first != weighed[i - 1].first) f(weighed[i].first, weighed[i].second);
    }
}

bool IrradianceCache::interpolate(const Vec3& p, const Vec3& n, Color* irradiance, float accuracy_scale) const {
    if (records_.empty()) return false;
    double weight_sum = 0.0;
    DVec3 sum(0.0);
    for_each_weight(p, n, accuracy_scale, [&](uint32_t index, double w) {
        const IrradianceRecord& r = records_[index];
        Color e = r.irradiance;
        if (settings_.gradients) {
            const Vec3 axis = glm::cross(r.normal, n);
            const Vec3 offset = p - r.position;
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

bool IrradianceCache::weigh_records(const Vec3& p, const Vec3& n, float accuracy_scale,
                                    std::vector<RecordWeight>* out) const {
    out->clear();
    if (records_.empty()) return false;
    double weight_sum = 0.0;
    for_each_weight(p, n, accuracy_scale, [&](uint32_t index, double w) {
        out->push_back({index, w});
        weight_sum += w;
    });
    if (!(weight_sum > 0.0)) return false;
    for (RecordWeight& r : *out) r.weight /= weight_sum;
    return true;
}

int32_t IrradianceCache::child_for(int32_t node_index, const Vec3& p) {
    // The node's geometry by value (not the node: that would copy its record list, and push_back
    // below may move the nodes).
    const Vec3 center = nodes_[static_cast<size_t>(node_index)].center;
    const float half_size = nodes_[static_cast<size_t>(node_index)].half_size;
    const int octant = (p.x > center.x ? 1 : 0) | (p.y > center.y ? 2 : 0) | (p.z > center.z ? 4 : 0);
    int32_t child = nodes_[static_cast<size_t>(node_index)].children[static_cast<size_t>(octant)];
    if (child < 0) {
        Node n{octant_center(center, half_size, octant), 0.5f * half_size, {}, {}};
        n.children.fill(-1);
        child = static_cast<int32_t>(nodes_.size());
        nodes_.push_back(std::move(n));
        nodes_[static_cast<size_t>(node_index)].children[static_cast<size_t>(octant)] = child;
    }
    return child;
}

bool IrradianceCache::accepts(const IrradianceRecord& record) {
    return record.radius > 0.0f && std::isfinite(record.radius) && is_finite(record.irradiance);
}

void IrradianceCache::neighbour_candidates(const IrradianceRecord& record, std::vector<uint32_t>* out) const {
    out->clear();
    // Every record whose domain overlaps the new one's is filed in a node within reach.
    for_each_unique_candidate(record.position, 1.0f, settings_.accuracy * record.radius, [&](uint32_t j) {
        if (may_neighbour(settings_.accuracy, record, records_[j])) out->push_back(j);
    });
}

void IrradianceCache::insert(IrradianceRecord record, float min_radius) {
    if (!accepts(record)) return;
    std::vector<uint32_t> candidates;
    neighbour_candidates(record, &candidates);
    insert(record, min_radius, candidates);
}

void IrradianceCache::insert(IrradianceRecord record, float min_radius, std::span<const uint32_t> candidates) {
    const float a = settings_.accuracy;
    if (!accepts(record)) return;
    // Neighbour clamping: R_i <= R_j + |P_i - P_j| for every record whose domain overlaps.
    const uint32_t new_index = static_cast<uint32_t>(records_.size());
    thread_local std::vector<uint32_t> neighbours;
    neighbours.clear();
    for (uint32_t j : candidates) {
        if (may_neighbour(a, record, records_[j])) neighbours.push_back(j);
    }
    for (uint32_t j : neighbours) {
        const float d = glm::length(record.position - records_[j].position);
        record.radius = std::max(min_radius, std::min(record.radius, records_[j].radius + d));
    }
    for (uint32_t j : neighbours) {
        IrradianceRecord& r = records_[j];
        r.radius = std::min(r.radius, record.radius + glm::length(record.position - r.position));
        spheres_[j].w = r.radius;
    }
    // The level whose nodes' half size h satisfies validity <= h < 2 validity; the record goes in
    // every node of that level its domain's bounding cube overlaps (at most 8), so a lookup only
    // needs the nodes on its own root-to-leaf path.
    const float validity = a * record.radius;
    int level = 0;
    float half = nodes_[0].half_size;
    while (0.5f * half >= validity && level < kMaxDepth) {
        half *= 0.5f;
        ++level;
    }
    const Vec3 lower = record.position - Vec3(validity), upper = record.position + Vec3(validity);
    bool filed = false;
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3 q((corner & 1) ? upper.x : lower.x, (corner & 2) ? upper.y : lower.y, (corner & 4) ? upper.z : lower.z);
        if (max_component(glm::abs(q - nodes_[0].center)) > nodes_[0].half_size) continue;  // outside the root
        int32_t node = 0;
        for (int l = 0; l < level; ++l) node = child_for(node, q);
        std::vector<uint32_t>& list = nodes_[static_cast<size_t>(node)].records;
        if (list.empty() || list.back() != new_index) list.push_back(new_index);
        filed = true;
    }
    if (!filed) nodes_[0].records.push_back(new_index);  // wholly outside the root: the root keeps it
    records_.push_back(record);
    spheres_.emplace_back(record.position, record.radius);
}

}  // namespace photond
