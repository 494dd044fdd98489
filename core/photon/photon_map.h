// A photon map: photons with their flux already divided by the number of photons emitted for
// this map, in a kd-tree, and the radiance estimate of Jensen (2001, eq. 7.6):
//   L_o(x, w_o) ~ 1 / (pi r^2) * sum_p f_r(x, w_p, w_o) dPhi_p
// over the k nearest photons, r the distance to the farthest, found in a disc around x rather than
// a sphere and counting only photons stored on a surface that faces like x's (Jensen 2001,
// section 7.2; kPhotonDiscFlattening, kPhotonNormalCosine). Immutable after construction; every
// const member may be called concurrently.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/material/bsdf.h"
#include "core/photon/kd_tree.h"
#include "core/photon/photon.h"

namespace photond {

/// Photon user flags: where the photon's path came from (light-path grammar, Heckbert 1990).
namespace photon_flags {
inline constexpr uint8_t kDirect = 1;   // first hit from the light: L D
inline constexpr uint8_t kCaustic = 2;  // through one or more specular or glossy bounces: L S+ D
/// A volume photon stored inside a closed transmissive solid (Material::interior_scatters), not
/// in the atmosphere: estimates in the one never count photons of the other.
inline constexpr uint8_t kInterior = 4;
/// A caustic photon (kCaustic) with a glossy bounce on its way: a visible point whose glossy
/// lobes take rays (which follow glossy lobes to the lights) reads it by its Lambertian lobe only.
inline constexpr uint8_t kGlossyCaustic = 8;
}  // namespace photon_flags

/// Fewer photons than this in an estimate give zero (the lecture's rule: too few to trust).
inline constexpr uint32_t kMinPhotonsPerEstimate = 8;

/// Minimum cosine between a query's normal and a precomputed-irradiance photon's normal.
inline constexpr float kIrradianceNormalCosine = 0.9f;

/// Minimum cosine between a query's normal and the surface normal a photon was stored with, for
/// the photon to count in an estimate (Jensen 2001, section 7.2: photons of other surfaces are
/// refused). Surfaces meeting at an edge (90 degrees: cosine 0) or the two sides of a thin wall
/// (cosine -1) are refused; a curved surface's own photons pass while its normal turns by less
/// than 60 degrees across the search radius.
inline constexpr float kPhotonNormalCosine = 0.5f;

/// Estimates gather photons from a disc, not a sphere (Jensen 2001, section 7.2): an ellipsoid
/// whose axis along the query's normal is this many times shorter than its radius, so that a
/// parallel surface facing the same way (the floor inside a box, seen from a surface under the
/// box) is read only where it lies closer than 1 / kPhotonDiscFlattening of the search radius.
/// On a curved surface the disc stretches distances by sqrt(1 + (f r / 2R)^2) at radius r for a
/// curvature radius R: 3% at r = R / 10.
inline constexpr float kPhotonDiscFlattening = 5.0f;

struct RadianceEstimateOptions {
    uint32_t k = 50;                 // nearest photons to gather
    float max_radius = 0.0f;         // search radius cap (world units); <= 0 means unbounded
    bool cone_filter = false;        // Jensen's cone filter (2001, eq. 7.10), for caustics
    /// Skip photons whose user flags intersect this mask (e.g. direct and caustic photons when
    /// the global map is read for indirect light only).
    uint8_t exclude_flags = 0;
    LobeMask lobes = kNonDeltaLobes;  // which BSDF lobes reflect the photons
    /// Non-zero on a surface whose shading normal is bent (a normal map), on wo's side: the
    /// photons' density is per area of the unbent surface (`normal`), so each one counts
    /// cos(shading_normal, wi) / cos(normal, wi) as much, and none from behind the bent normal.
    Vec3 shading_normal{0.0f};
    /// The surface transmits through a non-delta lobe (rough glass): photons stored on its
    /// other side (arrived from behind, stored with the opposite normal) count too, through
    /// the BSDF's transmission.
    bool both_sides = false;
    /// Photons with any of these flags are reflected by `restricted_lobes` instead of `lobes`
    /// (photon_flags::kGlossyCaustic: by the Lambertian lobe alone where rays take the others).
    uint8_t restricted_flags = 0;
    LobeMask restricted_lobes = kLambertianLobe;
};

class PhotonMap {
public:
    PhotonMap() = default;
    /// `photons` carry their final flux (path flux / photons emitted for this map).
    PhotonMap(std::vector<Photon> photons, uint64_t emitted);
    /// Adopts a built tree (e.g. PhotonKdTree::from_tree_order of a cached map).
    PhotonMap(PhotonKdTree tree, uint64_t emitted);

