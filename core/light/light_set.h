// Every light of a scene in one set: punctual lights (point, spot, directional, soft sun),
// emissive triangles and the environment. Photons leave lights chosen by power; next-event
// estimation chooses by the light tree (core/light/light_tree.h) or by power (LightSelection).
// Immutable after construction; safe to share between threads.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "core/light/emission_focus.h"
#include "core/light/environment_light.h"
#include "core/light/light_tree.h"
#include "core/math/frame.h"
#include "core/math/sampling.h"
#include "core/scene/interaction.h"
#include "core/scene/scene.h"

namespace photond {

enum class LightKind : uint8_t { Point, Spot, Directional, Triangle, Environment };

/// How next-event estimation picks the light it samples from a shading point.
/// Tree: the distant lights (directional, soft suns, the environment) by power as one group
/// against the lights with a position, those by the light tree from the shading point (their
/// intensity, distance and orientation). Power: every light by its power alone, wherever the
/// point is (one global distribution), as photon emission picks them.
enum class LightSelection : uint8_t { Tree, Power };
/// A light sample seen from a shading point (next-event estimation).
struct LightSample {
    Vec3 wi{0.0f};            // unit, from the shading point towards the light
    float distance = 0.0f;    // to the sampled light point; infinity for distant lights
    Color radiance{0.0f};     // incident radiance along -wi (intensity / d^2 for point lights)
    float pdf = 0.0f;         // solid-angle pdf incl. light choice; delta lights: choice probability
    bool is_delta = false;
    Vec3 point{0.0f};         // the light point (unused for directional lights)
    Vec3 normal{0.0f};        // emitter normal (triangles), for the shadow ray's far offset
};

/// A photon leaving a light: origin, direction and its share of the total power. The flux
/// weight's expectation over samples is the scene's total emitted power, so each of N emitted
/// photons carries flux_weight / N.
struct EmissionSample {
    Vec3 origin{0.0f};
    Vec3 direction{0.0f, 0.0f, 1.0f};
    Vec3 normal{0.0f};     // emitter normal at the origin (zero for point lights)
    Color flux_weight{0.0f};
    uint32_t light = 0;    // index into LightSet
};

class LightSet {
public:
    explicit LightSet(const Scene& scene, LightSelection selection = LightSelection::Tree);
    /// The scene's lights with `environment` in place of the scene's own (null: none); it must
    /// outlive the set.
    LightSet(const Scene& scene, const Environment* environment, LightSelection selection = LightSelection::Tree);
    /// The same with the scene's own lights (points, spots, suns, emitting triangles) and their
    /// light tree taken from `same_scene`, a set of the same scene and selection whose
    /// environment alone differs: they are the same, and a scene of a million emitting
    /// triangles takes seconds to make them.
    LightSet(const Scene& scene, const Environment* environment, LightSelection selection,
             const LightSet& same_scene);

    bool empty() const { return lights_.empty() || selection_.empty(); }
    size_t size() const { return lights_.size(); }
    LightKind kind(uint32_t light) const { return lights_[light].kind; }
    /// Radiant power of one light (W), and of all lights together.
    Color power(uint32_t light) const { return lights_[light].power; }
    Color total_power() const { return total_power_; }
    /// The probability of a light for photon emission (by power).
    float selection_probability(uint32_t light) const { return selection_.probability(light); }
    /// How sample_incident picks lights, and the tree it uses (empty with Power).
    LightSelection selection() const { return selection_mode_; }
    const LightTree& tree() const { return *tree_; }
    /// The probability with which sample_incident(p, ...) picks `light`.
    float incident_choice_probability(uint32_t light, const Vec3& p) const;

    /// Picks a light (LightSelection) and a point on it as seen from p.
    std::optional<LightSample> sample_incident(const Vec3& p, float u_select, const Vec2& u) const;

    /// Solid-angle pdf with which sample_incident(p, ...) would have produced `light_point` on the
    /// emissive triangle hit by a ray from p (for multiple importance sampling).
    float pdf_incident_triangle(uint32_t triangle, const Vec3& p, const Vec3& light_point) const;

    /// Radiance an emissive surface sends towards wo (front face only unless double-sided).
    Color emitted_radiance(const SurfaceInteraction& si, const Vec3& wo) const;

    /// Whether a ray that leaves the scene can meet light: an environment or a soft sun (the
    /// distant lights that are not delta lights).
    bool has_distant_area_lights() const { return !distant_area_lights_.empty(); }
    /// Radiance arriving along a ray that left the scene in direction `d` (unit), from every
    /// distant area light. With bsdf_pdf > 0 (the ray was BSDF-sampled with that solid-angle
    /// pdf) each light's share is weighted by the power heuristic against sample_incident; with
    /// bsdf_pdf = 0 (camera rays, delta bounces) it is taken whole.
    Color escaped_radiance(const Vec3& d, float bsdf_pdf) const;
    /// The environment, when the scene has one.
    const EnvironmentLight* environment() const { return environment_ ? &*environment_ : nullptr; }

