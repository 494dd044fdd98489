#include "core/integrators/final_gather.h"

#include <limits>
#include <vector>

#include "core/integrators/direct.h"
#include "core/integrators/volume_radiance.h"

namespace photond {

GatherGrid GatherGrid::for_rays(uint32_t rays) {
    // N ~ pi M (Ward): M = sqrt(rays / pi), N = rays / M.
    GatherGrid g;
    g.m = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(rays) / 3.14159265358979))));
    g.n = std::max(1, static_cast<int>(std::lround(static_cast<double>(rays) / g.m)));
    return g;
}

FinalGatherer::FinalGatherer(std::shared_ptr<const RenderScene> scene, std::shared_ptr<const PhotonMaps> maps,
                             const GatherSettings& settings,
                             std::shared_ptr<const CausticVisibility> caustic_visibility)
    : scene_(std::move(scene)), maps_(std::move(maps)), settings_(settings),
      caustic_visibility_(std::move(caustic_visibility)),
      grid_(GatherGrid::for_rays(settings.rays)) {
    if (settings_.max_radius <= 0.0f) settings_.max_radius = 0.2f * scene_->scene->bounds.radius();
    site_radius_cap_ = kIrradianceRadiusShare * scene_->scene->bounds.radius();
    if (settings_.max_radius_caustic <= 0.0f) settings_.max_radius_caustic = kCausticRadiusShare * scene_->scene->bounds.radius();
    site_reach_ = maps_->irradiance ? site_search_radius(*maps_->irradiance, settings_.max_radius) : settings_.max_radius;
}

