// A photon map: photons with their flux already divided by the number of photons emitted for
// this map, in a kd-tree, and the radiance estimate of Jensen (2001, eq. 7.6):
//   L_o(x, w_o) ~ 1 / (pi r^2) * sum_p f_r(x, w_p, w_o) dPhi_p
// over the k nearest photons, r the distance to the farthest. Immutable after construction;
// every const member may be called concurrently.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/material/bsdf.h"
#include "core/photon/kd_tree.h"
#include "core/photon/photon.h"

namespace photond {

/// Photon user flags: where the photon's path came from (light-path grammar, Heckbert 1990).
namespace photon_flags {
inline constexpr uint8_t kDirect = 1;   // first hit from the light: L D
inline constexpr uint8_t kCaustic = 2;  // through one or more specular bounces: L S+ D
}  // namespace photon_flags

/// Fewer photons than this in an estimate give zero (the lecture's rule: too few to trust).
inline constexpr uint32_t kMinPhotonsPerEstimate = 8;

/// Minimum cosine between a query's normal and a precomputed-irradiance photon's normal.
inline constexpr float kIrradianceNormalCosine = 0.9f;

struct RadianceEstimateOptions {
    uint32_t k = 50;                 // nearest photons to gather
    float max_radius = 0.0f;         // search radius cap (world units); <= 0 means unbounded
    bool cone_filter = false;        // Jensen's cone filter (2001, eq. 7.10), for caustics
    /// Skip photons whose user flags intersect this mask (e.g. direct and caustic photons when
    /// the global map is read for indirect light only).
    uint8_t exclude_flags = 0;
    LobeMask lobes = kNonDeltaLobes;  // which BSDF lobes reflect the photons
};

class PhotonMap {
public:
    PhotonMap() = default;
    /// `photons` carry their final flux (path flux / photons emitted for this map).
    PhotonMap(std::vector<Photon> photons, uint64_t emitted);
    /// Adopts a built tree (e.g. PhotonKdTree::from_tree_order of a cached map).
    PhotonMap(PhotonKdTree tree, uint64_t emitted);

    /// Reflected radiance at p towards wo; `normal` is the shading normal on wo's side. Photons
    /// arriving from behind the surface (dot(-direction, normal) <= 0) are skipped.
    Color estimate_radiance(const Vec3& p, const Vec3& normal, const Bsdf& bsdf, const Vec3& wo,
                            const RadianceEstimateOptions& options) const;

    /// Irradiance at p (photon flux per area), for diffuse reflection L = rho / pi * E.
    Color estimate_irradiance(const Vec3& p, const Vec3& normal, uint32_t k, float max_radius,
                              uint8_t exclude_flags = 0) const;

    /// Precomputed irradiance (Christensen 1999, "Faster photon map global illumination"): in a
    /// map whose photons hold irradiance (flux) and surface normal (direction), the nearest one
    /// within max_radius whose normal agrees with `normal` (cosine > kIrradianceNormalCosine).
    /// Returns false when none is near.
    bool nearest_irradiance(const Vec3& p, const Vec3& normal, float max_radius, Color* irradiance) const;

    bool empty() const { return tree_.empty(); }
    size_t size() const { return tree_.size(); }
    uint64_t emitted() const { return emitted_; }
    size_t bytes() const { return tree_.bytes(); }
    const PhotonKdTree& tree() const { return tree_; }

private:
    PhotonKdTree tree_;
    uint64_t emitted_ = 0;
};

}  // namespace photond
