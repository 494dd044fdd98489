// A bounding-volume hierarchy over the lights that have a position (point, spot, emissive
// triangles), for next-event estimation with many lights: from a shading point it picks a light
// by walking down the tree, at each node choosing a child in proportion to an importance that
// bounds what the child's lights can send to that point (their intensity, their distance, and
// the cone of directions they emit into). This is the light BVH of pbrt-v4 (`BVHLightSampler`,
// after Conty Estevez and Kulla, "Importance sampling of many lights with adaptive tree
// splitting", 2018), without the receiver's normal and without adaptive splitting.
//
// The probability of a light is the product of the child choices on its path, which pmf()
// recomputes exactly (same expressions, same order), so that multiple importance sampling sees
// the very pdf the sample was drawn with. Lights of zero intensity are left out (never picked).
//
// Immutable after construction; sample() and pmf() are pure functions of their arguments and
// safe to call from any number of threads.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace photond {

/// What the tree knows of one light, or of the lights under a node: where they are, how strong
/// they are and which directions they emit into. The emitted directions lie within the cone of
/// half-angle theta_o around w (normals of the emitting faces, or a spot's axis), each face
/// emitting up to theta_e beyond its normal (pi/2 for a Lambertian face); two-sided: the cones
/// around -w as well.
struct LightBounds {
    Bounds3 bounds;
    /// The largest radiant intensity the lights send in any direction (W/sr), summed: I for
    /// point and spot lights, L * A for an emitting triangle.
    float intensity = 0.0f;
    Vec3 w{0.0f, 0.0f, 1.0f};
    float cos_theta_o = 1.0f;
    float cos_theta_e = 0.0f;
    bool two_sided = false;
};

/// The bounds of two sets of lights together (bounding box, cone around both cones, summed
/// intensity).
LightBounds light_bounds_union(const LightBounds& a, const LightBounds& b);

/// An upper estimate of the irradiance the lights in `b` can send to point p, up to a common
/// factor (pbrt-v4 `LightBounds::Importance` without the receiver's normal): intensity * cos(theta')
/// / d^2, where d is the distance to the centre of the bounds (at least half their diagonal) and
/// theta' the smallest angle between the emission cone and the directions from the bounds to p,
/// zero when theta' is beyond theta_e (no light in `b` can reach p).
float light_importance(const LightBounds& b, const Vec3& p);

/// LightBounds in the form light_importance reads at every node: centre, bounding radius, the
/// cone's sine. Derived once per node when the tree is built.
struct ImportanceBounds {
    Vec3 center{0.0f};
    float radius2 = 0.0f;  // squared radius of the bounding sphere (half the box's diagonal)
    float radius = 0.0f;
    float intensity = 0.0f;
    Vec3 w{0.0f, 0.0f, 1.0f};
    float cos_theta_o = 1.0f;
    float sin_theta_o = 0.0f;
    float cos_theta_e = 0.0f;
    bool two_sided = false;

    explicit ImportanceBounds(const LightBounds& b);
    ImportanceBounds() = default;
};
float light_importance(const ImportanceBounds& b, const Vec3& p);

class LightTree {
public:
    LightTree() = default;
    /// Builds the tree over `lights`; a light's index is its position in the span.
    explicit LightTree(std::span<const LightBounds> lights);

    bool empty() const { return nodes_.empty(); }
    /// Lights in the tree (those with positive intensity).
    size_t light_count() const { return light_count_; }
    size_t node_count() const { return nodes_.size(); }
    int depth() const { return depth_; }

    /// Picks a light for shading point p with u in [0, 1); writes its probability. Nothing when
    /// no light of the tree can reach p.
    std::optional<uint32_t> sample(const Vec3& p, float u, float* pmf) const;
    /// The probability with which sample(p, ...) picks `light` (0 for a light not in the tree).
    float pmf(const Vec3& p, uint32_t light) const;

private:
    struct Node {
        ImportanceBounds bounds;
        uint32_t second_child = 0;  // interior nodes: the first child is the next node
        uint32_t light = 0;         // leaves: the light's index
        bool leaf = false;
    };
    /// Builds the subtree over lights[begin, end) (indices into `all`) into nodes
    /// [index, index + 2 (end - begin) - 1), depth first (a node, its first subtree, its second),
    /// large subtrees in parallel; returns the depth of its deepest leaf.
    int build(std::span<const LightBounds> all, std::vector<uint32_t>& lights, size_t begin, size_t end,
              uint32_t index, uint64_t trail, int depth);
    /// The probabilities of a node's two children at p (both zero: neither can reach p).
    void child_probabilities(const Node& node, uint32_t index, const Vec3& p, float* p0, float* p1) const;

    std::vector<Node> nodes_;
    /// Per light: the path from the root to its leaf, bit i the choice at depth i (1: second
    /// child); kNotInTree for lights left out.
    std::vector<uint64_t> trails_;
    size_t light_count_ = 0;
    int depth_ = 0;
};

}  // namespace photond
