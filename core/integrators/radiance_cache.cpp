#include "core/integrators/radiance_cache.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace photond {
namespace {

/// Bands a lobe of GGX alpha needs: kBandsTimesAlpha / alpha (RadianceCacheTest measures the
/// error of this choice against brute-force glossy gathering).
constexpr float kBandsTimesAlpha = 2.0f;
constexpr int kMinBands = 3;
/// Records of more bands than this get a radius shrunk by kDensityBands / bands.
constexpr float kDensityBands = 4.0f;
/// Each record's coefficients carry the Monte Carlo noise of its gather; interpolated, that noise
/// is a smooth error no number of camera samples removes. 16 rays a coefficient left it most of
/// the error on glossy-objects' aluminium sphere at 32 spp (relMSE 0.0022 against 0.0013 with 32;
/// README.md, "Glossy surfaces: the radiance cache").
constexpr uint32_t kRaysPerCoefficient = 32;
constexpr uint32_t kMaxRecordRays = 8192;
constexpr uint64_t kRadianceStreamTag = 0x72616469616e6365ull;  // separates record streams

/// The direction's local coordinates, below the horizon taken at the horizon (a record's
/// hemisphere ends there; a neighbouring point's tilted hemisphere may reach a little beyond).
Vec3 above_horizon(const Vec3& local) {
    if (local.z >= 0.0f) return local;
    const float rho = std::sqrt(local.x * local.x + local.y * local.y);
    return rho > 0.0f ? Vec3(local.x / rho, local.y / rho, 0.0f) : Vec3(1.0f, 0.0f, 0.0f);
}

}  // namespace

int radiance_order_for(float alpha) {
    if (!(alpha > 0.0f)) return std::numeric_limits<int>::max();
    const float bands = std::ceil(kBandsTimesAlpha / alpha);
    return bands > float(kMaxHarmonicsOrder) ? std::numeric_limits<int>::max()
                                             : std::max(kMinBands, static_cast<int>(bands));
}

namespace {

int cached_order(float alpha, bool transmits, const RadianceCacheSettings& settings) {
    if (!(alpha > 0.0f) || transmits) return 0;
    const int order = radiance_order_for(alpha);
    return order <= settings.max_order ? order : 0;
}

}  // namespace

int radiance_order_for(const Bsdf& bsdf, const RadianceCacheSettings& settings) {
    return cached_order(bsdf.sharpest_reflection_alpha(), bsdf.transmits_non_delta(), settings);
}

int radiance_order_for(const BsdfMaterial& material, const RadianceCacheSettings& settings) {
    return cached_order(sharpest_reflection_alpha(material), transmits_non_delta(material), settings);
}

uint32_t radiance_record_rays(uint32_t gather_rays, int order) {
    const uint32_t per_coefficient = kRaysPerCoefficient * static_cast<uint32_t>(harmonics_count(order));
    return std::min(kMaxRecordRays, std::max(gather_rays, per_coefficient));
}

