// Where photons meant for the caustic map alone are aimed: a projection map (Jensen 2001,
// section 5.3) made of spheres around the caustic casters (RenderScene::caustic_casters).
//
// A caustic path (L S+ D) starts with a bounce off a caster, so a photon traced for the caustic
// map alone only needs the directions in which a caster lies. Emitted over the light's whole
// distribution, nearly all of them miss (a small emitter beside glass spheres: 4.5 M photons
// emitted for 50,000 stored). Instead:
//   - parallel photons (directional lights, suns, the environment) start on the disc, across
//     their direction, of one of the spheres that cover the casters (`spheres`), chosen in
//     proportion to its area, uniform in it, and carry the reciprocal of the discs' density
//     there, covering / (sum of the discs' areas) (LightSet::sample_emission); on the disc of
//     the casters' bounding sphere (`center`, `radius`) where that is smaller than the discs;
//   - photons from a position (points, spots, emissive triangles) take a direction in the cone of
//     one of up to kMaxFocusSpheres spheres that cover the casters (`spheres`), chosen in
//     proportion to its solid angle times the emitter's largest cosine over it (none behind a
//     one-sided emitter or outside a spot's cone), uniform in it, with the mixture's density
//       p(w) = sum_c P_c [w in cone_c] / Omega_c,
//     and carry the light's own density of w over p(w): unbiased for every path whose first hit
//     lies in one of the spheres, which is every caustic path. Where the spheres' weights add
//     up to as much as the light's own distribution, it emits as usual (FocusOutcome::plain).
// A light's density over p(w) is at most its weights' total over its measure, so an aimed photon
// never carries more flux than an unaimed one.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/math/vec.h"

namespace photond {

struct Scene;

struct FocusSphere {
    Vec3 center{0.0f};
    float radius = 0.0f;
};

/// Spheres that cover the casters after kMaxFocusSpheres splits at most.
inline constexpr size_t kMaxFocusSpheres = 32;

struct EmissionFocus {
    /// The bounding sphere of every caster: parallel photons are aimed at it where its disc is
    /// smaller than the spheres' discs together.
    Vec3 center{0.0f};
    float radius = 0.0f;
    /// Spheres that together cover every caster: photons are aimed at them. Empty: photons from
    /// a position leave by the light's own distribution, parallel ones from the bounding disc.
    std::vector<FocusSphere> spheres;
};

/// The focus of `triangles` of the scene: their bounding sphere, and a cover of at most
/// kMaxFocusSpheres spheres built by splitting the group of widest sphere: one of several objects
/// (triangles joined through shared vertex positions) between them, at the middle of their
/// spheres' centres along the longest axis (the median where one side would be empty); one
/// object at the median of its triangles' centroids; either only as long as that narrows it.
/// Each sphere is a little larger than its triangles, so that rounding cannot shave photons off
/// their edges.
EmissionFocus focus_on_triangles(const Scene& scene, std::span<const uint32_t> triangles);

/// How a light with a position sees the focus: where it emits from and what it covers.
struct EmitterView {
    Vec3 origin{0.0f};
    /// A one-sided emitter's unit normal: spheres wholly behind it are never chosen and the others
    /// are weighted by their largest cosine with it. Zero: none (points, spots, two-sided).
    Vec3 normal{0.0f};
    /// A spot's cone (unit axis, cosine of its half-angle): spheres wholly outside it are never
    /// chosen. cone_cos = -1: every direction.
    Vec3 cone_axis{0.0f, 0.0f, 1.0f};
    float cone_cos = -1.0f;
    /// The size of the light's own distribution in the choice's weights, one over its largest
    /// density: 4 pi for a point, the cone's solid angle for a spot, pi for a one-sided emitter
    /// (weights are solid angle times cosine), 2 pi for a two-sided one (half its photons on each
    /// side, cosine-weighted).
    float measure = 4.0f * kPi;
};

enum class FocusOutcome : uint8_t {
    aimed,    // `direction` was drawn towards the spheres, with density `pdf`
    plain,    // the spheres take up as much as the light's distribution or more: aiming would not pay,
              // sample it as usual
    nothing,  // no sphere can be reached: the photon carries no flux
};

struct FocusedDirection {
    FocusOutcome outcome = FocusOutcome::nothing;
    Vec3 direction{0.0f, 0.0f, 1.0f};
    /// The mixture's solid-angle density of `direction` (see the header).
    float pdf = 0.0f;
};

/// Samples a direction from the emitter towards the spheres of `focus`, choosing a sphere by
/// u_choice and a direction in its cone by u.
FocusedDirection sample_focused_direction(const EmissionFocus& focus, const EmitterView& emitter, float u_choice, Vec2 u);

}  // namespace photond