    /// Samples a photon's origin and direction from the emission distribution of a light chosen
    /// by power: point (uniform sphere), spot (uniform cone), directional (parallel from a disc
    /// covering the scene's bounds; a soft sun's directions uniform in its cone), emissive
    /// triangles (uniform by area, cosine-weighted direction), the environment (directions by
    /// its importance distribution, parallel from a disc of the scene's bounding sphere).
    /// The random numbers by value: references would keep a caller's in memory.
    /// With `focus` (core/light/emission_focus.h), parallel photons start on the discs of the
    /// focus spheres, one chosen by its area with `u_focus` (or on the disc of the casters'
    /// bounding sphere where that is smaller; still outside the scene's bounding sphere), and
    /// their flux is scaled by the reciprocal of their density; photons from a position take a direction towards
    /// the focus spheres (sample_focused_direction, choosing a sphere by `u_focus`) and carry the
    /// light's density of it over the one it was drawn with. Unbiased for every path whose first
    /// hit lies in a focus sphere.
    std::optional<EmissionSample> sample_emission(float u_select, Vec2 u_position, Vec2 u_direction,
                                                  const EmissionFocus* focus = nullptr, float u_focus = 0.0f) const;

    /// Spot light angular falloff of KHR_lights_punctual (quadratic in the cosine).
    static float spot_falloff(const PunctualLight& light, float cos_angle);
    /// The same falloff from 1 - cos(angle to the axis), precise for narrow cones.
    static float spot_falloff_from_axis(const PunctualLight& light, float one_minus_cos);
    /// The radiance of a soft sun: its irradiance over pi sin^2 of its angular radius.
    static Color sun_radiance(const PunctualLight& light);

private:
    /// The solid-angle pdf with which sample_incident picks direction d from distant area
    /// light `light` (choice included), and the radiance it sends along d.
    float distant_pdf(uint32_t light, const Vec3& d, Color* radiance) const;
    /// The origin of a parallel photon travelling in `direction`: a point of a disc
    /// perpendicular to it, of the scene's bounding radius around its centre (or of `focus`,
    /// when given: the discs of its spheres, one chosen by `u_focus`, where they are smaller
    /// together than its bounding sphere's), moved back outside the scene. Writes the
    /// reciprocal of the point's density over the plane as a share of the scene's disc.
    Vec3 parallel_origin(const Vec3& direction, Vec2 u, const EmissionFocus* focus, float u_focus,
                         float* area_ratio) const;
    /// The light sample_incident samples from p, and its choice probability.
    std::optional<uint32_t> choose_incident(const Vec3& p, float u_select, float* choice_pdf) const;
    /// The light tree over the lights with a position (point, spot, triangles), and the
    /// distribution over the distant lights by power with the tree's lights as its last entry;
    /// the tree is `same_tree` when given (a set of the same scene lights built it).
    void build_tree(std::shared_ptr<const LightTree> same_tree);

    struct Entry {
        LightKind kind;
        uint32_t index;  // into Scene::lights or Scene::triangles
        Color power;
        float area;      // triangles
        /// sample_emission's flux weight, which does not depend on the sample (it already
        /// includes the choice probability); unused for spot lights, whose falloff varies.
        Color emission_weight{0.0f};
        /// Triangles: the shading frames of the emitting faces (the back one is used only when
        /// double-sided), built once rather than at every photon.
        Frame front_frame, back_frame;
        /// Triangles: the first vertex and the edges from it to the other two, so that a sampled
        /// point needs no vertex lookups (the same floats as from the vertices).
        Vec3 corner{0.0f}, edge1{0.0f}, edge2{0.0f};
        /// Triangles: the point at barycentric coordinates b of the second and third vertices.
        Vec3 point_at(Vec2 b) const { return corner + b.x * edge1 + b.y * edge2; }
        bool double_sided = false;
        /// Triangles: the material has an emissive texture, read at each sampled point.
        bool textured = false;
    };
    /// The emissive texture's value (without the factor) on triangle light `e` at barycentrics b.
    Color emissive_texel(const Entry& e, Vec2 b) const;
    /// Mean emissive texture value over a triangle (without the factor), for its power: the
    /// mean of a grid of points on it, read at the mip level where the triangle covers at most
    /// about 16 texels (levels are box means, so no emitting texel is missed between the points).
    Color mean_emissive_texel(uint32_t triangle) const;
    LightSet(const Scene& scene, const Environment* environment, LightSelection selection, const LightSet* same_scene);
    /// The scene's punctual lights and emitting triangles (before the environment).
    void add_scene_lights(const Scene& scene);
    /// The environment's entry, the choice by power, the flux weights and the tree (taken from
    /// `same_scene` when given).
    void finish(const Environment* environment, const LightSet* same_scene);
    /// The scene's own lights: lights_ before the environment's entry, which comes last.
    size_t scene_light_count() const { return lights_.size() - (environment_ ? 1 : 0); }
    const Scene* scene_;
    std::vector<Entry> lights_;
    std::vector<int32_t> light_of_triangle_;  // -1 when the triangle emits nothing
    std::vector<uint32_t> distant_area_lights_;  // the environment and soft suns, with power
    std::optional<EnvironmentLight> environment_;
    DiscreteDistribution selection_;
    LightSelection selection_mode_ = LightSelection::Tree;
    std::shared_ptr<const LightTree> tree_ = std::make_shared<const LightTree>();  // shared by sets of one scene
    std::vector<uint32_t> tree_lights_;        // the tree's light i is lights_[tree_lights_[i]]
    std::vector<int32_t> tree_index_of_light_;  // -1: a distant light
    DiscreteDistribution tree_or_distant_;      // lights_.size() + 1 entries; the last: the tree
    bool tree_only_ = false;                    // no distant light has power: the tree's share is 1
    Color total_power_{0.0f};
    Vec3 scene_center_{0.0f};
    float scene_radius_ = 0.0f;
};

}  // namespace photond
