#include "core/light/emission_focus.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/math/frame.h"
#include "core/math/sampling.h"
#include "core/scene/position_weld.h"
#include "core/scene/scene.h"

namespace photond {
namespace {

/// The sphere around the bounding box's centre that holds every vertex of `triangles`, widened by
/// `margin`.
FocusSphere sphere_of(const Scene& scene, std::span<const uint32_t> triangles, float margin) {
    Bounds3 bounds;
    for (uint32_t t : triangles)
        for (uint32_t v : {scene.triangles[t].x, scene.triangles[t].y, scene.triangles[t].z}) bounds.extend(scene.positions[v]);
    const Vec3 center = bounds.center();
    float radius2 = 0.0f;
    for (uint32_t t : triangles)
        for (uint32_t v : {scene.triangles[t].x, scene.triangles[t].y, scene.triangles[t].z})
            radius2 = std::max(radius2, glm::dot(scene.positions[v] - center, scene.positions[v] - center));
    return {center, 1.001f * std::sqrt(radius2) + margin};
}

Vec3 centroid(const Scene& scene, uint32_t t) {
    const glm::uvec3& v = scene.triangles[t];
    return (scene.positions[v.x] + scene.positions[v.y] + scene.positions[v.z]) * (1.0f / 3.0f);
}

/// One sphere as seen from an emission point: its cone and its weight in the choice.
struct Cone {
    Vec3 axis{0.0f};
    float cos_max = -1.0f;  // -1: the point is inside, every direction (axis unused)
    float solid_angle = 0.0f;
    float weight = 0.0f;
};

Cone cone_of(const FocusSphere& sphere, const EmitterView& emitter) {
    Cone cone;
    const bool one_sided = glm::dot(emitter.normal, emitter.normal) > 0.0f;
    const Vec3 to_center = sphere.center - emitter.origin;
    const float d2 = glm::dot(to_center, to_center);
    const float r2 = sphere.radius * sphere.radius;
    if (d2 <= r2) {  // every direction: no axis
        cone.solid_angle = 4.0f * kPi;
        cone.weight = cone.solid_angle;
        return cone;
    }
    const float d = std::sqrt(d2);
    cone.axis = to_center / d;
    const float sin2 = r2 / d2;
    const float sin_max = std::sqrt(sin2);
    cone.cos_max = std::sqrt(1.0f - sin2);
    // 1 - cos from sin^2, exact for the narrow cones of far spheres.
    cone.solid_angle = 2.0f * kPi * (sin2 / (1.0f + cone.cos_max));
    // The largest cosine between a direction of the cone and `axis`: 1 if axis lies in it, else
    // that of the cone's edge nearest it, cos(theta_axis - alpha).
    const auto largest_cosine = [&](const Vec3& axis) {
        const float cos_axis = glm::dot(axis, cone.axis);
        if (cos_axis >= cone.cos_max) return 1.0f;
        const float sin_axis = std::sqrt(std::max(0.0f, 1.0f - cos_axis * cos_axis));
        return cos_axis * cone.cos_max + sin_axis * sin_max;
    };
    float weight = cone.solid_angle;
    if (emitter.cone_cos > -1.0f && largest_cosine(emitter.cone_axis) < emitter.cone_cos) weight = 0.0f;
    if (one_sided) weight *= std::max(0.0f, largest_cosine(emitter.normal));
    cone.weight = weight;
    return cone;
}

bool inside(const Cone& cone, const Vec3& direction) {
    return cone.cos_max <= -1.0f || glm::dot(direction, cone.axis) >= cone.cos_max;
}

/// The objects among `triangles`: sets of triangles joined through shared vertex positions
/// (compared exactly, so that a UV seam's duplicated vertices do not cut a sphere in two). Each
/// object lists its triangles in their order in `triangles`; objects in order of their first.
std::vector<std::vector<uint32_t>> objects_of(const Scene& scene, std::span<const uint32_t> triangles) {
    std::vector<uint32_t> parent(triangles.size());
    for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
    const auto root = [&](uint32_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    PositionWelder welder;
    welder.reserve(triangles.size());
    std::vector<uint32_t> first_at;  // welded position -> the first triangle with a corner there
    for (uint32_t i = 0; i < triangles.size(); ++i) {
        const glm::uvec3& tri = scene.triangles[triangles[i]];
        for (uint32_t v : {tri.x, tri.y, tri.z}) {
            const uint32_t position = welder.id(scene.positions[v]);
            if (position == first_at.size()) {
                first_at.push_back(i);
                continue;
            }
            const uint32_t a = root(i), b = root(first_at[position]);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
    }
    std::vector<std::vector<uint32_t>> objects;
    std::vector<uint32_t> object_of_root(triangles.size(), UINT32_MAX);
    for (uint32_t i = 0; i < triangles.size(); ++i) {
        uint32_t& object = object_of_root[root(i)];
        if (object == UINT32_MAX) {
            object = static_cast<uint32_t>(objects.size());
            objects.emplace_back();
        }
        objects[object].push_back(triangles[i]);
    }
    return objects;
}

}  // namespace

EmissionFocus focus_on_triangles(const Scene& scene, std::span<const uint32_t> triangles) {
    EmissionFocus focus;
    if (triangles.empty()) return focus;
    const float margin = 1e-6f * scene.bounds.radius();
    const FocusSphere all = sphere_of(scene, triangles, margin);
    focus.center = all.center;
    focus.radius = all.radius;

    // Objects are kept whole while a group holds more than one: a split by triangles through a
    // round object leaves two halves each about as wide as the object.
    const std::vector<std::vector<uint32_t>> objects = objects_of(scene, triangles);
    std::vector<FocusSphere> object_spheres;
    object_spheres.reserve(objects.size());
    for (const std::vector<uint32_t>& object : objects) object_spheres.push_back(sphere_of(scene, object, margin));

    struct Group {
        std::vector<uint32_t> objects;    // more than one: split between objects
        std::vector<uint32_t> triangles;  // one object or part of one: split between triangles
        FocusSphere sphere;
        bool final = false;  // splitting it would not narrow it
    };
    const auto group_of_objects = [&](std::vector<uint32_t> ids) {
        Group g;
        if (ids.size() == 1) {
            g.triangles = objects[ids[0]];
            g.sphere = object_spheres[ids[0]];
            return g;
        }
        for (uint32_t id : ids) g.triangles.insert(g.triangles.end(), objects[id].begin(), objects[id].end());
        g.sphere = sphere_of(scene, g.triangles, margin);
        g.objects = std::move(ids);
        return g;
    };
    std::vector<uint32_t> every_object(objects.size());
    for (uint32_t i = 0; i < every_object.size(); ++i) every_object[i] = i;
    std::vector<Group> groups;
    groups.push_back(group_of_objects(std::move(every_object)));
    while (groups.size() < kMaxFocusSpheres) {
        // The widest group that may still split (ties: the first, so the cover is deterministic).
        Group* widest = nullptr;
        for (Group& g : groups)
            if (!g.final && g.triangles.size() > 1 && (!widest || g.sphere.radius > widest->sphere.radius)) widest = &g;
        if (!widest) break;
        Group left, right;
        if (widest->objects.size() > 1) {
            // Objects by their spheres' centres: at the middle of their extent along its longest
            // axis, or at the median where one side would be empty.
            Bounds3 centers;
            for (uint32_t id : widest->objects) centers.extend(object_spheres[id].center);
            const Vec3 extent = centers.extent();
            const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
            std::vector<uint32_t> ids = widest->objects;
            const float mid = centers.center()[axis];
            auto middle = std::stable_partition(ids.begin(), ids.end(),
                                                [&](uint32_t id) { return object_spheres[id].center[axis] < mid; });
            if (middle == ids.begin() || middle == ids.end()) {
                middle = ids.begin() + static_cast<std::ptrdiff_t>(ids.size() / 2);
                std::nth_element(ids.begin(), middle, ids.end(), [&](uint32_t a, uint32_t b) {
                    const float ca = object_spheres[a].center[axis], cb = object_spheres[b].center[axis];
                    return ca < cb || (ca == cb && a < b);
                });
            }
            left = group_of_objects(std::vector<uint32_t>(ids.begin(), middle));
            right = group_of_objects(std::vector<uint32_t>(middle, ids.end()));
            // Objects one inside the other (a liquid in its glass): keep them together.
            if (!(std::max(left.sphere.radius, right.sphere.radius) < widest->sphere.radius)) {
                widest->final = true;
                continue;
            }
        } else {
            // Within one object: at the median of its triangles' centroids along their longest
            // axis, kept only where that narrows it (a long rod, not a ball).
            Bounds3 centroids;
            for (uint32_t t : widest->triangles) centroids.extend(centroid(scene, t));
            const Vec3 extent = centroids.extent();
            const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
            std::vector<uint32_t> part = widest->triangles;
            const auto middle = part.begin() + static_cast<std::ptrdiff_t>(part.size() / 2);
            std::nth_element(part.begin(), middle, part.end(), [&](uint32_t a, uint32_t b) {
                const float ca = centroid(scene, a)[axis], cb = centroid(scene, b)[axis];
                return ca < cb || (ca == cb && a < b);
            });
            right.triangles.assign(middle, part.end());
            part.erase(middle, part.end());
            left.triangles = std::move(part);
            left.sphere = sphere_of(scene, left.triangles, margin);
            right.sphere = sphere_of(scene, right.triangles, margin);
            // Halves of one round object are each wider than the whole: keep it whole.
            if (!(std::max(left.sphere.radius, right.sphere.radius) < widest->sphere.radius)) {
                widest->final = true;
                continue;
            }
        }
        *widest = std::move(left);
        groups.push_back(std::move(right));
    }
    focus.spheres.reserve(groups.size());
    for (const Group& g : groups) focus.spheres.push_back(g.sphere);
    return focus;
}

FocusedDirection sample_focused_direction(const EmissionFocus& focus, const EmitterView& emitter, float u_choice, Vec2 u) {
    std::array<Cone, kMaxFocusSpheres> cones;
    const size_t count = std::min(focus.spheres.size(), kMaxFocusSpheres);
    float total = 0.0f;
    for (size_t i = 0; i < count; ++i) {
        cones[i] = cone_of(focus.spheres[i], emitter);
        total += cones[i].weight;
    }
    FocusedDirection out;
    if (!(total > 0.0f)) return out;
    if (total >= emitter.measure) {
        out.outcome = FocusOutcome::plain;
        return out;
    }
    // The sphere: the first whose cumulative weight passes u_choice * total (the last with weight
    // if rounding leaves it short).
    const float target = u_choice * total;
    size_t chosen = count;
    float cumulative = 0.0f;
    for (size_t i = 0; i < count; ++i) {
        if (cones[i].weight <= 0.0f) continue;
        chosen = i;
        cumulative += cones[i].weight;
        if (target < cumulative) break;
    }
    const Cone& cone = cones[chosen];
    out.direction = cone.cos_max <= -1.0f ? sample_uniform_sphere(u)
                                          : Frame(cone.axis).to_world(sample_uniform_cone(u, cone.cos_max));
    // The mixture's density; the chosen sphere counts whatever rounding did to its cone's edge.
    double pdf = 0.0;
    for (size_t i = 0; i < count; ++i) {
        if (cones[i].weight <= 0.0f || (i != chosen && !inside(cones[i], out.direction))) continue;
        pdf += double(cones[i].weight) / (double(total) * double(cones[i].solid_angle));
    }
    out.pdf = static_cast<float>(pdf);
    out.outcome = out.pdf > 0.0f && is_finite(out.direction) ? FocusOutcome::aimed : FocusOutcome::nothing;
    return out;
}

}  // namespace photond