namespace {

/// The microfacet lobes of LobeKind::Diffuse (rough glass, metal, dielectric layer and coat as
/// rough as diffuse), without the Lambertian one.
constexpr LobeMask kRoughLobes = mask_of(LobeKind::Diffuse) | kExcludeLambertian;

/// Photons of an estimate at a gather hit on a normal-mapped surface read as diffuse.
constexpr uint32_t kBentNormalPhotons = 32;

/// Bounces one ray traces by the short-ray rule (GatherSettings::short_ray_radii), in all its
/// branches together, before it reads the photons wherever it lands. A glossy ray from a visible
/// point: 4, as a contact's gap sends rays back and forth between its two surfaces, each bounce
/// reflecting a share of the light (glossy-objects' torus base against path: +1.9 % with 4, +13 %
/// with 1). A gather ray of an irradiance record: 1, as the record holds each ray's noise for
/// every pixel it covers, and further bounces sample bright patches of direct light beside a
/// contact by chance (foggy-room, seed 102: relMSE 0.0020 without the rule, 0.0021 with 1,
/// 0.0048 with 2 or 4, a bright blotch beside the sphere).
constexpr int kGlossyRayShortRayBounces = 4;
constexpr int kRecordShortRayBounces = 1;

/// The cosine a gather ray's cell is taken to have at least, for its cone's spread: the cells
/// next to the horizon are thin slivers, not the wide cones 1 / cos would make of them.
constexpr float kMinGatherCosine = 0.1f;

/// The nearest irradiance site on the side a hit is seen from (PhotonMap::nearest_irradiance).
struct NearestSite {
    bool found = false;
    Color irradiance{0.0f};
    float radius = 0.0f;
};

/// Radiance leaving a non-delta surface towards wo, from the photon maps: precomputed
/// irradiance times rho / pi where every lobe is diffuse or as rough as the photon passes take
/// for diffuse (the rough metal and dielectric layer of most glTF materials: read by their
/// albedo at wo, exact under uniform light, instead of evaluating the BSDF per photon); for rough
/// glass of any roughness, the same from both sides (one lobe sample picks the side and carries
/// the lobes' weight); else the global map's estimate.
/// `exclude_flags`: photons the estimate leaves out (where it falls back to one). `front_site`:
/// the nearest site on wo's side, when the caller has looked it up already. `site_reach`: how
/// far to search for a site (FinalGatherer::site_reach_).
Color radiance_from_photons(const PhotonMaps& maps, const SurfaceInteraction& si, const Bsdf& bsdf,
                            const Vec3& wo, const GatherSettings& settings, float site_reach, Rng& rng,
                            LobeMask lobes = kNonDeltaLobes, uint8_t exclude_flags = 0,
                            const NearestSite* front_site = nullptr) {
    if (!maps.global) return Color(0.0f);
    const bool front = glm::dot(si.surface_normal, wo) >= 0.0f;
    const Vec3 n = front ? si.surface_normal : -si.surface_normal;
    // A normal map bends the shading normal: the precomputed irradiance (about the unbent
    // normal) would light the surface as if flat, and brighten what it lights in turn.
    const Vec3 bent = bent_shading_normal(si, front);
    if (maps.irradiance && bent == Vec3(0.0f)) {
        Color e;
        if (bsdf.reads_as_diffuse(lobes)) {
            if (front_site ? front_site->found : maps.irradiance->nearest_irradiance(si.p, n, site_reach, &e))
                return bsdf.diffuse_like_reflectance(wo) * kInvPi * (front_site ? front_site->irradiance : e);
        } else if (bsdf.reads_as_diffuse_from_both_sides(lobes) || (bsdf.transmits_non_delta(lobes) && exclude_flags == 0)) {
            // Rough glass: each side's incident light taken as uniform, E_side / pi, exact for
            // uniform light on either side as the albedo read above is. A kNN estimate here
            // evaluated the BSDF for each of k photons, and rough glass's photons lie sparse on
            // small curved solids: most of a glass-heavy scene's gathering time went to them.
            // Glossy glass is read so too where gather rays stop following it
            // (max_glossy_bounces): through its sharp lobe, the few photons that line up with it
            // were fireflies (TransmissionTest's rough yellow sphere, one sample 21 times its
            // pixel's value). Only without excluded photons, as the sites hold them all. A side
            // with no site near takes its own estimate: the two-sided one below would count the
            // other side's photons too.
            const float u_lobe = rng.next_float();
            const Vec2 u = rng.next_vec2();
            const std::optional<BsdfSample> s = bsdf.sample(wo, u_lobe, u, TransportMode::Radiance, lobes);
            if (!s || !(s->pdf > 0.0f) || is_black(s->weight)) return Color(0.0f);
            const Vec3 side = glm::dot(s->wi, n) >= 0.0f ? n : -n;
            if (!maps.irradiance->nearest_irradiance(si.p, side, site_reach, &e))
                e = maps.global->estimate_irradiance(si.p, side, settings.k_global, settings.max_radius);
            return s->weight * kInvPi * e;
        }
    }
    RadianceEstimateOptions options;
    // Where only the bent normal keeps the precomputed irradiance from serving, fewer photons:
    // each gather ray's value is averaged with the others' (the irradiance cache's hundreds).
    const bool diffuse_but_bent = bent != Vec3(0.0f) && bsdf.reads_as_diffuse(lobes);
    options.k = diffuse_but_bent ? std::min(settings.k_global, kBentNormalPhotons) : settings.k_global;
    options.max_radius = settings.max_radius;
    options.lobes = lobes;
    options.exclude_flags = exclude_flags;
    return maps.global->estimate_radiance(si.p, n, bsdf, wo, estimate_options_at(options, si, bsdf, front));
}

}  // namespace

Color FinalGatherer::photon_radiance(const SurfaceInteraction& si, const Bsdf& bsdf, const Vec3& wo, Rng& rng) const {
    return radiance_from_photons(*maps_, si, bsdf, wo, settings_, site_reach_, rng);
}