    /// Reflected radiance at p towards wo; `normal` is the shading normal on wo's side. The k
    /// nearest photons (in a disc: PhotonKdTree::k_nearest_in_disc) set the radius; the farthest,
    /// on the disc's edge, is not counted: k - 1 photons over the disc's area is the unbiased
    /// density of a uniform distribution, k of them 1 / (k - 1) too much. Photons
    /// arriving from behind the surface (dot(-direction, normal) <= 0) are skipped, and so are
    /// photons stored with a surface normal that disagrees with `normal` (cosine <=
    /// kPhotonNormalCosine): those on the other side of a thin wall or on another surface.
    Color estimate_radiance(const Vec3& p, const Vec3& normal, const Bsdf& bsdf, const Vec3& wo,
                            const RadianceEstimateOptions& options) const;

    /// Irradiance at p (photon flux per area), for diffuse reflection L = rho / pi * E. Photons
    /// are skipped as in estimate_radiance.
    ///
    /// `radius_hint`, when given and positive, is a guess of the estimate's radius (a neighbouring
    /// estimate's, a little widened): the k photons are first sought within it, and only if fewer
    /// are there within max_radius. The k nearest within the hint are the k nearest anywhere, so
    /// the estimate takes the same photons and radius as without a hint (their sum may differ in
    /// its last bits: it adds them in the order the search met them); the search is shorter when
    /// the guess is good. On return it holds this estimate's radius (0 when fewer than k photons
    /// were found).
    Color estimate_irradiance(const Vec3& p, const Vec3& normal, uint32_t k, float max_radius,
                              uint8_t exclude_flags = 0, float* radius_hint = nullptr) const;

    /// In a volume map (PhotonMaps::volume): the in-scattered radiance source at x towards wo,
    /// sigma_s times the phase-weighted integral of the radiance arriving there (Jensen &
    /// Christensen 1998): the sum over the k nearest photons, but the farthest on the sphere's
    /// edge (as in estimate_radiance), of HG(g, wo, -direction) times their flux (stored with the
    /// event's albedo), over the volume (4/3) pi r^3 of the sphere they fill. Photons with any of exclude_flags are skipped (photon_flags::kDirect: the single
    /// scattering a ray march takes by light samples). Zero with fewer than
    /// kMinPhotonsPerEstimate photons. With `medium_bounds` (the box the medium fills), the
    /// sphere's caps beyond its faces are left out of the volume: no photon can lie there, and a
    /// whole sphere would darken the medium along the box's walls.
    /// `interior`: x lies inside a scattering solid, whose photons (photon_flags::kInterior) alone
    /// are searched; else those are never among the k. `surface_distance(r)`, when given: how far
    /// x is from the surface that bounds its medium (a solid's) if that is under the estimate's
    /// radius r, else anything not below r; the sphere's part beyond it is left out of the volume
    /// as a plane there at that distance would cut it.
    Color estimate_in_scattering(const Vec3& x, const Vec3& wo, float g, uint32_t k, float max_radius,
                                 uint8_t exclude_flags = 0, const Bounds3* medium_bounds = nullptr,
                                 bool interior = false,
                                 const std::function<float(float)>& surface_distance = {}) const;

    /// Precomputed irradiance (Christensen 1999, "Faster photon map global illumination"): in a
    /// map of irradiance sites (make_irradiance_site: irradiance as flux, a surface normal, the
    /// estimate's radius), the nearest one within max_radius (by disc distance, as estimates
    /// search) whose normal agrees with `normal` (cosine > kIrradianceNormalCosine), where its
    /// own estimate's disc holds p. Sites without a normal are never taken. Returns false when
    /// there is no such site or its disc ends short of p; else its irradiance, and its
    /// estimate's radius in `site_radius` when given.
    bool nearest_irradiance(const Vec3& p, const Vec3& normal, float max_radius, Color* irradiance,
                            float* site_radius = nullptr) const;

    bool empty() const { return tree_.empty(); }
    size_t size() const { return tree_.size(); }
    uint64_t emitted() const { return emitted_; }
    size_t bytes() const { return tree_.bytes(); }
    const PhotonKdTree& tree() const { return tree_; }

private:
    PhotonKdTree tree_;
    uint64_t emitted_ = 0;
};

/// The largest estimate radius among a map of irradiance sites (Photon::site_radius). No site is
/// taken farther from a query than its radius (PhotonMap::nearest_irradiance), so searching
/// further than this finds nothing more.
float largest_site_radius(const PhotonMap& sites);
/// How far a search for the nearest site need reach (nearest_irradiance's max_radius): the
/// largest site's radius where that is less than max_radius (or max_radius is <= 0, unbounded);
/// max_radius where the sites have no radius (0 would mean unbounded).
float site_search_radius(const PhotonMap& sites, float max_radius);

}  // namespace photond
