// Every light of a scene in one set: punctual lights (point, spot, directional) and emissive
// triangles, chosen by power. Immutable after construction; safe to share between threads.
#pragma once

#include <optional>
#include <vector>

#include "core/math/frame.h"
#include "core/math/sampling.h"
#include "core/scene/interaction.h"
#include "core/scene/scene.h"

namespace photond {

enum class LightKind : uint8_t { Point, Spot, Directional, Triangle };

/// A light sample seen from a shading point (next-event estimation).
struct LightSample {
    Vec3 wi{0.0f};            // unit, from the shading point towards the light
    float distance = 0.0f;    // to the sampled light point; infinity for directional lights
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
    explicit LightSet(const Scene& scene);

    bool empty() const { return lights_.empty() || selection_.empty(); }
    size_t size() const { return lights_.size(); }
    LightKind kind(uint32_t light) const { return lights_[light].kind; }
    /// Radiant power of one light (W), and of all lights together.
    Color power(uint32_t light) const { return lights_[light].power; }
    Color total_power() const { return total_power_; }
    float selection_probability(uint32_t light) const { return selection_.probability(light); }

    /// Picks a light by power and a point on it as seen from p.
    std::optional<LightSample> sample_incident(const Vec3& p, float u_select, const Vec2& u) const;

    /// Solid-angle pdf with which sample_incident(p, ...) would have produced `light_point` on the
    /// emissive triangle hit by a ray from p (for multiple importance sampling).
    float pdf_incident_triangle(uint32_t triangle, const Vec3& p, const Vec3& light_point) const;

    /// Radiance an emissive surface sends towards wo (front face only unless double-sided).
    Color emitted_radiance(const SurfaceInteraction& si, const Vec3& wo) const;

    /// Samples a photon's origin and direction from the emission distribution of a light chosen
    /// by power: point (uniform sphere), spot (uniform cone), directional (a disc covering the
    /// scene's bounds), emissive triangles (uniform by area, cosine-weighted direction).
    /// The random numbers by value: references would keep a caller's in memory.
    std::optional<EmissionSample> sample_emission(float u_select, Vec2 u_position, Vec2 u_direction) const;

    /// Spot light angular falloff of KHR_lights_punctual (quadratic in the cosine).
    static float spot_falloff(const PunctualLight& light, float cos_angle);
    /// The same falloff from 1 - cos(angle to the axis), precise for narrow cones.
    static float spot_falloff_from_axis(const PunctualLight& light, float one_minus_cos);

private:
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
    /// mean of a grid of points on it, read at the mip level where the triangle covers about 256
    /// texels (levels are box means, so no emitting texel is missed between the points).
    Color mean_emissive_texel(uint32_t triangle) const;
    const Scene* scene_;
    std::vector<Entry> lights_;
    std::vector<int32_t> light_of_triangle_;  // -1 when the triangle emits nothing
    DiscreteDistribution selection_;
    Color total_power_{0.0f};
    Vec3 scene_center_{0.0f};
    float scene_radius_ = 0.0f;
};

}  // namespace photond