Color FinalGatherer::gather_ray_radiance(const Ray& ray, Rng& rng, RayCounters& counters, float* distance,
                                         FirstHitEmission* emission, RayFootprint cone) const {
    return trace_gather_ray(ray, rng, counters, distance, emission, false, kGlossyRayShortRayBounces, cone);
}

Color FinalGatherer::trace_gather_ray(const Ray& ray, Rng& rng, RayCounters& counters, float* distance,
                                      FirstHitEmission* emission, bool caustic_chains, int short_ray_bounces,
                                      RayFootprint cone) const {
    const RenderScene& rs = *scene_;
    // Walk through ideal specular surfaces; `depth` counts them. At glossy surfaces the glossy
    // lobes are followed too, and rough glass (up to settings_.max_glossy_bounces): reading them
    // from the photons would evaluate a sharp lobe per photon, whose rare aligned photons are
    // fireflies.
    // While the walk is a caustic chain (`caustic_chains`, and every bounce so far specular or
    // glossy: `from` is null), emitters count nowhere: the caustic map holds that light.
    struct Walker {
        const FinalGatherer& g;
        const RenderScene& rs;
        Rng& rng;
        RayCounters& counters;
        FirstHitEmission* emission;
        bool caustic_chains;
        /// Bounces the short-ray rule may still trace, shared by every walker of the gather ray
        /// (a hit's short-ray bounce and its glossy lobes' ray both go on from it).
        int& short_ray_budget;
        /// Where a ray that samples a glossy lobe started, and the lobe's pdf for it (0 once a
        /// delta bounce followed: then no light sample could have found what it meets).
        struct GlossyOrigin {
            Vec3 point;
            float pdf;
        };
        /// `first`: the gather ray itself (its hit's emission is reported to the caller).
        /// `cone`: the ray's cone from r's origin on; its width at the hit picks the texture
        /// level there, and the rays that go on from the hit widen it further (a glossy lobe
        /// only widens it more: the cone is the narrowest it can be).
        Color along(const Ray& r, RayFootprint cone, int depth, float* first_distance, bool first,
                    int glossy_bounces = 0, const GlossyOrigin* from = nullptr) const {
            const std::optional<Hit> hit = trace_ray(rs, r, counters);
            if (first_distance) *first_distance = hit ? hit->t : std::numeric_limits<float>::infinity();
            std::optional<SurfaceInteraction> hit_point;
            if (hit) hit_point = make_interaction(*rs.scene, *hit, r.direction, cone.texture_at(hit->t), ConeKind::Wide);
            const RayFootprint on = hit ? cone.from(hit->t) : cone;
            // The atmosphere on the way: what lies beyond is seen through it, and it adds all the
            // light it scatters towards the ray (the volume map, first events included).
            Color fog(1.0f), in_scattered(0.0f);
            if (const std::optional<HomogeneousMedium>& atmosphere = rs.scene->atmosphere) {
                const MediumSpan span = atmosphere_span(*rs.scene, r, hit_point ? &*hit_point : nullptr);
                if (!span.empty()) {
                    fog = atmosphere->transmittance(span.t1 - span.t0);
                    if (g.maps_->volume && atmosphere->scatters()) {
                        SampleContext context{rng, counters};
                        in_scattered = volume_in_scattering(*g.maps_->volume, *atmosphere, &rs.scene->bounds, r, span, g.settings_.k_volume,
                                                            g.settings_.max_radius, 0, 1, context);
                    }
                }
            }
            // Inside a solid that scatters: all the light its inside sends (the volume map's photons
            // there); from_surface attenuates what lies beyond (volume_transmittance).
            if (hit_point && g.maps_->volume && rs.scattering_interiors) {
                if (const std::optional<HomogeneousMedium> interior = scattering_interior(*rs.scene, *hit_point)) {
                    SampleContext context{rng, counters};
                    in_scattered += interior_in_scattering(rs, *g.maps_->volume, *interior, r, *hit_point,
                                                           g.settings_.k_volume, g.settings_.max_radius, 1, context);
                }
            }
            const Color beyond = from_surface(r, hit_point ? &*hit_point : nullptr, on, depth, first, glossy_bounces, from);
            if (first && emission) {
                emission->radiance *= fog;  // the emitter is seen through the atmosphere too
                emission->in_scattered = in_scattered;
            }
            return in_scattered + fog * beyond;
        }
        /// What the ray's hit sends back (null: it left the scene), before the atmosphere.
        Color from_surface(const Ray& r, const SurfaceInteraction* hit_point, RayFootprint cone, int depth, bool first,
                           int glossy_bounces, const GlossyOrigin* from) const {
            if (!hit_point) {
                // After a glossy lobe, the whole sky and soft suns, weighted against the light
                // samples taken where the lobe was sampled.
                if (from) return rs.lights->escaped_radiance(r.direction, from->pdf);
                // Also through specular surfaces: caustic photons leave the diffuse sky out
                // (trace_photons), so that this is its only way to a surface.
                if (g.settings_.gather_diffuse_sky && rs.diffuse_sky) return rs.diffuse_sky->radiance(r.direction);
                return Color(0.0f);
            }
            const SurfaceInteraction& si = *hit_point;
            const Vec3 wo = -r.direction;
            if (first && emission) {
                emission->radiance = volume_transmittance(*rs.scene, si) * rs.lights->emitted_radiance(si, wo);
                emission->triangle = si.triangle;
                emission->point = si.p;
            }
            Color radiance(0.0f);
            if (from) {
                const Color emitted = rs.lights->emitted_radiance(si, wo);
                if (!is_black(emitted)) {
                    const float light_pdf =
                        from->pdf > 0.0f ? rs.lights->pdf_incident_triangle(si.triangle, from->point, si.p) : 0.0f;
                    const float weight = from->pdf > 0.0f ? power_heuristic(from->pdf, light_pdf) : 1.0f;
                    radiance += emitted * weight;
                }
            }
            const Bsdf bsdf = make_bsdf(rs, si, wo);
            if (bsdf.has_non_delta()) {
                constexpr LobeMask kGlossy = mask_of(LobeKind::Glossy);
                const bool caustic_chain = caustic_chains && !from && bsdf.continues_caustic(LobeKind::Glossy);
                // A caustic chain's last glossy lobe, where its ray was short, is followed a bounce
                // more (the short-ray rule) instead of read from the lobe's photons below.
                NearestSite site;
                // Rough glass, also as rough as diffuse (LobeKind::Diffuse), is followed as glossy
                // lobes are: read at once, it takes the irradiance on each side of its surface,
                // and few photons reach the inside of a small solid (TransmissionTest's rough
                // stripes read 7 % dark, and grainy). Not in a caustic chain, which rough glass
                // ends.
                const bool follows = glossy_bounces < g.settings_.max_glossy_bounces;
                const bool follows_glass = follows && !caustic_chain && bsdf.transmits_non_delta();
                // The Lambertian lobe where the rough lobes are followed (none on pure glass).
                const auto lambertian = [&] {
                    return max_component(bsdf.diffuse_reflectance()) > 0.0f
                               ? photons_or_bounce(si, bsdf, wo, cone, depth, kLambertianLobe)
                               : Color(0.0f);
                };
                if ((bsdf.lobes() & kGlossy) && (follows || (caustic_chain && takes_short_ray_bounce(si, wo, &site)))) {
                    radiance += glossy_lobes(si, bsdf, wo, cone, depth, glossy_bounces, caustic_chain,
                                             follows_glass ? kGlossy | kRoughLobes : kGlossy);
                    radiance += follows_glass ? lambertian() : photons_or_bounce(si, bsdf, wo, cone, depth, kNonDeltaLobes & ~kGlossy);
                } else if ((bsdf.lobes() & kGlossy) && caustic_chain) {
                    // The chain's last glossy lobe: the photons that came to it through a diffuse
                    // surface (those straight from the lights or through caustic bounces would
                    // continue the caustic chain).
                    radiance += photons_or_bounce(si, bsdf, wo, cone, depth, kNonDeltaLobes & ~kGlossy);
                    radiance += radiance_from_photons(*g.maps_, si, bsdf, wo, g.settings_, g.site_reach_, rng, kGlossy,
                                                      photon_flags::kDirect | photon_flags::kCaustic);
                } else if (follows_glass) {
                    radiance += glossy_lobes(si, bsdf, wo, cone, depth, glossy_bounces, false, kRoughLobes);
                    radiance += lambertian();
                } else {
                    radiance += photons_or_bounce(si, bsdf, wo, cone, depth, kNonDeltaLobes);
                }
            }
            if (bsdf.has_delta() && depth < g.settings_.max_specular_depth) {
                // One lobe per gather ray is enough: the gather averages many rays.
                const GlossyOrigin after_delta{si.p, 0.0f};
                radiance += follow_delta_lobes(bsdf, wo, false, rng, [&](const BsdfSample& s) {
                    return along(spawn_ray(rs, si, s.wi), cone, depth + 1, nullptr, false, glossy_bounces,
                                 from ? &after_delta : nullptr);
                });
            }
            return volume_transmittance(*rs.scene, si) * radiance;
        }
        /// What `lobes` reflect at a non-delta hit of the light arriving from elsewhere: the
        /// photons' estimate, or one bounce traced where the ray that came is short.
        Color photons_or_bounce(const SurfaceInteraction& si, const Bsdf& bsdf, const Vec3& wo, RayFootprint cone,
                                int depth, LobeMask lobes) const {
            if (!(bsdf.lobes() & lobes)) return Color(0.0f);
            NearestSite site;
            if (takes_short_ray_bounce(si, wo, &site)) return short_ray_bounce(si, bsdf, wo, cone, depth, lobes);
            return radiance_from_photons(*g.maps_, si, bsdf, wo, g.settings_, g.site_reach_, rng, lobes, 0,
                                         site.found ? &site : nullptr);
        }
        /// Whether the ray that reached `si` is short next to the radius of the nearest
        /// irradiance site's estimate (GatherSettings::short_ray_radii). Where no site is near
        /// (or the maps have none) the hit reads the photons as before. The site looked up is
        /// left in `site` for the estimate to use.
        bool is_short(const SurfaceInteraction& si, const Vec3& wo, NearestSite* site) const {
            const float factor = g.settings_.short_ray_radii;
            // No site's estimate reaches further than the sites' cap: longer rays are never short.
            if (!(factor > 0.0f) || short_ray_budget <= 0 || !g.maps_->global || !g.maps_->irradiance ||
                !(si.distance < factor * g.site_radius_cap_))
                return false;
            const Vec3 n = glm::dot(si.surface_normal, wo) >= 0.0f ? si.surface_normal : -si.surface_normal;
            site->found = g.maps_->irradiance->nearest_irradiance(si.p, n, g.site_reach_, &site->irradiance,
                                                                  &site->radius);
            return site->found && si.distance < factor * site->radius;
        }
        /// is_short, and if so one bounce of the gather ray's budget spent (and counted).
        bool takes_short_ray_bounce(const SurfaceInteraction& si, const Vec3& wo, NearestSite* site) const {
            if (!is_short(si, wo, site)) return false;
            --short_ray_budget;
            ++counters.short_ray_bounces;
            return true;
        }
        /// Jensen's short-ray rule (GatherSettings::short_ray_radii): what `lobes` reflect at
        /// `si`, as a visible point takes it: a light sample, the caustic map's estimate and one
        /// lobe-sampled ray on (a new path: its glossy bounces count from 0), whose own short hits
        /// trace again while the ray's budget lasts (kGlossyRayShortRayBounces, kRecordShortRayBounces). With a caustic map the ray on counts no
        /// emitter through specular and sharply glossy surfaces (a new caustic chain: the map
        /// holds that light) and none straight ahead (the light sample, unweighted, does);
        /// without one it is weighted against the light sample by the power heuristic, as
        /// glossy lobes are.
        Color short_ray_bounce(const SurfaceInteraction& si, const Bsdf& bsdf, const Vec3& wo, RayFootprint cone,
                               int depth, LobeMask lobes) const {
            SampleContext context{rng, counters};
            const bool caustics = g.maps_->caustic != nullptr;
            Color radiance(0.0f);
            if (caustics) {
                // The diffuse sky, where gather rays see it, is the ray on's (as at a visible point).
                const LightSet& lights =
                    g.settings_.gather_diffuse_sky && rs.lights_with_sky_peaks ? *rs.lights_with_sky_peaks : *rs.lights;
                radiance += sample_direct_light(rs, lights, si, bsdf, wo, context, false, lobes);
            } else {
                radiance += sample_direct_light(rs, *rs.lights, si, bsdf, wo, context, true, lobes);
            }
            const float u_lobe = rng.next_float();
            const Vec2 u = rng.next_vec2();
            const std::optional<BsdfSample> s = bsdf.sample(wo, u_lobe, u, TransportMode::Radiance, lobes);
            if (s && s->pdf > 0.0f && !is_black(s->weight)) {
                const GlossyOrigin origin{si.p, s->pdf};
                const Walker on{g, rs, rng, counters, nullptr, caustics, short_ray_budget};
                radiance += s->weight * on.along(spawn_ray(rs, si, s->wi), cone, depth, nullptr, false, 0,
                                                 caustics ? nullptr : &origin);
            }
            // Last, so that what the hit sends otherwise is known: the caustic map's estimate
            // only where it may show next to it, as at a visible point (it draws no random
            // numbers, so the rest of the path is the same either way).
            if (caustics) {
                const Vec3 n = glm::dot(si.surface_normal, wo) >= 0.0f ? si.surface_normal : -si.surface_normal;
                if (!g.caustic_visibility_ || g.caustic_visibility_->may_show(si.p, n, bsdf, wo, luminance(radiance), lobes))
                    radiance += caustic_estimate(si, bsdf, wo, lobes);
            }
            return radiance;
        }
        /// The caustic map's light reflected by `lobes` at `si`, a short ray's hit: its estimate
        /// from a disc no wider than the ray is long over short_ray_radii, the rule's own bound,
        /// so that it too stays out of light that the surfaces meeting there shadow (a caustic
        /// ring around a sphere's contact). Too few photons there read as none.
        Color caustic_estimate(const SurfaceInteraction& si, const Bsdf& bsdf, const Vec3& wo, LobeMask lobes) const {
            const bool front = glm::dot(si.surface_normal, wo) >= 0.0f;
            RadianceEstimateOptions options;
            options.k = g.settings_.k_caustic;
            options.max_radius = std::min(g.settings_.max_radius_caustic, si.distance / g.settings_.short_ray_radii);
            options.cone_filter = true;
            options.lobes = lobes;
            return g.maps_->caustic->estimate_radiance(si.p, front ? si.surface_normal : -si.surface_normal, bsdf, wo,
                                                       estimate_options_at(options, si, bsdf, front));
        }
        /// The glossy lobes' reflection at a gather hit (or `lobes`', rough glass's), as a path
        /// tracer takes it: a light sample and a lobe sample, weighted by the power heuristic. In
        /// a caustic chain, the lobe sample alone, and the chain goes on.
        Color glossy_lobes(const SurfaceInteraction& si, const Bsdf& bsdf, const Vec3& wo, RayFootprint cone,
                           int depth, int glossy_bounces, bool caustic_chain,
                           LobeMask lobes = mask_of(LobeKind::Glossy)) const {
            SampleContext context{rng, counters};
            Color radiance(0.0f);
            if (!caustic_chain) radiance += sample_direct_light(rs, *rs.lights, si, bsdf, wo, context, true, lobes);
            const float u_lobe = rng.next_float();
            const Vec2 u = rng.next_vec2();
            const std::optional<BsdfSample> s = bsdf.sample(wo, u_lobe, u, TransportMode::Radiance, lobes);
            if (s && s->pdf > 0.0f && !is_black(s->weight)) {
                const GlossyOrigin origin{si.p, s->pdf};
                radiance += s->weight * along(spawn_ray(rs, si, s->wi), cone, depth, nullptr, false, glossy_bounces + 1,
                                              caustic_chain ? nullptr : &origin);
            }
            return radiance;
        }
    };
    if (emission) *emission = FirstHitEmission{};
    int short_ray_budget = short_ray_bounces;
    return Walker{*this, rs, rng, counters, emission, caustic_chains, short_ray_budget}.along(ray, cone, 0, distance, true);
}

