#include "core/photon/photon_tracer.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>
#include <tbb/scalable_allocator.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <limits>
#include <utility>

#include "core/math/rng.h"
#include "core/scene/atmosphere.h"
#include "core/shading/scene_queries.h"

namespace photond {
namespace {

using Clock = std::chrono::steady_clock;
constexpr uint64_t kPhotonStreamTag = 0x70686f746f6e73ull;  // separates photon streams from pixels
constexpr uint32_t kChunkSize = 1024;                       // photons per parallel task
constexpr uint64_t kEmptyMapTrial = 1u << 20;               // emissions before an empty map is given up
// A precomputed irradiance estimate's search starts at its spatial neighbour's radius times this.
constexpr float kRadiusHintWidening = 1.25f;
constexpr size_t kHintBlock = 256;  // sites whose estimates pass the hint on, one after another
// A batch stores at most about this share of a map's photons: the chunks' buffers of traced
// photons (28 bytes each) then stay a small part of the map's memory (photon_series.py's peak).
constexpr double kBatchesPerMap = 8.0;
constexpr double kBatchGrowth = 8.0;  // the most a batch grows over the one before

/// A stored photon before its map is complete: packed as the map stores it, but with its flux
/// not yet divided by the photons emitted for its map (Photon::scale_flux does that once they
/// are counted), and its emission index within the batch, to cut the map at the photon that
/// fills it. 28 bytes: a full-precision record was 56, and with the packed copy made from it
/// the traced photons took 3.3 times the map's bytes at their peak.
struct TracedPhoton {
    Photon photon;
    uint32_t path;
};

/// Traced photons of one chunk. oneTBB's scalable allocator keeps freed blocks for reuse, where
/// glibc hands them back to the kernel: the next photon pass (another job in the daemon) then
/// writes into memory already mapped instead of taking a page fault every few dozen photons
/// (on virtual machines, where faults are dear, they were a large share of tracing time).
/// Under AddressSanitizer the standard allocator, whose blocks the sanitizer guards.
#if defined(__SANITIZE_ADDRESS__)
using TracedPhotons = std::vector<TracedPhoton>;
#else
using TracedPhotons = std::vector<TracedPhoton, tbb::scalable_allocator<TracedPhoton>>;
#endif

struct ChunkOutput {
    TracedPhotons global;
    TracedPhotons caustic;
    TracedPhotons volume;
    uint64_t rays = 0;
};

struct MapBuilder {
    uint32_t target = 0;
    uint64_t cap = 0;         // emission cap for this map
    bool active = false;      // still collecting
    bool complete = true;
    uint64_t emitted = 0;     // photons emitted for this map (set when it fills or stops)
    uint64_t first = 0;       // the emission its photons count from (restart)
    size_t count = 0;         // photons collected so far
    double flux_sum = 0.0;    // their flux's luminance, not yet divided by the emissions
    /// The collected photons in emission order, flux not yet divided (TracedPhoton), in one
    /// array reserved for the whole map: it becomes the map, and its kd-tree is built in it.
    std::vector<Photon> photons;

    /// Takes a batch's photons in order; stops at the one that fills the map. The chunks'
    /// photons are copied in parallel, each chunk to its own range.
    void append(std::span<ChunkOutput> chunks, TracedPhotons ChunkOutput::*member, uint64_t batch_start) {
        if (!active) return;
        std::vector<size_t> offsets(chunks.size() + 1, count);
        size_t used = 0;  // chunks that contribute
        for (size_t c = 0; c < chunks.size() && active; ++c) {
            TracedPhotons& traced = chunks[c].*member;
            if (count + traced.size() >= target) {
                traced.resize(target - count);
                if (!traced.empty()) emitted = batch_start + traced.back().path + 1 - first;
                active = false;
            }
            count += traced.size();
            offsets[c + 1] = count;
            used = c + 1;
        }
        photons.resize(count);
        std::vector<double> sums(used, 0.0);
        tbb::parallel_for(size_t(0), used, [&](size_t c) {
            Photon* out = photons.data() + offsets[c];
            for (const TracedPhoton& t : chunks[c].*member) {
                *out++ = t.photon;
                sums[c] += static_cast<double>(luminance(t.photon.flux()));
            }
        });
        for (const double sum : sums) flux_sum += sum;  // in chunk order: the same on every run
    }

