#include "core/photon/photon_map.h"

#include <algorithm>

namespace photond {

namespace {
constexpr double kPiDouble = 3.14159265358979323846;
}  // namespace

PhotonMap::PhotonMap(std::vector<Photon> photons, uint64_t emitted)
    : tree_(std::move(photons)), emitted_(emitted) {}

PhotonMap::PhotonMap(PhotonKdTree tree, uint64_t emitted)
    : tree_(std::move(tree)), emitted_(emitted) {}

namespace {

/// One reusable neighbour list per thread: queries never allocate after warm-up.
KnnResult& thread_scratch() {
    thread_local KnnResult scratch;
    return scratch;
}

/// The disc (or ball) an estimate's photons were gathered from.
///
/// Its squared radius: the farthest photon's when k were found, else the whole search ball (fewer
/// than k photons within max_radius means the density is known over the full ball, not only up
/// to the farthest photon). Where the farthest photon sets the radius it lies on the edge, not
/// inside, and is left out of the sum (`edge`): the photons inside a disc whose radius is the k-th
/// nearest distance number k - 1, and over a Poisson density lambda, E[(k - 1) / (pi r_k^2)] =
/// lambda, while the k photons over the same area are k / (k - 1) too many on average (+2 % at
/// k = 50, the same in a ball; Loftsgaarden & Quesenberry 1965). Rooms lit by photon-map
/// estimates came out that much brighter than `path`.
struct EstimateSupport {
    double radius2 = 0.0;
    int edge = -1;  // index into KnnResult::neighbors of the photon on the edge, or -1
};

EstimateSupport estimate_support(const KnnResult& found, uint32_t k, float max_radius) {
    if (found.size() < k && std::isfinite(max_radius)) return {static_cast<double>(max_radius) * max_radius, -1};
    if (found.empty()) return {};
    return {static_cast<double>(found.radius2), static_cast<int>(found.farthest())};
}

/// Whether a photon may count in an estimate at a surface point with unit normal n (on the side
/// of the viewer): it arrived from that side, and it was stored on a surface facing the same way
/// (photons made without a normal only have the first test).
bool photon_counts(const Photon& photon, const Vec3& n) {
    if (glm::dot(-photon.direction(), n) <= 0.0f) return false;
    return !photon.has_normal() || glm::dot(photon.normal(), n) > kPhotonNormalCosine;
}

/// photon_counts() for either side of the surface: n's or the opposite one.
bool photon_counts_either_side(const Photon& photon, const Vec3& n) {
    return photon_counts(photon, n) || photon_counts(photon, -n);
}

}  // namespace

Color PhotonMap::estimate_radiance(const Vec3& p, const Vec3& normal, const Bsdf& bsdf,
                                   const Vec3& wo, const RadianceEstimateOptions& options) const {
    if (tree_.empty()) return Color(0.0f);
    KnnResult& found = thread_scratch();
    const float max_radius = options.max_radius > 0.0f ? options.max_radius
                                                       : std::numeric_limits<float>::infinity();
    tree_.k_nearest_in_disc(p, normal, kPhotonDiscFlattening, options.k, max_radius, found);
    // The estimate's own radius decides (a pile of photons at p inside a finite search ball has
    // one); zero only when k photons sit exactly at p, where the density is undefined.
    const EstimateSupport support = estimate_support(found, options.k, max_radius);
    if (found.size() < kMinPhotonsPerEstimate || !(support.radius2 > 0.0)) return Color(0.0f);
    const double r = std::sqrt(support.radius2);
    // Cone filter weight w = 1 - d / (k_cone r), normalised by 1 - 2 / (3 k_cone) (Jensen 2001).
    constexpr double kCone = 1.1;
    DVec3 sum(0.0);
    const bool bent = glm::dot(options.shading_normal, options.shading_normal) > 0.0f;
    for (size_t i = 0; i < found.neighbors.size(); ++i) {
        if (static_cast<int>(i) == support.edge) continue;
        const KnnNeighbor& n = found.neighbors[i];
        const Photon& photon = tree_.photon(n.index);
        if (photon.user_flags() & options.exclude_flags) continue;
        if (!(options.both_sides ? photon_counts_either_side(photon, normal) : photon_counts(photon, normal)))
            continue;
        const Vec3 wi = -photon.direction();
        const LobeMask lobes = photon.user_flags() & options.restricted_flags ? options.restricted_lobes : options.lobes;
        const Color f = bsdf.eval(wo, wi, TransportMode::Radiance, lobes);
        DVec3 contribution = DVec3(f) * DVec3(photon.flux());
        if (bent) {
            // The photon's side of the surface: normal's, or the other one (both_sides).
            const float side = glm::dot(normal, wi) >= 0.0f ? 1.0f : -1.0f;
            const float cos_bent = side * glm::dot(options.shading_normal, wi);
            if (!(cos_bent > 0.0f)) continue;
            // photon_counts() kept only photons in front of their side; the floor bounds the
            // weight of the few that graze it.
            contribution *= static_cast<double>(cos_bent / std::max(side * glm::dot(normal, wi), 0.05f));
        }
        if (options.cone_filter) contribution *= 1.0 - std::sqrt(static_cast<double>(n.dist2)) / (kCone * r);
        sum += contribution;
    }
    double area = kPiDouble * r * r;
    if (options.cone_filter) area *= 1.0 - 2.0 / (3.0 * kCone);
    return Color(sum / area);
}

Color PhotonMap::estimate_irradiance(const Vec3& p, const Vec3& normal, uint32_t k, float max_radius,
                                     uint8_t exclude_flags, float* radius_hint) const {
    if (tree_.empty()) return Color(0.0f);
    KnnResult& found = thread_scratch();
    max_radius = max_radius > 0.0f ? max_radius : std::numeric_limits<float>::infinity();
    const bool hinted = radius_hint && *radius_hint > 0.0f && *radius_hint < max_radius;
    if (hinted) tree_.k_nearest_in_disc(p, normal, kPhotonDiscFlattening, k, *radius_hint, found);
    if (!hinted || found.size() < k) tree_.k_nearest_in_disc(p, normal, kPhotonDiscFlattening, k, max_radius, found);
    if (radius_hint) *radius_hint = found.size() >= k && k > 0 ? std::sqrt(found.radius2) : 0.0f;
    const EstimateSupport support = estimate_support(found, k, max_radius);
    if (found.size() < kMinPhotonsPerEstimate || !(support.radius2 > 0.0)) return Color(0.0f);
    DVec3 sum(0.0);
    for (size_t i = 0; i < found.neighbors.size(); ++i) {
        const Photon& photon = tree_.photon(found.neighbors[i].index);
        if (static_cast<int>(i) == support.edge || (photon.user_flags() & exclude_flags) ||
            !photon_counts(photon, normal))
            continue;
        sum += DVec3(photon.flux());
    }
    return Color(sum / (kPiDouble * support.radius2));
}

namespace {

/// The volume of a sphere of radius r beyond a plane at distance h < r from its centre (a cap of
/// height r - h; the whole sphere less the cap on the centre's side when h < 0).
double cap_volume(double r, double h) {
    const double height = std::clamp(r - h, 0.0, 2.0 * r);
    return kPiDouble * height * height * (3.0 * r - height) / 3.0;
}

}  // namespace

Color PhotonMap::estimate_in_scattering(const Vec3& x, const Vec3& wo, float g, uint32_t k, float max_radius,
                                        uint8_t exclude_flags, const Bounds3* medium_bounds, bool interior,
                                        const std::function<float(float)>& surface_distance) const {
    if (tree_.empty()) return Color(0.0f);
    KnnResult& found = thread_scratch();
    max_radius = max_radius > 0.0f ? max_radius : std::numeric_limits<float>::infinity();
    if (interior)
        tree_.k_nearest_flagged(x, k, max_radius, photon_flags::kInterior, 0, found);
    else
        tree_.k_nearest_flagged(x, k, max_radius, 0, photon_flags::kInterior, found);
    const EstimateSupport support = estimate_support(found, k, max_radius);
    if (found.size() < kMinPhotonsPerEstimate || !(support.radius2 > 0.0)) return Color(0.0f);
    DVec3 sum(0.0);
    for (size_t i = 0; i < found.neighbors.size(); ++i) {
        const Photon& photon = tree_.photon(found.neighbors[i].index);
        if (static_cast<int>(i) == support.edge || (photon.user_flags() & exclude_flags)) continue;
        sum += static_cast<double>(henyey_greenstein(g, wo, -photon.direction())) * DVec3(photon.flux());
    }
    const double r = std::sqrt(support.radius2);
    double volume = 4.0 / 3.0 * kPiDouble * support.radius2 * r;
    if (medium_bounds && !medium_bounds->empty()) {
        // Each face the sphere crosses cuts off a cap of height h: pi h^2 (3 r - h) / 3 (caps of
        // two faces overlap only near the box's edges, which the floor below covers).
        double outside = 0.0;
        for (int axis = 0; axis < 3; ++axis) {
            for (const double gap : {static_cast<double>(x[axis] - medium_bounds->lower[axis]),
                                     static_cast<double>(medium_bounds->upper[axis] - x[axis])})
                outside += cap_volume(r, gap);
        }
        volume = std::max(volume - outside, 0.125 * volume);
    }
    // The solid's surface taken as the plane at its nearest point: curved surfaces leave a little
    // more or less than the cap (a convex one more), within the sphere's last few percent.
    if (surface_distance) {
        const double distance = surface_distance(static_cast<float>(r));
        if (distance < r) volume = std::max(volume - cap_volume(r, distance), 0.125 * volume);
    }
    return Color(sum / volume);
}

bool PhotonMap::nearest_irradiance(const Vec3& p, const Vec3& normal, float max_radius, Color* irradiance,
                                   float* site_radius) const {
    if (tree_.empty() || !is_finite(normal)) return false;
    KnnResult& found = thread_scratch();
    if (!(max_radius > 0.0f)) max_radius = std::numeric_limits<float>::infinity();
    // One search for the nearest site that faces the query's way (the nearest few sites of a
    // crumpled cloth or a sheet's other side face away), asking a site's normal only where it is
    // nearer than the best so far (k_nearest_where). A site whose estimate's disc ends short of p
    // never measured the light there: the caller estimates it from the photons instead.
    constexpr float kStretch2 = kPhotonDiscFlattening * kPhotonDiscFlattening - 1.0f;
    tree_.k_nearest_where(
        p, 1, max_radius, found,
        [p, normal](const Vec3& q) { return PhotonKdTree::disc_distance2(p, q, normal, kStretch2); },
        [normal](const Photon& site) { return site.has_normal() && glm::dot(site.normal(), normal) > kIrradianceNormalCosine; });
    if (found.empty()) return false;
    const Photon& site = tree_.photon(found.neighbors[0].index);
    if (found.neighbors[0].dist2 > site.site_radius() * site.site_radius()) return false;
    *irradiance = site.flux();
    if (site_radius) *site_radius = site.site_radius();
    return true;
}

float largest_site_radius(const PhotonMap& sites) {
    float largest = 0.0f;
    for (const Photon& site : sites.tree().photons()) largest = std::max(largest, site.site_radius());
    return largest;
}

float site_search_radius(const PhotonMap& sites, float max_radius) {
    const float largest = largest_site_radius(sites);
    if (!(largest > 0.0f)) return max_radius;
    return max_radius > 0.0f ? std::min(max_radius, largest) : largest;
}

}  // namespace photond