GatherResult FinalGatherer::gather(const Vec3& p, const Vec3& n, const Vec3& geometric_normal, Rng& rng,
                                   RayCounters& counters, bool compute_gradients, uint32_t rays) const {
    const RenderScene& rs = *scene_;
    const GatherGrid grid = rays > 0 ? GatherGrid::for_rays(rays) : grid_;
    const int m = grid.m, cells_n = grid.n;
    const Frame frame(n);
    thread_local std::vector<Color> radiance;
    thread_local std::vector<float> distance;
    radiance.assign(static_cast<size_t>(m * cells_n), Color(0.0f));
    distance.assign(static_cast<size_t>(m * cells_n), std::numeric_limits<float>::infinity());
    const auto cell = [cells_n](int j, int k) { return static_cast<size_t>(j * cells_n + k); };

    GatherResult result;
    DVec3 sum(0.0);
    double inverse_distance_sum = 0.0;
    for (int j = 0; j < m; ++j) {
        for (int k = 0; k < cells_n; ++k) {
            const Vec2 u = rng.next_vec2();
            const float sin2 = (static_cast<float>(j) + u.x) / static_cast<float>(m);
            const float sin_theta = std::sqrt(sin2), cos_theta = safe_sqrt(1.0f - sin2);
            const float phi = 2.0f * kPi * (static_cast<float>(k) + u.y) / static_cast<float>(cells_n);
            const Vec3 direction = frame.to_world({sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta});
            // Directions under the geometric surface (tilted shading normals) see nothing.
            if (glm::dot(direction, geometric_normal) <= 0.0f) continue;
            float d = 0.0f;
            // The ray stands for its cell, of projected solid angle pi / cells (solid angle
            // pi / (cells cos theta)): its cone's spread, which filters the textures it meets.
            // A record's cells, also in a gather of fewer rays at a cache miss: the pixel's
            // samples together gather as many rays as a record does.
            const float cell_solid_angle =
                kPi / (static_cast<float>(grid_.m * grid_.n) * std::max(cos_theta, kMinGatherCosine));
            const RayFootprint cone{0.0f, std::sqrt(cell_solid_angle), 1.0f};
            const Color L = trace_gather_ray(Ray{rs.tracer->offset_origin(p, geometric_normal, direction), direction},
                                             rng, counters, &d, nullptr, maps_->caustic != nullptr, kRecordShortRayBounces,
                                             cone);
            radiance[cell(j, k)] = L;
            distance[cell(j, k)] = d;
            sum += DVec3(L);
            if (std::isfinite(d) && d > 0.0f) inverse_distance_sum += 1.0 / d;
            ++result.rays;
        }
    }
    const double cells = static_cast<double>(m) * cells_n;
    result.irradiance = Color(sum * (3.14159265358979323846 / cells));
    result.harmonic_mean_distance = inverse_distance_sum > 0.0 ? static_cast<float>(cells / inverse_distance_sum)
                                                               : std::numeric_limits<float>::infinity();
    if (!compute_gradients) return result;

    // Rotation gradient (Ward & Heckbert 1992): pi / (M N) sum_k v_k sum_j tan(theta_j) L_jk, v_k the
    // tangent at azimuth phi_k + pi/2, theta_j at the row's centre so that tan stays bounded next
    // to the horizon. Tilting the normal towards azimuth phi is a rotation about v(phi) and raises
    // the cosine of directions near phi by tan(theta) per radian, hence the positive sign with
    // the interpolation term (n_i x n) . grad_r (Ward & Heckbert orient v_k the other way).
    // Translation gradient: the change of the cosine-weighted solid angle each cell wall sweeps
    // when the point moves, times the radiance difference across the wall, the wall at the
    // nearer of its two cells' hit distances (Ward & Heckbert 1992, section 3.2).
    std::array<DVec3, 3> rotation{}, translation{};
    const float cell_phi = 2.0f * kPi / static_cast<float>(cells_n);
    for (int k = 0; k < cells_n; ++k) {
        const float phi_centre = (static_cast<float>(k) + 0.5f) * cell_phi;
        const float phi_wall = static_cast<float>(k) * cell_phi;  // between cells k - 1 and k
        const Vec3 u_k = frame.to_world({std::cos(phi_centre), std::sin(phi_centre), 0.0f});
        const Vec3 v_k = frame.to_world({-std::sin(phi_centre), std::cos(phi_centre), 0.0f});
        const Vec3 v_wall = frame.to_world({-std::sin(phi_wall), std::cos(phi_wall), 0.0f});
        const int k_prev = (k + cells_n - 1) % cells_n;
        DVec3 rotation_row(0.0);
        for (int j = 0; j < m; ++j) {
            const double theta_centre = std::asin(std::sqrt((j + 0.5) / m));
            rotation_row += std::tan(theta_centre) * DVec3(radiance[cell(j, k)]);
            // Wall between rows j - 1 and j at theta_minus: sin cos^2 (2 pi / N) / r.
            if (j > 0) {
                const double sin_minus = std::sqrt(static_cast<double>(j) / m);
                const double cos2_minus = 1.0 - sin_minus * sin_minus;
                const double r = std::min(distance[cell(j, k)], distance[cell(j - 1, k)]);
                if (std::isfinite(r) && r > 0.0) {
                    const double coefficient = cell_phi * sin_minus * cos2_minus / r;
                    const DVec3 difference = DVec3(radiance[cell(j, k)]) - DVec3(radiance[cell(j - 1, k)]);
                    for (int c = 0; c < 3; ++c) translation[c] += DVec3(u_k) * (coefficient * difference[c]);
                }
            }
            // Wall between columns k - 1 and k over row j: (sin theta+ - sin theta-) / r.
            const double r = std::min(distance[cell(j, k)], distance[cell(j, k_prev)]);
            if (cells_n > 1 && std::isfinite(r) && r > 0.0) {
                const double coefficient = (std::sqrt((j + 1.0) / m) - std::sqrt(static_cast<double>(j) / m)) / r;
                const DVec3 difference = DVec3(radiance[cell(j, k)]) - DVec3(radiance[cell(j, k_prev)]);
                for (int c = 0; c < 3; ++c) translation[c] += DVec3(v_wall) * (coefficient * difference[c]);
            }
        }
        for (int c = 0; c < 3; ++c) rotation[c] += DVec3(v_k) * rotation_row[c];
    }
    const double scale = 3.14159265358979323846 / cells;
    for (int c = 0; c < 3; ++c) {
        result.rotation_gradient[c] = Vec3(rotation[c] * scale);
        result.translation_gradient[c] = Vec3(translation[c]);
    }
    return result;
}

}  // namespace photond