RadianceGather gather_radiance_record(const FinalGatherer& gatherer, const DiffusePoint& point, int order,
                                      uint32_t rays, bool gradients, Rng& rng, RayCounters& counters) {
    const RenderScene& rs = gatherer.scene();
    const GatherGrid grid = GatherGrid::for_rays(rays);
    const int m = grid.m, cells_n = grid.n;
    // Each ray stands for its cell of the uniformly sampled hemisphere: its cone spreads over
    // the cell's solid angle, 2 pi / cells, and filters the textures it meets.
    const RayFootprint cone{0.0f, std::sqrt(2.0f * kPi / static_cast<float>(m * cells_n)), 1.0f};
    const int count = harmonics_count(order);
    RadianceGather result;
    RadianceRecord& record = result.record;
    record.order = order;
    record.frame = Frame(point.normal);
    thread_local std::vector<Color> radiance;
    thread_local std::vector<float> distance;
    thread_local std::vector<float> basis;
    radiance.assign(static_cast<size_t>(m * cells_n), Color(0.0f));
    distance.assign(static_cast<size_t>(m * cells_n), std::numeric_limits<float>::infinity());
    basis.resize(static_cast<size_t>(count));
    const auto cell = [cells_n](int j, int k) { return static_cast<size_t>(j * cells_n + k); };

    std::vector<DVec3> sum(static_cast<size_t>(count), DVec3(0.0));
    double inverse_distance_sum = 0.0;
    for (int j = 0; j < m; ++j) {
        for (int k = 0; k < cells_n; ++k) {
            const Vec2 u = rng.next_vec2();
            const float cos_theta = 1.0f - (static_cast<float>(j) + u.x) / static_cast<float>(m);
            const float sin_theta = safe_sqrt(1.0f - cos_theta * cos_theta);
            const float phi = 2.0f * kPi * (static_cast<float>(k) + u.y) / static_cast<float>(cells_n);
            const Vec3 local(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta);
            const Vec3 direction = record.frame.to_world(local);
            // Directions under the geometric surface (tilted shading normals) see nothing.
            if (glm::dot(direction, point.geometric_normal) <= 0.0f) continue;
            float d = 0.0f;
            const Color L = gatherer.gather_ray_radiance(
                Ray{rs.tracer->offset_origin(point.position, point.geometric_normal, direction), direction}, rng,
                counters, &d, nullptr, cone);
            radiance[cell(j, k)] = L;
            distance[cell(j, k)] = d;
            ++result.rays;
            if (std::isfinite(d) && d > 0.0f) inverse_distance_sum += 1.0 / d;
            if (is_black(L)) continue;
            hemispherical_harmonics(order, local, basis);
            for (int i = 0; i < count; ++i) sum[size_t(i)] += double(basis[size_t(i)]) * DVec3(L);
        }
    }
    const double cells = static_cast<double>(m) * cells_n;
    const double solid_angle = 2.0 * double(kPi) / cells;  // every cell's
    record.coefficients.resize(size_t(count));
    for (int i = 0; i < count; ++i) record.coefficients[size_t(i)] = Color(sum[size_t(i)] * solid_angle);
    result.harmonic_mean_distance = inverse_distance_sum > 0.0 ? static_cast<float>(cells / inverse_distance_sum)
                                                               : std::numeric_limits<float>::infinity();
    record.gradient_s.assign(size_t(count), Color(0.0f));
    record.gradient_t.assign(size_t(count), Color(0.0f));
    if (!gradients) return result;

    // The cell-wall terms of the header, in the frame's (s, t) coordinates.
    std::vector<DVec3> gradient_s(size_t(count), DVec3(0.0)), gradient_t(size_t(count), DVec3(0.0));
    const double cell_phi = 2.0 * double(kPi) / cells_n;
    const auto add_wall = [&](const Vec3& at, double coefficient, const DVec3& difference, double ds, double dt) {
        hemispherical_harmonics(order, at, basis);
        for (int i = 0; i < count; ++i) {
            const DVec3 term = difference * (coefficient * double(basis[size_t(i)]));
            gradient_s[size_t(i)] += term * ds;
            gradient_t[size_t(i)] += term * dt;
        }
    };
    for (int k = 0; k < cells_n; ++k) {
        const double phi_centre = (k + 0.5) * cell_phi;
        const double phi_wall = k * cell_phi;  // between columns k - 1 and k
        const int k_prev = (k + cells_n - 1) % cells_n;
        for (int j = 0; j < m; ++j) {
            // Wall between rows j - 1 and j: cos(theta) = 1 - j / M.
            if (j > 0) {
                const double r = std::min(distance[cell(j, k)], distance[cell(j - 1, k)]);
                const DVec3 difference = DVec3(radiance[cell(j, k)]) - DVec3(radiance[cell(j - 1, k)]);
                if (std::isfinite(r) && r > 0.0 && difference != DVec3(0.0)) {
                    const double cos_w = 1.0 - static_cast<double>(j) / m;
                    const double sin_w = std::sqrt(std::max(0.0, 1.0 - cos_w * cos_w));
                    const Vec3 at(float(sin_w * std::cos(phi_centre)), float(sin_w * std::sin(phi_centre)), float(cos_w));
                    add_wall(at, cell_phi * sin_w * cos_w / r, difference, std::cos(phi_centre), std::sin(phi_centre));
                }
            }
            // Wall between columns k - 1 and k over row j.
            const double r = std::min(distance[cell(j, k)], distance[cell(j, k_prev)]);
            const DVec3 difference = DVec3(radiance[cell(j, k)]) - DVec3(radiance[cell(j, k_prev)]);
            if (cells_n > 1 && std::isfinite(r) && r > 0.0 && difference != DVec3(0.0)) {
                const double theta_a = std::acos(1.0 - static_cast<double>(j) / m);
                const double theta_b = std::acos(std::max(-1.0, 1.0 - (j + 1.0) / m));
                const double theta_c = 0.5 * (theta_a + theta_b);
                const Vec3 at(float(std::sin(theta_c) * std::cos(phi_wall)), float(std::sin(theta_c) * std::sin(phi_wall)),
                              float(std::cos(theta_c)));
                add_wall(at, (theta_b - theta_a) / r, difference, -std::sin(phi_wall), std::cos(phi_wall));
            }
        }
    }
    for (int i = 0; i < count; ++i) {
        record.gradient_s[size_t(i)] = Color(gradient_s[size_t(i)]);
        record.gradient_t[size_t(i)] = Color(gradient_t[size_t(i)]);
    }
    return result;
}

RadianceCache::RadianceCache(const Bounds3& scene_bounds, const IrradianceCacheSettings& settings)
    : geometry_(scene_bounds, settings) {}

size_t RadianceCache::memory_bytes() const {
    size_t bytes = geometry_.memory_bytes() + records_.capacity() * sizeof(RadianceRecord);
    for (const RadianceRecord& r : records_)
        bytes += (r.coefficients.capacity() + r.gradient_s.capacity() + r.gradient_t.capacity()) * sizeof(Color);
    return bytes;
}

