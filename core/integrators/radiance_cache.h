// Radiance caching (Krivanek, Gautron, Pattanaik & Bouatouch 2005): the irradiance cache carried
// over to glossy surfaces (docs/ARCHITECTURE.md, "Radiance caching").
//
// A record at P_i holds the indirect radiance arriving over the hemisphere of its normal,
// projected on hemispherical harmonics (core/math/hemispherical_harmonics.h) in the frame of the
// normal,
//   lambda_k = integral L(w) H_k(w) dw ~ 2 pi / (M N) sum_jk L_jk H_k(w_jk),
// from M x N gather rays stratified uniformly in solid angle (rows in cos(theta), columns in
// phi), each read from the photon maps as a final-gather ray reads them. The number of bands n
// follows the sharpest glossy lobe at the point (radiance_order_for): a lobe of GGX alpha spans
// about alpha radians, and n bands resolve about pi / n. Translation gradients of every
// coefficient come from the same rays: Ward & Heckbert's cell-wall terms with the coefficient's
// basis function in place of the cosine (Krivanek et al. 2005, "improved gradients"):
//   theta wall (rows j-1 | j, column k):  (L_j - L_{j-1}) dphi sin(theta) cos(theta) H_k(theta, phi_c) / r  u(phi_c)
//   phi wall (columns k-1 | k, row j):     (L_k - L_{k-1}) (theta_b - theta_a) H_k(theta_c, phi) / r  v(phi)
// r the nearer of the two cells' hit distances, u and v the radial and azimuthal tangents.
//
// Records live in an IrradianceCache that holds their position, normal and radius: the same
// validity test, weights, neighbour clamping, octree and deterministic wave-by-wave building as
// irradiance records (core/integrators/irradiance_cache_builder.h). Their radius is the harmonic
// mean distance times kDensityBands / n where n > kDensityBands: sharper lobes, denser records.
//
// At a glossy point the records' fields, each moved to P by its gradients and read in its own
// frame (no rotation of coefficients is needed: every record is evaluated at world directions),
// are blended with the cache's weights into the incident radiance L~(w), which the lobe then
// integrates by importance sampling: L_o = 1/S sum_s f cos / pdf L~(w_s). L~ is smooth, so a few
// samples suffice where BSDF-sampled rays each trace the scene and read the photon maps.
#pragma once

#include <any>
#include <vector>

#include "core/integrators/irradiance_cache_builder.h"
#include "core/math/frame.h"
#include "core/math/hemispherical_harmonics.h"

namespace photond {

struct RadianceCacheSettings {
    bool enabled = false;
    /// The most bands a record may have; lobes that need more are BSDF-sampled instead.
    int max_order = 10;
    /// Lobe samples of the interpolated incident radiance at each shading point.
    uint32_t samples = 16;
};

/// Bands needed for a glossy lobe of GGX alpha: ceil(kBandsTimesAlpha / alpha), at least kMinBands.
int radiance_order_for(float alpha);

/// The bands a point with `bsdf` needs, or 0 when its lobes are not cached: no glossy lobe, a
/// rough transmission lobe (records see one hemisphere), or a lobe sharper than max_order allows.
int radiance_order_for(const Bsdf& bsdf, const RadianceCacheSettings& settings);
/// The same for a material's factors (a texture may make some of its points rougher).
int radiance_order_for(const BsdfMaterial& material, const RadianceCacheSettings& settings);

struct RadianceRecord {
    int order = 0;
    Frame frame;  // around the record's normal: the frame its coefficients are in
    std::vector<Color> coefficients;  // order^2
    /// Derivatives of each coefficient along frame.s and frame.t.
    std::vector<Color> gradient_s, gradient_t;
};

/// A record's gather: the record, the harmonic mean distance of its rays' hits and their count.
struct RadianceGather {
    RadianceRecord record;
    float harmonic_mean_distance = 0.0f;
    uint32_t rays = 0;
};

/// Gather rays for a record of `order` bands: the gatherer's, and at least kRaysPerCoefficient per
/// coefficient.
uint32_t radiance_record_rays(uint32_t gather_rays, int order);

/// Gathers the incident radiance at `point` (its normal, geometric normal) into a record of
/// `order` bands from `rays` stratified rays; with `gradients`, its translation gradients too.
RadianceGather gather_radiance_record(const FinalGatherer& gatherer, const DiffusePoint& point, int order,
                                      uint32_t rays, bool gradients, Rng& rng, RayCounters& counters);

class RadianceCache {
public:
    RadianceCache(const Bounds3& scene_bounds, const IrradianceCacheSettings& settings);

    /// Where records are: positions, normals, radii (the records' index is theirs here).
    IrradianceCache& geometry() { return geometry_; }
    const IrradianceCache& geometry() const { return geometry_; }
    const std::vector<RadianceRecord>& records() const { return records_; }
    /// Appends the record the geometry took last (CacheRecordKind::accepted).
    void add(RadianceRecord record) { records_.push_back(std::move(record)); }
    size_t size() const { return records_.size(); }
    size_t memory_bytes() const;

    /// The blended incident radiance of the records usable at a point.
    class Field {
    public:
        /// Radiance arriving from world direction wi (the band-limited field may ring below zero
        /// next to sharp features: callers clamp what they integrate, not each direction).
        Color incident(const Vec3& wi) const;
        bool empty() const { return entries_.empty(); }

    private:
        friend class RadianceCache;
        struct Entry {
            const RadianceRecord* record;
            float weight;
            size_t first;  // its moved coefficients in coefficients_
        };
        std::vector<Entry> entries_;
        std::vector<Color> coefficients_;
    };
    /// The field at p (normal n): false when no record is usable. `accuracy_scale` as
    /// IrradianceCache::interpolate's.
    bool field_at(const Vec3& p, const Vec3& n, float accuracy_scale, Field* field) const;

private:
    IrradianceCache geometry_;
    std::vector<RadianceRecord> records_;
};

/// Radiance records at the points whose glossy lobes radiance_order_for caches.
class RadianceRecordKind final : public CacheRecordKind {
public:
    RadianceRecordKind(const FinalGatherer& gatherer, const CacheBuildSettings& build,
                       const RadianceCacheSettings& settings, RadianceCache& cache)
        : gatherer_(gatherer), build_(build), settings_(settings), cache_(cache) {}
    uint64_t stream_tag() const override;
    bool wants(const Bsdf& bsdf, const Vec3& wo, CachePoint* point) const override;
    IrradianceRecord make_record(const CachePoint& point, Rng& rng, RayCounters& counters,
                                 std::any* payload) const override;
    void accepted(std::any&& payload) override;

private:
    const FinalGatherer& gatherer_;
    const CacheBuildSettings& build_;
    const RadianceCacheSettings& settings_;
    RadianceCache& cache_;
};

/// Builds the radiance cache of a view, as build_irradiance_cache builds the irradiance cache.
std::unique_ptr<RadianceCache> build_radiance_cache(const RenderScene& scene, const FinalGatherer& gatherer,
                                                    const Camera& camera, const CacheBuildSettings& build,
                                                    const RadianceCacheSettings& settings,
                                                    CacheBuildStatistics* statistics);

}  // namespace photond