    /// Photons emitted for this map when `total` have been emitted in all.
    uint64_t emitted_of(uint64_t total) const { return total - first; }
    /// Drops the photons collected so far: the map counts from emission `at` on.
    void restart(uint64_t at) {
        count = 0;
        flux_sum = 0.0;
        photons.clear();
        first = at;
    }

    /// Calls f(photon) for every stride-th photon in emission order (the 0th, the stride-th, ...).
    template <typename F>
    void for_each_strided(size_t stride, F&& f) const {
        for (size_t i = 0; i < count; i += stride) f(photons[i]);
    }
};

/// Traces photon `index` and appends what it stores to `out`: global and volume photons along
/// whole paths (`want_global`, `want_volume`), caustic photons along L S+ D paths.
void trace_one_photon(const RenderScene& rs, const PhotonTracingSettings& settings, const RngStreamFamily& streams,
                      uint64_t index, uint32_t path_in_batch, bool want_global, bool want_caustic, bool want_volume,
                      ChunkOutput& out) {
    Rng rng = streams.stream(index);  // Rng::for_stream(settings.seed, kPhotonStreamTag, index)
    const float u_select = rng.next_float();
    const Vec2 u_position = rng.next_vec2();
    const Vec2 u_direction = rng.next_vec2();
    // With a global map under an environment, final gathering collects the diffuse sky, also
    // through specular surfaces (RenderScene::diffuse_sky): caustic photons then come from the
    // other lights and the sky's peaks only.
    const bool sky_gathered = settings.global_photons > 0 && rs.lights_with_sky_peaks;
    // Whole paths: for the global or the volume map; else only caustic paths are wanted.
    const bool whole_paths = want_global || want_volume;
    const LightSet& lights = !whole_paths && sky_gathered ? *rs.lights_with_sky_peaks : *rs.lights;
    // Photons for the caustic map alone are aimed at its casters (core/light/emission_focus.h).
    const EmissionFocus* focus = !whole_paths && rs.caustic_casters ? &rs.caustic_focus : nullptr;
    // Their choice of a focus sphere draws one more number: whole paths keep their streams.
    const float u_focus = focus ? rng.next_float() : 0.0f;
    const std::optional<EmissionSample> emission = lights.sample_emission(u_select, u_position, u_direction, focus, u_focus);
    if (!emission || is_black(emission->flux_weight)) return;
    if (want_caustic && whole_paths && sky_gathered && lights.kind(emission->light) == LightKind::Environment) {
        const EnvironmentLight* peaks = rs.lights_with_sky_peaks->environment();
        if (!peaks || is_black(peaks->radiance(-emission->direction))) want_caustic = false;
    }

    Color flux = emission->flux_weight;
    Ray ray{emission->origin, emission->direction};
    if (glm::dot(emission->normal, emission->normal) > 0.0f)
        ray.origin = rs.tracer->offset_origin(emission->origin, emission->normal, emission->direction);
    int specular_bounces = 0;  // ideal specular and sharply glossy ones (Bsdf::continues_caustic)
    bool glossy_seen = false;
    bool diffuse_seen = false;
    // For the caustic map alone, a photon that no specular surface lies ahead of stores nothing.
    if (!whole_paths && rs.caustic_casters && !rs.caustic_casters->occluded(ray)) return;
    // In a scattering atmosphere, free flights by a hero channel drawn once for the photon, and
    // what it stores divided by the channel average of the pdf ratios (sample_free_flight), as
    // path tracing does.
    // Solids that scatter inside (Material::interior_scatters) are media of their own.
    const std::optional<HomogeneousMedium>& atmosphere = rs.scene->atmosphere;
    const bool media = atmosphere || rs.scattering_interiors;
    const int hero = media ? std::min(2, static_cast<int>(rng.next_float() * 3.0f)) : 0;
    Color spectral(1.0f);
    const auto stored_flux = [&](const Color& f) { return media ? f / average(spectral) : f; };
    // Russian roulette after an event that takes the photon's flux to `next`: survive with the
    // ratio of what it would store then to `stored_before` (what it stored before the event),
    // so that surviving photons keep about the same flux.
    const auto survives = [&](const Color& next, const Color& stored_before) {
        const float survive = std::min(1.0f, max_component(stored_flux(next)) / max_component(stored_before));
        if (!(survive > 0.0f) || rng.next_float() >= survive) return false;
        flux = next * (1.0f / survive);
        return is_finite(flux);
    };

    for (int bounce = 0; bounce < settings.max_bounces; ++bounce) {
        ++out.rays;
        const std::optional<Hit> hit = rs.tracer->intersect(ray);
        std::optional<SurfaceInteraction> hit_point;
        if (hit) hit_point = make_interaction(*rs.scene, *hit, ray.direction);
        // The medium on the way, as path tracing takes it (path.cpp): the solid's own where the
        // segment ends inside a transmissive material that scatters, else the atmosphere.
        std::optional<HomogeneousMedium> interior;
        if (rs.scattering_interiors && hit_point && segment_inside_solid(*rs.scene, *hit_point) &&
            rs.scene->materials[hit_point->material].interior_scatters())
            interior = rs.scene->materials[hit_point->material].interior_medium();
        const HomogeneousMedium* medium = interior ? &*interior : atmosphere ? &*atmosphere : nullptr;
        if (medium) {
            const MediumSpan span = interior ? MediumSpan{ray.tmin, hit->t}
                                             : atmosphere_span(*rs.scene, ray, hit_point ? &*hit_point : nullptr);
            if (!span.empty() && !medium->scatters()) {
                flux *= medium->transmittance(span.t1 - span.t0);
            } else if (!span.empty()) {
                const FreeFlight flight = sample_free_flight(*medium, span.t1 - span.t0, hero, rng.next_float());
                const Color before = stored_flux(flux);
                spectral *= flight.pdf_ratio;
                if (!flight.scattered) {
                    flux *= flight.weight;
                } else {
                    // A scattering event: the photon is stored with the flux it scatters
                    // (estimate_in_scattering), then goes on by the phase function.
                    const Vec3 x = ray.origin + (span.t0 + flight.t) * ray.direction;
                    const Color next = flux * flight.weight;
                    const uint8_t flags = static_cast<uint8_t>((bounce == 0 ? photon_flags::kDirect : 0) |
                                                               (interior ? photon_flags::kInterior : 0));
                    if (want_volume)
                        out.volume.push_back({make_photon(x, ray.direction, stored_flux(next), flags), path_in_batch});
                    diffuse_seen = true;
                    if (!whole_paths || !survives(next, before)) return;
                    ray = Ray{x, sample_henyey_greenstein(medium->g, -ray.direction, rng.next_vec2())};
                    continue;
                }
            }
        }
        if (!hit) return;
        const SurfaceInteraction& si = *hit_point;
        const Vec3 wo = -ray.direction;  // towards where the photon came from
        if (!interior && rs.scene->materials[si.material].has_volume()) {  // a free flight took it
            flux *= volume_transmittance(*rs.scene, si);
            if (is_black(flux)) return;
        }
        const Bsdf bsdf = make_bsdf(rs, si, wo);
        // Stored wherever the material has a non-delta lobe somewhere, not only where this texel
        // has one: an estimate elsewhere on the surface counts the photons of the texels around it.
        if (rs.photon_storing_materials[si.material]) {
            const bool caustic_path = specular_bounces > 0 && !diffuse_seen;
            const uint8_t flags = static_cast<uint8_t>(
                (bounce == 0 ? photon_flags::kDirect : 0) | (caustic_path ? photon_flags::kCaustic : 0) |
                (caustic_path && glossy_seen ? photon_flags::kGlossyCaustic : 0));
            const Vec3 normal = glm::dot(si.surface_normal, wo) >= 0.0f ? si.surface_normal : -si.surface_normal;
            const TracedPhoton photon{make_photon(si.p, ray.direction, stored_flux(flux), flags, normal), path_in_batch};
            if (want_global) out.global.push_back(photon);
            if (want_caustic && caustic_path) out.caustic.push_back(photon);
        }
        // Only caustic paths wanted, and no specular or glossy way on from here: no need to sample it.
        if (!whole_paths && !bsdf.may_continue_caustic()) return;
        const float u_lobe = bsdf.samples_lobe_choice() ? rng.next_float() : 0.0f;
        const Vec2 u = rng.next_vec2();
        const std::optional<BsdfSample> s = bsdf.sample(wo, u_lobe, u, TransportMode::Importance);
        if (!s || !(s->pdf > 0.0f)) return;
        // Caustic paths are L S+ D with S ideal specular or sharp glossy (kSharpGlossyRoughness):
        // the final gather leaves what such bounces bring from the lights to the caustic map
        // (FinalGatherer::gather).
        if (!bsdf.continues_caustic(s->kind)) {
            diffuse_seen = true;
            if (!whole_paths) return;  // only caustic paths are wanted, and this is none any more
        } else {
            ++specular_bounces;
            glossy_seen = glossy_seen || s->kind == LobeKind::Glossy;
        }
        // Russian roulette on the reflectivity of the chosen component.
        if (!survives(flux * s->weight, stored_flux(flux))) return;
        ray = spawn_ray(rs, si, s->wi);
    }
}

/// Spreads the low 10 bits of v so that two zero bits follow each (a Morton code's axis).
uint32_t spread_bits(uint32_t v) {
    v &= 0x3ffu;
    v = (v | (v << 16)) & 0x030000ffu;
    v = (v | (v << 8)) & 0x0300f00fu;
    v = (v | (v << 4)) & 0x030c30c3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

/// Where irradiance is precomputed: a global photon's position and surface normal.
struct IrradianceSite {
    Vec3 position;
    Vec3 normal;
};

/// The stride of a map's irradiance sites: every `stride`-th photon, wider where that would give
/// more than kMaxIrradianceSites sites, but never past half the photons of an estimate (`k`), so
/// that the sites stay closer together than an estimate's radius and the nearest one still
/// stands for the point looked up. The precomputation's cost then stops growing with the map
/// (10M photons: every 20th instead of every 4th, 0.5M estimates instead of 2.5M).
uint32_t site_stride(size_t photons, uint32_t stride, uint32_t k) {
    if (stride == 0) return 0;
    const size_t widened = (photons + kMaxIrradianceSites - 1) / kMaxIrradianceSites;
    return static_cast<uint32_t>(std::max<size_t>(stride, std::min<size_t>(widened, std::max<uint32_t>(k / 2, 1))));
}

/// Every stride-th traced photon of `traced`, in photon order, as an irradiance site. Taken
/// before the map's kd-tree is built in the photons' array, which reorders it.
std::vector<IrradianceSite> irradiance_sites(const MapBuilder& traced, uint32_t stride) {
    std::vector<IrradianceSite> sites;
    if (stride == 0) return sites;
    sites.reserve((traced.count + stride - 1) / stride);
    traced.for_each_strided(stride, [&](const Photon& p) { sites.push_back({p.position, p.normal()}); });
    return sites;
}

/// The indices of `sites` sorted by the Morton code of their positions in the sites' bounds
/// (ties by index, so the order is the same on every run).
std::vector<uint32_t> morton_order(const std::vector<IrradianceSite>& sites) {
    Bounds3 bounds;
    for (const IrradianceSite& site : sites) bounds.extend(site.position);
    const Vec3 extent = glm::max(bounds.extent(), Vec3(1e-30f));
    std::vector<std::pair<uint32_t, uint32_t>> keyed(sites.size());
    tbb::parallel_for(size_t(0), sites.size(), [&](size_t i) {
        const Vec3 cell = glm::clamp((sites[i].position - bounds.lower) / extent, 0.0f, 1.0f) * 1023.0f;
        const uint32_t code = (spread_bits(static_cast<uint32_t>(cell.x)) << 2) |
                              (spread_bits(static_cast<uint32_t>(cell.y)) << 1) | spread_bits(static_cast<uint32_t>(cell.z));
        keyed[i] = {code, static_cast<uint32_t>(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    std::vector<uint32_t> order(sites.size());
    for (size_t j = 0; j < keyed.size(); ++j) order[j] = keyed[j].second;
    return order;
}

/// Irradiance at each site, estimated from `global` (the global map, or the caustic one), packed
/// with its estimate's radius (make_irradiance_site; max_radius where fewer than k photons were
/// within it: the estimate then spread over the whole disc).
std::shared_ptr<const PhotonMap> precompute_irradiance(const PhotonMap& global, const std::vector<IrradianceSite>& sites,
                                                       uint32_t k, float max_radius) {
    std::vector<Photon> points(sites.size());
    // Estimated in spatial (Morton) order rather than photon order: neighbouring estimates then
    // walk the same kd-tree nodes and photons while they are in cache.
    const std::vector<uint32_t> order = morton_order(sites);
    // Each estimate's search starts from the previous one's radius in its block, widened a
    // little (PhotonMap::estimate_irradiance). The blocks are fixed, not the scheduler's ranges:
    // the hint decides the order in which an estimate meets its photons, and so the last bits of
    // its sum, which must not depend on the thread count.
    const size_t blocks = (sites.size() + kHintBlock - 1) / kHintBlock;
    tbb::parallel_for(size_t(0), blocks, [&](size_t block) {
        float hint = 0.0f;
        for (size_t j = block * kHintBlock; j < std::min(sites.size(), (block + 1) * kHintBlock); ++j) {
            const size_t i = order[j];
            const IrradianceSite& site = sites[i];
            hint *= kRadiusHintWidening;
            const Color e = global.estimate_irradiance(site.position, site.normal, k, max_radius, 0, &hint);
            points[i] = make_irradiance_site(site.position, site.normal, e, hint > 0.0f ? hint : max_radius);
        }
    });
    return std::make_shared<const PhotonMap>(std::move(points), 0);
}

/// The traced photons, their flux divided by the photons emitted for the map, become the map;
/// its kd-tree is built in their array.
std::shared_ptr<const PhotonMap> finish_map(MapBuilder& builder) {
    const double scale = builder.emitted > 0 ? 1.0 / static_cast<double>(builder.emitted) : 0.0;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, builder.count, 1u << 14), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) builder.photons[i].scale_flux(scale);
    });
    return std::make_shared<const PhotonMap>(std::exchange(builder.photons, {}), builder.emitted);
}

/// The caustic map's visibility test (photon_tracer.h): the largest ratio, over the caustic
/// photons at `sites`, of the caustic irradiance (`caustic`, k photons an estimate) to all the
/// irradiance the global map finds there; infinity where the global map finds none.
double caustic_peak_ratio(const PhotonMap& caustic, const PhotonMap& global, const std::vector<IrradianceSite>& sites,
                          uint32_t k, const PhotonTracingSettings& settings, float scene_radius) {
    std::vector<double> ratios(sites.size(), 0.0);
    tbb::parallel_for(size_t(0), sites.size(), [&](size_t i) {
        const IrradianceSite& site = sites[i];
        const double e_caustic = luminance(
            caustic.estimate_irradiance(site.position, site.normal, k, kCausticRadiusShare * scene_radius));
        const double e_all = luminance(global.estimate_irradiance(site.position, site.normal, settings.k_irradiance,
                                                                  kIrradianceRadiusShare * scene_radius));
        if (e_caustic > 0.0) ratios[i] = e_all > 0.0 ? e_caustic / e_all : std::numeric_limits<double>::infinity();
    });
    double peak = 0.0;
    for (const double r : ratios) peak = std::max(peak, r);
    return peak;
}

/// Records that the caustic map's visibility test ran (its peak ratio already in `stats`);
/// true, and the map marked dropped, when its light would not show anywhere.
bool caustic_test_drops(PhotonTracingStatistics& stats) {
    stats.caustic_tested = true;
    stats.caustic_dropped = stats.caustic_peak_ratio < kInvisibleCausticRatio;
    return stats.caustic_dropped;
}

/// The caustic photons traced so far packed into a map of their own (the traced ones stay), their
/// flux divided by the `emitted` photons so far: the visibility test's map while tracing goes on.
PhotonMap partial_map(const MapBuilder& builder, uint64_t emitted) {
    std::vector<Photon> packed(builder.photons.begin(), builder.photons.begin() + builder.count);
    const double scale = emitted > 0 ? 1.0 / static_cast<double>(emitted) : 0.0;
    for (Photon& p : packed) p.scale_flux(scale);
    return PhotonMap(std::move(packed), emitted);
}

/// Every n-th photon of `builder`, n chosen so that at most kCausticTestSites are taken.
std::vector<IrradianceSite> caustic_test_sites(const MapBuilder& builder) {
    const uint32_t stride = static_cast<uint32_t>(std::max<size_t>(1, (builder.count + kCausticTestSites - 1) / kCausticTestSites));
    return irradiance_sites(builder, stride);
}

}  // namespace

double caustic_flux_share(const PhotonMaps& maps) {
    if (!maps.global || !maps.caustic) return 0.0;
    const auto total = [](const PhotonMap& map) {
        double sum = 0.0;
        for (const Photon& p : map.tree().photons()) sum += static_cast<double>(luminance(p.flux()));
        return sum;
    };
    const double global = total(*maps.global);
    return global > 0.0 ? total(*maps.caustic) / global : 0.0;
}

Expected<PhotonMaps> trace_photons(const RenderScene& rs, const PhotonTracingSettings& settings) {
    if (rs.lights->empty())
        return Error{"photon pass: the scene has no light with positive power, so no photon can be emitted"};
    const Clock::time_point start = Clock::now();
    MapBuilder global, caustic, volume;
    global.target = settings.global_photons;
    caustic.target = settings.caustic_photons;
    // The volume map: only where the atmosphere or a solid's inside scatters light.
    const bool scattering_atmosphere = rs.scene->atmosphere && rs.scene->atmosphere->scatters();
    volume.target = scattering_atmosphere || rs.scattering_interiors ? settings.volume_photons : 0;
    for (MapBuilder* m : {&global, &caustic, &volume}) {
        m->active = m->target > 0;
        m->cap = static_cast<uint64_t>(m->target) * settings.max_emitted_per_stored;
        // Reserved whole, touched as photons arrive: no copy when the array grows.
        m->photons.reserve(m->target);
    }

    PhotonMaps maps;
    PhotonTracingStatistics& stats = maps.statistics;
    const float scene_radius = rs.scene->bounds.radius();
    // The global map is built as soon as it is full when the caustic map goes on (its test needs
    // it), else after tracing; the irradiance sites are taken before its traced photons go.
    std::vector<IrradianceSite> sites;
    double early_build_seconds = 0.0;  // the global map's build inside the tracing loop
    const auto finish_global = [&] {
        const Clock::time_point t = Clock::now();
        sites = irradiance_sites(global, site_stride(global.count, settings.irradiance_stride, settings.k_irradiance));
        maps.global = finish_map(global);
        return std::chrono::duration<double>(Clock::now() - t).count();
    };
    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    uint64_t emitted = 0;
    bool cancelled = false;
    const RngStreamFamily streams(settings.seed, kPhotonStreamTag);
    std::vector<ChunkOutput> chunks;
    // The photons emitted, and each map's count, when the maps being collected last changed: a
    // photon for the caustic map alone is aimed at its casters (core/light/emission_focus.h) and
    // stores at another rate than one traced along its whole path.
    uint64_t regime_emitted = 0;
    uint64_t last_batch = 0;
    std::array<size_t, 3> regime_counts{};
    std::array<bool, 3> regime_wants{};
    while ((global.active || caustic.active || volume.active) && !cancelled) {
        const std::array<bool, 3> wants{global.active, caustic.active, volume.active};
        if (wants != regime_wants) {
            regime_wants = wants;
            regime_emitted = emitted;
            regime_counts = {global.count, caustic.count, volume.count};
        }
        // Size the next batch from the store rate since then (deterministic: it depends only on
        // the maps' contents), within [16K, 1M] photons: enough for the map that fills first, so
        // that photons past its fill point are not traced for it (the caustic map usually needs
        // ten times the emissions; after the global map fills, its photons trace cheaply), and
        // storing at most 1 / kBatchesPerMap of any map. The first batch of each regime is the
        // smallest, to measure its rate.
        uint64_t batch = 16384;
        if (emitted > regime_emitted) {
            double needed_first = 1048576.0, largest = 1048576.0;
            const std::array<const MapBuilder*, 3> builders{&global, &caustic, &volume};
            for (size_t i = 0; i < builders.size(); ++i) {
                const MapBuilder* m = builders[i];
                const size_t stored = m->count - regime_counts[i];
                if (!m->active || stored == 0) continue;
                const double rate = static_cast<double>(stored) / static_cast<double>(emitted - regime_emitted);
                needed_first = std::min(needed_first, 1.1 * static_cast<double>(m->target - m->count) / rate);
                largest = std::min(largest, static_cast<double>(m->target) / kBatchesPerMap / rate);
            }
            // A rate measured on a handful of photons may be far off: grow by kBatchGrowth at most.
            largest = std::min(largest, kBatchGrowth * static_cast<double>(last_batch));
            batch = std::clamp<uint64_t>(static_cast<uint64_t>(needed_first), batch,
                                         std::max<uint64_t>(batch, static_cast<uint64_t>(largest)));
        }
        const bool want_global = global.active, want_caustic = caustic.active, want_volume = volume.active;
        const size_t chunk_count = (batch + kChunkSize - 1) / kChunkSize;
        // Chunk buffers are kept from batch to batch: their capacity is reused, not reallocated.
        if (chunks.size() < chunk_count) chunks.resize(chunk_count);
        // Size the buffers from the store rate so far (growing them photon by photon is copying
        // and page faults); they keep their capacity from batch to batch.
        const auto expected = [&](const MapBuilder& m) {
            if (!m.active) return size_t(0);
            // First guess: a global or volume photon per emission; caustic photons are rarer.
            if (emitted == 0) return &m == &caustic ? size_t(0) : size_t(kChunkSize);
            return static_cast<size_t>(1.2 * kChunkSize * static_cast<double>(m.count) / static_cast<double>(emitted)) + 16;
        };
        const size_t expected_global = expected(global), expected_caustic = expected(caustic),
                     expected_volume = expected(volume);
        for (size_t c = 0; c < chunk_count; ++c) {
            chunks[c].global.clear();
            chunks[c].caustic.clear();
            chunks[c].volume.clear();
            chunks[c].global.reserve(expected_global);
            chunks[c].caustic.reserve(expected_caustic);
            chunks[c].volume.reserve(expected_volume);
            chunks[c].rays = 0;
        }
        arena.execute([&] {
            tbb::parallel_for(size_t(0), chunk_count, [&](size_t c) {
                if (settings.cancel && settings.cancel->load(std::memory_order_relaxed)) return;
                enable_flush_denormals();
                const uint64_t first = c * kChunkSize;
                const uint64_t last = std::min<uint64_t>(first + kChunkSize, batch);
                for (uint64_t i = first; i < last; ++i) {
                    trace_one_photon(rs, settings, streams, emitted + i, static_cast<uint32_t>(i), want_global,
                                     want_caustic, want_volume, chunks[c]);
                }
            });
        });
        if (settings.cancel && settings.cancel->load()) cancelled = true;
        const std::span<ChunkOutput> batch_chunks(chunks.data(), chunk_count);
        for (const ChunkOutput& c : batch_chunks) stats.rays += c.rays;
        arena.execute([&] {
            global.append(batch_chunks, &ChunkOutput::global, emitted);
            caustic.append(batch_chunks, &ChunkOutput::caustic, emitted);
            volume.append(batch_chunks, &ChunkOutput::volume, emitted);
        });
        emitted += batch;
        last_batch = batch;
        // A caustic map that carries next to no light is not worth its emissions: stop it.
        if (caustic.active && global.target > 0 && !global.active && global.emitted > 0 && global.flux_sum > 0.0 &&
            caustic.count >= kCausticShareMinPhotons) {
            const double share = (caustic.flux_sum / static_cast<double>(caustic.emitted_of(emitted))) /
                                 (global.flux_sum / static_cast<double>(global.emitted));
            if (share < kNegligibleCausticShare) {
                caustic.active = false;
                caustic.complete = false;
                caustic.emitted = caustic.emitted_of(emitted);
            }
        }
        for (MapBuilder* m : {&global, &caustic, &volume}) {
            // A map that nothing reached after a fair trial will not fill: stop early.
            const uint64_t for_map = m->emitted_of(emitted);
            const bool hopeless = m->count == 0 && for_map >= std::max<uint64_t>(kEmptyMapTrial, m->target);
            if (m->active && (for_map >= m->cap || hopeless)) {  // keep what arrived, say so
                m->active = false;
                m->complete = false;
                m->emitted = for_map;
            }
        }
        // Only the caustic map left, and its photons aimed at the casters from now on: the few
        // caustic photons whole paths stored each carry a whole share of a light's flux, next to
        // the many aimed ones that carry a cone's; kept together, those few would stand out as
        // blotches in its estimates. The map starts again with aimed photons alone.
        if (caustic.active && caustic.first == 0 && rs.caustic_casters && !global.active && !volume.active &&
            (global.target > 0 || volume.target > 0))
            caustic.restart(emitted);
        // The global map full and the caustic map still collecting: build the global one now,
        // and test whether the caustic light would show once the caustic map holds enough
        // photons for estimates of its final radii (photon_tracer.h).
        if (caustic.active && global.target > 0 && !global.active && !maps.global)
            arena.execute([&] { early_build_seconds = finish_global(); });
        const uint64_t needed_for_test =
            (static_cast<uint64_t>(caustic.target) * kCausticTestMinPhotons + kCausticTestPhotons - 1) / kCausticTestPhotons;
        if (caustic.active && maps.global && !stats.caustic_tested && caustic.count >= needed_for_test) {
            const uint32_t k = static_cast<uint32_t>(std::clamp<uint64_t>(
                (uint64_t(kCausticTestPhotons) * caustic.count + caustic.target / 2) / caustic.target,
                kCausticTestMinPhotons, kCausticTestPhotons));
            const PhotonMap partial = partial_map(caustic, caustic.emitted_of(emitted));
            arena.execute([&] {
                stats.caustic_peak_ratio =
                    caustic_peak_ratio(partial, *maps.global, caustic_test_sites(caustic), k, settings, scene_radius);
            });
            if (caustic_test_drops(stats)) {
                caustic.active = false;
                caustic.complete = false;
                caustic.emitted = caustic.emitted_of(emitted);
            }
        }
    }
    if (cancelled) return Error{"photon pass: cancelled"};
    stats.emitted = emitted;
    stats.tracing_seconds = std::chrono::duration<double>(Clock::now() - start).count() - early_build_seconds;
    // An empty global map means no light reaches a diffuse surface: the image cannot be right.
    // An empty caustic map only means that no light focuses (PhotonTracingStatistics says so).
    if (global.target > 0 && global.count == 0) {
        return Error{"photon pass: no photon reached a surface that stores it for the global map after " +
                     std::to_string(emitted) +
                     " photons were emitted (lights facing away from the scene, or nothing reflects)"};
    }
    stats.emitted_global = global.emitted;
    stats.emitted_caustic = caustic.emitted;
    stats.stored_global = global.count;
    stats.stored_caustic = caustic.count;
    stats.global_complete = global.complete;
    stats.caustic_complete = caustic.complete;
    stats.emitted_volume = volume.emitted;
    stats.stored_volume = volume.count;
    stats.volume_complete = volume.complete;

    const Clock::time_point build_start = Clock::now();
    // A caustic map not tested yet (it filled or stopped before the global map was full, or the
    // global map came last) is tested whole, with the render's photons per estimate.
    const bool test_at_end = caustic.target > 0 && caustic.count > 0 && global.target > 0 && !stats.caustic_tested;
    const std::vector<IrradianceSite> caustic_sites = test_at_end ? caustic_test_sites(caustic) : std::vector<IrradianceSite>{};
    const std::vector<IrradianceSite> caustic_irradiance_sites =
        stats.caustic_dropped ? std::vector<IrradianceSite>{}
                              : irradiance_sites(caustic, site_stride(caustic.count, settings.irradiance_stride, kCausticTestPhotons));
    arena.execute([&] {
        tbb::parallel_invoke([&] { if (global.target > 0 && !maps.global) finish_global(); },
                             [&] { if (caustic.target > 0 && !stats.caustic_dropped) maps.caustic = finish_map(caustic); },
                             [&] { if (volume.target > 0) maps.volume = finish_map(volume); });
    });
    if (test_at_end) {
        const uint32_t k = static_cast<uint32_t>(std::min<uint64_t>(kCausticTestPhotons, caustic.count));
        arena.execute([&] {
            stats.caustic_peak_ratio = caustic_peak_ratio(*maps.caustic, *maps.global, caustic_sites, k, settings, scene_radius);
        });
        if (caustic_test_drops(stats)) maps.caustic = nullptr;
    }
    stats.build_seconds = std::chrono::duration<double>(Clock::now() - build_start).count() + early_build_seconds;
    if (maps.global && settings.irradiance_stride > 0) {
        const Clock::time_point irradiance_start = Clock::now();
        const float max_radius = kIrradianceRadiusShare * rs.scene->bounds.radius();
        arena.execute([&] { maps.irradiance = precompute_irradiance(*maps.global, sites, settings.k_irradiance, max_radius); });
        stats.irradiance_photons = maps.irradiance->size();
        // The caustic map's too, with the render's photons per caustic estimate: where it is a
        // small part of the global one's, estimates at visible points may skip the caustic map.
        if (maps.caustic && !caustic_irradiance_sites.empty()) {
            arena.execute([&] {
                maps.caustic_irradiance = precompute_irradiance(*maps.caustic, caustic_irradiance_sites, kCausticTestPhotons,
                                                                kCausticRadiusShare * scene_radius);
            });
            stats.irradiance_photons += maps.caustic_irradiance->size();
        }
        stats.irradiance_seconds = std::chrono::duration<double>(Clock::now() - irradiance_start).count();
    }
    return maps;
}

}  // namespace photond