bool RadianceCache::field_at(const Vec3& p, const Vec3& n, float accuracy_scale, Field* field) const {
    field->entries_.clear();
    field->coefficients_.clear();
    thread_local std::vector<IrradianceCache::RecordWeight> weights;
    if (!geometry_.weigh_records(p, n, accuracy_scale, &weights)) return false;
    const bool gradients = geometry_.settings().gradients;
    for (const IrradianceCache::RecordWeight& w : weights) {
        const RadianceRecord& r = records_[w.index];
        const Vec3 offset = p - geometry_.records()[w.index].position;
        const float ds = glm::dot(offset, r.frame.s), dt = glm::dot(offset, r.frame.t);
        field->entries_.push_back({&r, static_cast<float>(w.weight), field->coefficients_.size()});
        for (size_t i = 0; i < r.coefficients.size(); ++i) {
            Color c = r.coefficients[i];
            if (gradients) c += ds * r.gradient_s[i] + dt * r.gradient_t[i];
            field->coefficients_.push_back(c);
        }
    }
    return true;
}

Color RadianceCache::Field::incident(const Vec3& wi) const {
    thread_local std::vector<float> basis;
    Color sum(0.0f);
    for (const Entry& e : entries_) {
        const int count = harmonics_count(e.record->order);
        basis.resize(size_t(count));
        hemispherical_harmonics(e.record->order, above_horizon(e.record->frame.to_local(wi)), basis);
        Color value(0.0f);
        const Color* c = coefficients_.data() + e.first;
        for (int i = 0; i < count; ++i) value += basis[size_t(i)] * c[i];
        sum += e.weight * value;
    }
    return sum;
}

uint64_t RadianceRecordKind::stream_tag() const { return kRadianceStreamTag; }

bool RadianceRecordKind::wants(const Bsdf& bsdf, const Vec3&, CachePoint* point) const {
    point->order = radiance_order_for(bsdf, settings_);
    return point->order > 0;
}

IrradianceRecord RadianceRecordKind::make_record(const CachePoint& point, Rng& rng, RayCounters& counters,
                                                 std::any* payload) const {
    const uint32_t rays = radiance_record_rays(gatherer_.settings().rays, point.order);
    RadianceGather g = gather_radiance_record(gatherer_, point, point.order, rays, build_.gradients, rng, counters);
    float min_radius = 0.0f, max_radius = 0.0f;
    record_radius_limits(build_, point.footprint, &min_radius, &max_radius);
    const float density = std::min(1.0f, kDensityBands / static_cast<float>(point.order));
    IrradianceRecord where;
    where.position = point.position;
    where.normal = point.normal;
    where.radius = std::max(min_radius, std::min(g.harmonic_mean_distance, max_radius) * density);
    // Gradient limiting, as for irradiance records: across its domain (distance a R) a record's
    // coefficients may change by at most their own size.
    RadianceRecord& r = g.record;
    const float reach = build_.accuracy * where.radius;
    for (int c = 0; c < 3; ++c) {
        double value = 0.0, gradient = 0.0;
        for (size_t i = 0; i < r.coefficients.size(); ++i) {
            value += double(r.coefficients[i][c]) * r.coefficients[i][c];
            gradient += double(r.gradient_s[i][c]) * r.gradient_s[i][c] + double(r.gradient_t[i][c]) * r.gradient_t[i][c];
        }
        const double change = std::sqrt(gradient) * reach, limit = std::sqrt(value);
        if (change > limit) {
            const float scale = change > 0.0 ? static_cast<float>(limit / change) : 0.0f;
            for (size_t i = 0; i < r.coefficients.size(); ++i) {
                r.gradient_s[i][c] *= scale;
                r.gradient_t[i][c] *= scale;
            }
        }
    }
    bool finite = true;
    for (size_t i = 0; i < r.coefficients.size(); ++i)
        finite = finite && is_finite(r.coefficients[i]) && is_finite(r.gradient_s[i]) && is_finite(r.gradient_t[i]);
    // A record with a non-finite coefficient is refused by the geometry (IrradianceCache::accepts).
    where.irradiance = finite ? Color(0.0f) : Color(std::numeric_limits<float>::quiet_NaN());
    *payload = std::move(r);
    return where;
}

void RadianceRecordKind::accepted(std::any&& payload) {
    cache_.add(std::any_cast<RadianceRecord>(std::move(payload)));
}

std::unique_ptr<RadianceCache> build_radiance_cache(const RenderScene& rs, const FinalGatherer& gatherer,
                                                    const Camera& camera, const CacheBuildSettings& build,
                                                    const RadianceCacheSettings& settings,
                                                    CacheBuildStatistics* statistics) {
    auto cache = std::make_unique<RadianceCache>(rs.scene->bounds, build.interpolation());
    RadianceRecordKind kind(gatherer, build, settings, *cache);
    fill_cache_in_waves(rs, camera, build, kind, cache->geometry(), statistics);
    return cache;
}

}  // namespace photond
