#include "server/render_pipeline.h"

#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <set>

#include "core/camera/camera.h"
#include "core/image/png_preview.h"
#include "core/integrators/direct.h"
#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/render/preview_renderer.h"
#include "core/render/render_plan.h"
#include "core/shading/render_scene.h"
#include "core/scene/builtin_scenes.h"
#include "core/image/environment_image.h"
#include "core/scene/gltf_loader.h"
#include "core/photon/photon_map_key.h"
#include "core/util/path_containment.h"
#include "protocol/render_settings.h"

namespace photond::service {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

Vec3 to_vec3(const std::array<double, 3>& a) {
    return Vec3(static_cast<float>(a[0]), static_cast<float>(a[1]), static_cast<float>(a[2]));
}

float radians(double degrees) { return static_cast<float>(degrees * 3.14159265358979323846 / 180.0); }

/// The file of a job's environment image: below the scene root for built-in and path scenes, in
/// the uploaded bundle for {"id": ...} scenes. The error is the message for environment.image.
Expected<std::filesystem::path> environment_image_file(const protocol::Job& job, const PipelineOptions& options) {
    const std::string& name = job.environment.image;
    std::filesystem::path root;
    if (job.scene.kind == protocol::SceneRef::Kind::Id) {
        std::optional<std::filesystem::path> bundle;
        if (options.bundle_lookup) bundle = options.bundle_lookup(job.scene.value);
        if (!bundle)
            return Error{"the uploaded scene " + job.scene.value +
                         " has no bundle of files; upload the scene with its environment image as a zip "
                         "or tar bundle"};
        root = *bundle;
    } else {
        if (options.scene_root.empty()) return Error{"no scene root is configured to read '" + name + "' from"};
        root = options.scene_root;
    }
    const std::optional<std::filesystem::path> file = resolve_below(root, name);
    if (!file) return Error{"'" + name + "' lies outside the scene root"};
    std::error_code error;
    if (!std::filesystem::is_regular_file(*file, error))
        return Error{"no environment image '" + name + "' below the " +
                     std::string(job.scene.kind == protocol::SceneRef::Kind::Id ? "uploaded bundle" : "scene root")};
    return *file;
}

Expected<Environment> load_environment_image(const protocol::Job& job, const PipelineOptions& options) {
    auto file = environment_image_file(job, options);
    if (!file) return Error{"environment.image: " + file.error().message};
    auto environment = read_environment_image(*file);
    if (!environment) return Error{"environment.image: " + environment.error().message};
    environment->name = job.environment.image;
    return environment;
}

/// Emissive surfaces whose power is below this share of a white sky's (radiance 1 through the
/// scene's bounding disc) do not keep the default environment away: labels and glowing details
/// do not light a model.
constexpr float kEmissiveOnlyShareOfSky = 0.05f;

constexpr const char* kNoLightMessage =
    "the scene has no light and the job turned the default environment off; add \"lights\" (point, "
    "spot, directional or quad) or an \"environment\" ({\"color\": [1, 1, 1]} or {\"image\": "
    "\"sky.exr\"})";

std::string format_number(double value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%g", value);
    return text;
}

std::string describe_colour(const std::array<double, 3>& c) {
    char text[96];
    std::snprintf(text, sizeof(text), "[%g, %g, %g]", c[0], c[1], c[2]);
    return text;
}

/// The job's atmosphere as the renderer's medium.
HomogeneousMedium atmosphere_medium(const protocol::AtmosphereSpec& spec) {
    HomogeneousMedium medium;
    medium.sigma_a = to_vec3(spec.sigma_a);
    medium.sigma_s = to_vec3(spec.sigma_s);
    medium.g = static_cast<float>(spec.g);
    return medium;
}

/// The plan's line for the atmosphere: what it is, where, and how dense.
PassDecision atmosphere_decision(const Scene& scene) {
    const HomogeneousMedium& medium = *scene.atmosphere;
    const auto color_text = [](const Color& c) { return describe_colour({c.x, c.y, c.z}); };
    // The optical depth across the box's diagonal, in its densest channel: how much of the light
    // that crosses the scene the medium takes (e^-depth passes).
    const float depth = max_component(medium.sigma_t()) * glm::length(scene.bounds.extent());
    return {"atmosphere", !medium.empty(),
            "a homogeneous medium (sigma_a " + color_text(medium.sigma_a) + ", sigma_s " + color_text(medium.sigma_s) +
                " per unit, g " + format_number(medium.g) + ") filling the scene's bounds " +
                color_text(scene.bounds.lower) + " to " + color_text(scene.bounds.upper) +
                ", outside transmissive solids; optical depth " + format_number(depth) + " across them"};
}

/// The plan's line for the radiance cache of a photon-map job whose scene has a glossy lobe:
/// which materials' lobes it holds (and in how many bands) and which take BSDF-sampled rays,
/// and why. None for other integrators or scenes without a glossy lobe.
std::optional<PassDecision> radiance_cache_decision(const protocol::RenderSettings& settings, const RenderScene& rs) {
    if (settings.integrator != "photon-map") return std::nullopt;
    const RadianceCacheSettings& cache = settings.photon_map.radiance_cache;
    const Scene& scene = *rs.scene;
    const std::vector<bool> used = scene.materials_in_use();
    // Material names grouped by what becomes of their glossy lobes, in the scene's order.
    std::map<std::string, std::vector<std::string>> groups;
    std::vector<std::string> order;
    bool any_cached = false;
    for (size_t i = 0; i < scene.materials.size() && i < rs.bsdf_materials.size(); ++i) {
        const BsdfMaterial& m = rs.bsdf_materials[i];
        const float alpha = sharpest_reflection_alpha(m);
        if (!used[i] || (!(alpha > 0.0f) && !transmits_non_delta(m))) continue;
        std::string group;
        if (transmits_non_delta(m)) {
            group = "BSDF-sampled rays (rough transmission: a record sees one side)";
        } else if (const int bands = radiance_order_for(m, cache); bands > 0) {
            group = "cached in " + std::to_string(bands) + " bands";
            any_cached = true;
        } else if (const int needed = radiance_order_for(alpha); needed > kMaxHarmonicsOrder) {
            group = "BSDF-sampled rays (sharper than " + std::to_string(kMaxHarmonicsOrder) + " bands resolve)";
        } else {
            group = "BSDF-sampled rays (" + std::to_string(needed) + " bands needed, max_order " +
                    std::to_string(cache.max_order) + ")";
        }
        if (!groups.contains(group)) order.push_back(group);
        groups[group].push_back("'" + scene.materials[i].name + "'");
    }
    if (order.empty()) return std::nullopt;
    if (!cache.enabled)
        return PassDecision{"radiance_cache", false,
                            "the job leaves it off (radiance_cache.enabled): glossy lobes take BSDF-sampled rays"};
    if (!settings.photon_map.final_gather) return PassDecision{"radiance_cache", false, "it needs final gathering"};
    constexpr size_t kNamesShown = 4;
    std::string account;
    for (const std::string& group : order) {
        const std::vector<std::string>& names = groups[group];
        std::string list;
        for (size_t k = 0; k < names.size() && k < kNamesShown; ++k) list += (k ? ", " : "") + names[k];
        if (names.size() > kNamesShown) list += " and " + std::to_string(names.size() - kNamesShown) + " more";
        account += (account.empty() ? "" : "; ") + group + ": " + list;
    }
    return PassDecision{"radiance_cache", any_cached,
                        (any_cached ? "glossy lobes read incident radiance in hemispherical harmonics; "
                                    : "no glossy lobe it can hold; ") +
                            account};
}

/// What the job's material_media cannot apply to `scene`, naming the entry: no material of
/// that name, or one that is not transmissive (its surface closes no medium).
std::optional<protocol::FieldError> material_media_problem(const protocol::Job& job, const Scene& scene) {
    for (const auto& [name, spec] : job.material_media) {
        const std::string path = "material_media." + name;
        // Solids among the materials some triangle uses: a material all of whose primitives are
        // open keeps an unused solid original beside its thin-walled copy (the glTF loader).
        const std::vector<bool> used = scene.materials_in_use();
        bool found = false, solid = false;
        for (size_t i = 0; i < scene.materials.size(); ++i) {
            const Material& m = scene.materials[i];
            if (m.name != name) continue;
            if (!(m.transmission > 0.0f))
                return protocol::FieldError{path, "material '" + name + "' is not transmissive (no "
                                                  "KHR_materials_transmission): its surface closes no medium"};
            found = true;
            solid = solid || (used[i] && !m.thin_walled);
        }
        if (found && !solid)
            return protocol::FieldError{path, "material '" + name + "' is only on open meshes, taken as thin walls "
                                              "(README.md, \"Transmission without KHR_materials_volume\"): "
                                              "its surface closes no medium"};
        if (!found) {
            std::set<std::string> names;
            std::string transmissive;
            for (const Material& m : scene.materials)
                if (m.transmission > 0.0f && names.insert(m.name).second)
                    transmissive += (transmissive.empty() ? "'" : ", '") + m.name + "'";
            return protocol::FieldError{path, "the scene has no material '" + name + "' (its transmissive materials: " +
                                                  (transmissive.empty() ? std::string("none") : transmissive) + ")"};
        }
    }
    return std::nullopt;
}

/// The job's material_media (material_media_problem found none) given to the scene's materials
/// of those names (every one of a name: glTF names need not be unique). Returns the plan's
/// account of it, one entry per name; empty without entries.
std::string apply_material_media(const protocol::Job& job, Scene& scene) {
    std::string applied;
    const std::vector<bool> used = scene.materials_in_use();
    for (const auto& entry : job.material_media) {
        const std::string& name = entry.first;  // a named variable: lambdas may not capture bindings (C++17)
        const auto& spec = entry.second;
        for (size_t i = 0; i < scene.materials.size(); ++i) {
            Material& m = scene.materials[i];
            // A thin wall has no inside; an unused material (a thin wall's solid original) none
            // that shows.
            if (m.name != name || m.thin_walled || !used[i]) continue;
            m.scattering = to_vec3(spec.sigma_s);
            m.phase_g = static_cast<float>(spec.g);
            if (spec.sigma_a) m.attenuation = to_vec3(*spec.sigma_a);
        }
        // material_media_problem found a solid of that name in use.
        size_t first = 0;
        while (first + 1 < scene.materials.size() &&
               (scene.materials[first].name != name || scene.materials[first].thin_walled || !used[first]))
            ++first;
        const Material* m = &scene.materials[first];
        applied += std::string(applied.empty() ? "" : "; ") + "'" + name + "': sigma_a " +
                   describe_colour({m->attenuation.x, m->attenuation.y, m->attenuation.z}) + " (" +
                   (spec.sigma_a ? "the job's" : "the file's") + "), sigma_s " + describe_colour(spec.sigma_s) +
                   ", g " + format_number(spec.g);
    }
    return applied;
}

/// Plans the photon pass of a photon-map job and gets its maps: from the store when one is
/// given (a hit skips tracing), else traced for this job. Records it all in the statistics.
Expected<std::shared_ptr<const PhotonMaps>> build_photon_maps(const protocol::RenderSettings& render_settings, const RenderScene& scene,
                                                              const PipelineOptions& options,
                                                              RenderStatistics& stats) {
    const RenderPlan plan = plan_photon_passes(*scene.scene, *scene.lights,
                                               {render_settings.photon_tracing.global_photons, render_settings.photon_tracing.caustic_photons,
                                                render_settings.photon_tracing.volume_photons},
                                               scene.lights_with_sky_peaks.get());
    stats.plan = plan.decisions;
    const PhotonTracingSettings settings = photon_settings(render_settings, plan, options);
    if (settings.global_photons == 0 && settings.caustic_photons == 0 && settings.volume_photons == 0) {
        stats.photons = PhotonTracingStatistics{};
        return std::make_shared<const PhotonMaps>();
    }
    if (options.on_pass) options.on_pass("photon_tracing");
    const Clock::time_point pass_start = Clock::now();
    const auto trace = [&]() { return trace_photons(scene, settings); };
    std::shared_ptr<const PhotonMaps> maps;
    if (options.photon_maps) {
        stats.photon_map_key = photon_map_key(*scene.scene, settings);
        bool hit = false;
        auto cached = options.photon_maps->get_or_build(stats.photon_map_key, trace, &hit);
        if (!cached) return cached.error();
        maps = *cached;
        stats.photon_cache = hit ? "hit" : "miss";
    } else {
        auto traced = trace();
        if (!traced) return traced.error();
        maps = std::make_shared<const PhotonMaps>(std::move(traced).value());
    }
    stats.photons = maps->statistics;
    stats.photon_map_bytes = maps->bytes();
    stats.caustic_flux_share = caustic_flux_share(*maps);
    for (std::string& warning : incomplete_photon_map_warnings(maps->statistics, settings))
        stats.warnings.push_back(std::move(warning));
    // Adds to the caustic map's reason in the plan; `skipped`: the map is not read after all.
    const auto tell_caustic_plan = [&](const std::string& text, bool skipped) {
        for (PassDecision& d : stats.plan) {
            if (d.pass != "caustic_map") continue;
            if (skipped) d.enabled = false;
            d.reason += text;
        }
    };
    char text[320];
    if (caustic_stopped_as_negligible(maps->statistics, settings)) {
        // Not a warning: the map is right, only its light is too faint to be worth more photons.
        std::snprintf(text, sizeof text,
                      "; stopped early at %llu of %u photons (%.1f M emitted): they carry %.2g %% of the light "
                      "the global map brings to surfaces, under %.2g %%, so more would not show",
                      static_cast<unsigned long long>(maps->statistics.stored_caustic), settings.caustic_photons,
                      static_cast<double>(maps->statistics.emitted_caustic) * 1e-6,
                      100.0 * stats.caustic_flux_share, 100.0 * kNegligibleCausticShare);
        tell_caustic_plan(text, false);
    }
    if (maps->statistics.caustic_dropped) {
        // Not a warning either: the caustic would change no pixel by as much as its threshold.
        std::snprintf(text, sizeof text,
                      "; dropped after %llu photons (%.1f M emitted): where they land the caustic is at most "
                      "%.2g %% of the irradiance, under %.2g %%, so it would not show",
                      static_cast<unsigned long long>(maps->statistics.stored_caustic),
                      static_cast<double>(maps->statistics.emitted_caustic) * 1e-6,
                      100.0 * maps->statistics.caustic_peak_ratio, 100.0 * kInvisibleCausticRatio);
        tell_caustic_plan(text, true);
    }
    if (settings.caustic_photons > 0 && maps->statistics.stored_caustic == 0)
        tell_caustic_plan("; no photon reached a diffuse surface through them after " +
                              std::to_string(maps->statistics.emitted_caustic) + " emitted: the scene has no caustics",
                          false);
    // The photon pass in parts: tracing, the kd-trees and the irradiance precomputed at photons
    // when traced here, and the rest of its wall time (the cache's file written, or read on a
    // hit) as photon_map_store, so that the passes add up to the whole.
    const bool traced_here = stats.photon_cache != "hit";
    const PhotonTracingStatistics& traced = maps->statistics;
    const double tracing = traced_here ? traced.tracing_seconds : 0.0;
    const double kdtree = traced_here ? traced.build_seconds : 0.0;
    const double irradiance = traced_here ? traced.irradiance_seconds : 0.0;
    stats.passes.push_back({"photon_tracing", tracing});
    stats.passes.push_back({"photon_kdtree", kdtree});
    stats.passes.push_back({"photon_irradiance", irradiance});
    stats.passes.push_back({"photon_map_store", std::max(0.0, seconds_since(pass_start) - tracing - kdtree - irradiance)});
    return maps;
}

Expected<std::unique_ptr<Integrator>> make_integrator(const protocol::RenderSettings& render_settings,
                                                      std::shared_ptr<const RenderScene> scene,
                                                      const PipelineOptions& options,
                                                      RenderStatistics& stats) {
    if (render_settings.integrator == "path") return std::unique_ptr<Integrator>(new PathIntegrator(scene));
    if (render_settings.integrator == "direct") return std::unique_ptr<Integrator>(new DirectIntegrator(scene));
    if (render_settings.integrator == "photon-map") {
        auto maps = build_photon_maps(render_settings, *scene, options, stats);
        if (!maps) return maps.error();
        PhotonMapIntegratorSettings settings = render_settings.photon_map;
        settings.irradiance_cache.threads = options.threads;
        settings.irradiance_cache.cancel = options.callbacks.cancel;
        return std::unique_ptr<Integrator>(new PhotonMapIntegrator(scene, *maps, settings));
    }
    return Error{"integrator: unknown integrator '" + render_settings.integrator + "'"};
}

}  // namespace

bool caustic_stopped_as_negligible(const PhotonTracingStatistics& photons, const PhotonTracingSettings& settings) {
    // Stopped short of the emission cap with photons in it: the negligible-share rule did it.
    return settings.caustic_photons > 0 && !photons.caustic_complete && !photons.caustic_dropped &&
           photons.stored_caustic > 0 && photons.emitted_caustic <
               static_cast<uint64_t>(settings.caustic_photons) * settings.max_emitted_per_stored;
}

std::vector<std::string> incomplete_photon_map_warnings(const PhotonTracingStatistics& photons,
                                                        const PhotonTracingSettings& settings) {
    std::vector<std::string> warnings;
    const auto grouped = [](uint64_t n) {  // 1145 -> "1,145"
        std::string digits = std::to_string(n), out;
        for (size_t i = 0; i < digits.size(); ++i) {
            if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
            out += digits[i];
        }
        return out;
    };
    const auto millions = [](uint64_t n) {
        char text[32];
        std::snprintf(text, sizeof text, "%.1f M", static_cast<double>(n) * 1e-6);
        return std::string(text);
    };
    // The emission cap allows max_emitted_per_stored emissions per requested photon: a map whose
    // store rate is below that fills at no requested count, so fewer photons would not help.
    const auto rate = [&](uint64_t stored, uint64_t emitted) {
        return stored > 0 ? "1 photon stored per " + grouped((emitted + stored / 2) / stored) + " emitted"
                          : std::string("no photon stored");
    };
    const auto incomplete = [&](const char* map, uint64_t stored, uint32_t requested, uint64_t emitted,
                                const char* consequence) {
        warnings.push_back("photon map incomplete: the " + std::string(map) + " map holds " + grouped(stored) +
                           " of the " + grouped(requested) + " photons requested (" + rate(stored, emitted) +
                           "; emission stopped at " + millions(emitted) + " photons, the cap of " +
                           grouped(settings.max_emitted_per_stored) + " per requested photon): " + consequence);
    };
    // An empty caustic map is not incomplete: no light focuses (the plan's reason says so).
    if (settings.caustic_photons > 0 && !photons.caustic_complete && !photons.caustic_dropped &&
        photons.stored_caustic > 0 && !caustic_stopped_as_negligible(photons, settings))
        incomplete("caustic", photons.stored_caustic, settings.caustic_photons, photons.emitted_caustic,
                   "little light reaches a diffuse surface through the specular ones, so its caustics are noisy. "
                   "Set photons.caustic=0 to skip the caustic map, or give the scene more specular surfaces in "
                   "the lights' reach");
    if (settings.global_photons > 0 && !photons.global_complete)
        incomplete("global", photons.stored_global, settings.global_photons, photons.emitted_global,
                   "most photons leave the scene or land on nothing, so indirect light is noisy. Aim the lights "
                   "at the geometry or close the scene");
    if (settings.volume_photons > 0 && !photons.volume_complete)
        incomplete("volume", photons.stored_volume, settings.volume_photons, photons.emitted_volume,
                   "few photons scatter in the atmosphere before they leave it, so its light scattered more than "
                   "once is noisy. Thicken the atmosphere (sigma_s) or lower photons.volume");
    return warnings;
}

PhotonTracingSettings photon_settings(const protocol::RenderSettings& render_settings, const RenderPlan& plan,
                                      const PipelineOptions& options) {
    PhotonTracingSettings settings = render_settings.photon_tracing;
    if (!plan.global_map) settings.global_photons = 0;
    if (!plan.caustic_map) settings.caustic_photons = 0;
    if (!plan.volume_map) settings.volume_photons = 0;  // and the key stays that of a clear scene
    settings.threads = options.threads;
    settings.cancel = options.callbacks.cancel;
    return settings;
}

Expected<std::shared_ptr<const Scene>> load_job_scene(const protocol::SceneRef& ref,
                                                      const PipelineOptions& options) {
    const std::filesystem::path& scene_root = options.scene_root;
    switch (ref.kind) {
        case protocol::SceneRef::Kind::Builtin: {
            auto scene = make_builtin_scene(ref.value);
            if (!scene) return scene.error();
            return std::make_shared<const Scene>(std::move(scene).value());
        }
        case protocol::SceneRef::Kind::Path: {
            if (scene_root.empty()) return Error{"scene.path: no scene root is configured"};
            const std::optional<std::filesystem::path> file = resolve_below(scene_root, ref.value);
            if (!file) return Error{"scene.path: '" + ref.value + "' lies outside the scene root"};
            GltfLoadOptions options;
            options.bundle_root = file->parent_path();
            auto scene = load_gltf_file(*file, options);
            if (!scene) return scene.error();
            return std::make_shared<const Scene>(std::move(scene).value());
        }
        case protocol::SceneRef::Kind::Id:
            if (!options.scene_lookup) return Error{"scene.id: uploaded scenes are served by the daemon only"};
            return options.scene_lookup(ref.value);
    }
    return Error{"scene: unknown kind"};
}

Expected<AddedLighting> job_lighting(const protocol::Job& job, const Scene& scene, const PipelineOptions& options,
                                     PassDecision* decision) {
    AddedLighting lighting;
    for (size_t i = 0; i < job.lights.size(); ++i) {
        const protocol::LightSpec& spec = job.lights[i];
        const std::string name = "lights[" + std::to_string(i) + "]";
        const Color colour = to_vec3(spec.color) * static_cast<float>(spec.strength);
        if (spec.type == "quad") {
            lighting.quads.push_back({name, to_vec3(spec.position), to_vec3(spec.edge_u), to_vec3(spec.edge_v),
                                      colour, spec.two_sided});
            continue;
        }
        PunctualLight light;
        light.name = name;
        light.intensity = colour;
        light.position = to_vec3(spec.position);
        light.direction = glm::normalize(to_vec3(spec.direction));
        if (spec.type == "point") light.type = PunctualLightType::Point;
        if (spec.type == "spot") {
            light.type = PunctualLightType::Spot;
            light.cos_inner = std::cos(radians(spec.inner_cone_deg));
            light.cos_outer = std::cos(radians(spec.outer_cone_deg));
        }
        if (spec.type == "directional") {
            light.type = PunctualLightType::Directional;
            light.angular_radius = 0.5f * radians(spec.angular_diameter_deg);
        }
        lighting.lights.push_back(light);
    }

    using Kind = protocol::EnvironmentSpec::Kind;
    const protocol::EnvironmentSpec& spec = job.environment;
    *decision = {"environment", true, ""};
    switch (spec.kind) {
        case Kind::Default:
            if (scene.environment) {
                *decision = {"environment", true, "the scene's own: '" + scene.environment->name + "'"};
                break;
            }
            if (!job.lights.empty() || !scene.lights.empty()) {
                *decision = {"environment", false,
                             std::string(job.lights.empty() ? "the scene" : "the job") +
                                 " has lights of its own (add \"environment\" to light it from a sky too)"};
                break;
            }
            if (scene_emits_light(scene)) {
                // Only emissive surfaces: a lamp's glow, a screen, a label. Unless they could
                // light the scene as well as a sky would, the model is shown under the sky too,
                // as glTF viewers do.
                // By power alone: the light tree is no part of the total.
                const float own = average(LightSet(scene, LightSelection::Power).total_power());
                const float radius = std::max(scene.bounds.radius(), 1e-6f);
                const float sky = 4.0f * kPi * kPi * radius * radius;  // radiance 1 through the scene's disc
                if (own >= kEmissiveOnlyShareOfSky * sky) {
                    *decision = {"environment", false,
                                 "the scene's emissive surfaces light it (" + format_number(own) +
                                     " W; add \"environment\" to light it from a sky too)"};
                    break;
                }
                lighting.environment = Environment{};
                lighting.environment->name = "default";
                decision->reason = "default: a uniform white environment of radiance 1, since the scene's only "
                                   "light is emissive surfaces of " + format_number(own) + " W, under " +
                                   format_number(100.0 * kEmissiveOnlyShareOfSky) + " % of what such a sky sends (" +
                                   format_number(sky) + " W; set \"environment\": null to render by them alone)";
                break;
            }
            lighting.environment = Environment{};
            lighting.environment->name = "default";
            decision->reason =
                "default: a uniform white environment of radiance 1, since neither the scene nor the job has "
                "a light (set \"environment\": null to refuse such jobs instead)";
            break;
        case Kind::None:
            *decision = {"environment", false, "the job turned it off (\"environment\": null)"};
            if (job.lights.empty() && !scene_emits_light(scene))
                return Error{std::string("environment: ") + kNoLightMessage};
            break;
        case Kind::Uniform:
            lighting.environment = Environment{};
            lighting.environment->name = "uniform";
            lighting.environment->color = to_vec3(spec.color);
            lighting.environment->intensity = static_cast<float>(spec.intensity);
            decision->reason = "uniform radiance " + describe_colour(spec.color) + " x " + format_number(spec.intensity);
            break;
        case Kind::Image: {
            auto environment = load_environment_image(job, options);
            if (!environment) return environment.error();
            environment->intensity = static_cast<float>(spec.intensity);
            environment->rotation = radians(spec.rotation_deg);
            decision->reason = "image '" + spec.image + "' (" + std::to_string(environment->width) + " x " +
                               std::to_string(environment->height) + "), importance-sampled";
            lighting.environment = std::move(environment).value();
            break;
        }
    }
    // A black environment lights nothing: say so rather than render black in silence.
    if (lighting.environment && !environment_emits_light(*lighting.environment))
        decision->reason += "; it is black and adds no light";
    return lighting;
}

std::optional<protocol::FieldError> check_job_media(const protocol::Job& job, const PipelineOptions& options) {
    if (job.material_media.empty()) return std::nullopt;
    auto scene = load_job_scene(job.scene, options);
    if (!scene) return std::nullopt;  // the render says what is wrong with the scene itself
    return material_media_problem(job, **scene);
}

std::optional<protocol::FieldError> check_job_lighting(const protocol::Job& job, const PipelineOptions& options) {
    if (job.environment.kind == protocol::EnvironmentSpec::Kind::Image) {
        auto file = environment_image_file(job, options);
        if (!file) return protocol::FieldError{"environment.image", file.error().message};
    }
    if (job.environment.kind == protocol::EnvironmentSpec::Kind::None && job.lights.empty()) {
        auto scene = load_job_scene(job.scene, options);
        if (scene && !scene_emits_light(**scene)) return protocol::FieldError{"environment", kNoLightMessage};
    }
    return std::nullopt;
}

Expected<CameraDesc> resolve_camera(const protocol::Job& job, const Scene& scene) {
    if (job.camera) {
        if (const auto* gltf = std::get_if<protocol::GltfCamera>(&*job.camera)) {
            if (gltf->index < 0 || static_cast<size_t>(gltf->index) >= scene.cameras.size())
                return Error{"camera.gltf_camera: the scene has " + std::to_string(scene.cameras.size()) +
                             " camera(s); index " + std::to_string(gltf->index) + " does not exist"};
            const CameraDesc& camera = scene.cameras[static_cast<size_t>(gltf->index)];
            if (!camera.placed)
                return Error{"camera.gltf_camera: camera " + std::to_string(gltf->index) + " '" + camera.name +
                             "' is placed by no node of the scene, so it has no position to render from"};
            return camera;
        }
        const auto& look = std::get<protocol::LookAtCamera>(*job.camera);
        CameraDesc desc;
        desc.name = "job";
        desc.position = to_vec3(look.look_from);
        desc.look_at = to_vec3(look.look_at);
        desc.up = to_vec3(look.up);
        desc.vfov_deg = static_cast<float>(look.vfov_deg);
        return desc;
    }
    // The scene's first camera that a node places (glTF: the lowest index into cameras[]).
    for (const CameraDesc& camera : scene.cameras)
        if (camera.placed) return camera;
    // No camera anywhere: look at the scene's bounds from the +z side, framing them.
    CameraDesc desc;
    desc.name = "default";
    const Vec3 center = scene.bounds.center();
    const float radius = std::max(scene.bounds.radius(), 1e-3f);
    desc.vfov_deg = 40.0f;
    desc.look_at = center;
    desc.position = center + Vec3(0.0f, 0.0f, radius / std::tan(0.5f * desc.vfov_deg * kPi / 180.0f) * 1.1f);
    return desc;
}

Expected<PipelineResult> run_job(const protocol::Job& job, std::shared_ptr<EmbreeDevice> device,
                                 const PipelineOptions& options) {
    const Clock::time_point start = Clock::now();
    PipelineResult result;
    RenderStatistics& stats = result.statistics;
    stats.integrator = job.integrator;
    stats.width = job.image.width;
    stats.height = job.image.height;
    stats.samples_per_pixel = job.image.spp;
    stats.threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
    const protocol::RenderSettings settings = protocol::to_render_settings(job);

    Clock::time_point pass_start = Clock::now();
    if (options.on_pass) options.on_pass("scene");
    auto scene = load_job_scene(job.scene, options);
    if (!scene) return scene.error();
    PassDecision environment_decision;
    auto lighting = job_lighting(job, **scene, options, &environment_decision);
    if (!lighting) return lighting.error();
    std::shared_ptr<const Scene> lit_scene = *scene;
    if (const auto error = material_media_problem(job, **scene)) return Error{protocol::describe(*error)};
    std::string media_applied;
    if (!lighting->empty() || job.atmosphere || !job.material_media.empty()) {
        auto lit = with_added_lighting(**scene, *lighting);
        if (!lit) return lit.error();
        // The atmosphere fills the bounds grown by the job's lights too.
        if (job.atmosphere) lit->atmosphere = atmosphere_medium(*job.atmosphere);
        media_applied = apply_material_media(job, *lit);
        lit_scene = std::make_shared<const Scene>(std::move(lit).value());
    }
    stats.lighting.job_lights = job.lights.size();
    stats.lighting.environment = lit_scene->environment ? lit_scene->environment->name : "";
    stats.passes.push_back({"scene", seconds_since(pass_start)});
    stats.warnings = (*scene)->warnings;
    for (size_t i = 0; i < job.lights.size(); ++i) {
        const protocol::LightSpec& light = job.lights[i];
        if (light.strength * std::max({light.color[0], light.color[1], light.color[2]}) <= 0.0)
            stats.warnings.push_back("lights[" + std::to_string(i) + "] (" + light.type + ") has no " +
                                     std::string(protocol::light_strength_field(light.type)) +
                                     " or a black colour: it adds no light");
    }
    if (lit_scene->atmosphere && lit_scene->atmosphere->empty())
        stats.warnings.push_back("the atmosphere has neither absorption nor scattering (sigma_a and sigma_s are 0): "
                                 "it changes nothing");
    if (lit_scene->environment && !environment_emits_light(*lit_scene->environment))
        stats.warnings.push_back("the environment '" + lit_scene->environment->name + "' is black: it adds no light");

    pass_start = Clock::now();
    if (options.on_pass) options.on_pass("acceleration");
    auto render_scene = RenderScene::create(device, lit_scene, settings.light_selection);
    if (!render_scene) return render_scene.error();
    stats.lighting.lights = (*render_scene)->lights->size();
    stats.passes.push_back({"acceleration", seconds_since(pass_start)});

    // The camera frames the scene as loaded: lights added by the job do not move it.
    auto camera_desc = resolve_camera(job, **scene);
    if (!camera_desc) return camera_desc.error();
    auto camera = Camera::create(*camera_desc, job.image.width, job.image.height);
    if (!camera) return camera.error();
    auto integrator = make_integrator(settings, *render_scene, options, stats);
    if (!integrator) return integrator.error();
    stats.plan.insert(stats.plan.begin(), environment_decision);
    if (lit_scene->atmosphere) stats.plan.insert(stats.plan.begin() + 1, atmosphere_decision(*lit_scene));
    if (!media_applied.empty())
        stats.plan.insert(stats.plan.begin() + (lit_scene->atmosphere ? 2 : 1),
                          PassDecision{"material_media", true, "the solids of " + media_applied});
    if (auto decision = radiance_cache_decision(settings, **render_scene)) stats.plan.push_back(std::move(*decision));

    Integrator& renderer = **integrator;
    // The preview needs the photon maps (a cache hit has them at once) and nothing the
    // irradiance-cache prepass builds: it streams while the prepass and the tiles are still to come.
    if (options.previews && settings.preview && !options.caches_only) {
        pass_start = Clock::now();
        if (options.on_pass) options.on_pass("preview");
        const std::unique_ptr<Integrator> cheap = renderer.make_preview();
        PreviewSettings preview = *settings.preview;
        preview.threads = options.threads;
        const PreviewResult previewed = render_preview(cheap ? *cheap : renderer, *camera, preview, options.callbacks);
        stats.rays += previewed.counters.rays;
        stats.shadow_rays += previewed.counters.shadow_rays;
        stats.short_ray_bounces += previewed.counters.short_ray_bounces;
        RenderStatistics::PreviewFigures figures;
        figures.stride = previewed.stride;
        figures.samples = previewed.samples;
        figures.tiles = previewed.tiles;
        figures.seconds = seconds_since(pass_start);
        stats.preview = figures;
        stats.passes.push_back({"preview", figures.seconds});
    }
    const std::string_view preparation = renderer.preparation_pass();
    if (!job.irradiance_cache.start_from.empty() && preparation != "irradiance_cache")
        stats.warnings.push_back("irradiance_cache.start_from is ignored: this job has no irradiance cache (it needs the "
                                 "photon-map integrator with irradiance_cache.enabled)");
    if (!preparation.empty()) {
        if (options.on_pass) options.on_pass(std::string(preparation));
        pass_start = Clock::now();
        const PrepareContext context{.camera = *camera,
                                     .camera_desc = *camera_desc,
                                     .width = job.image.width,
                                     .height = job.image.height,
                                     .photon_map_key = stats.photon_map_key,
                                     .render_caches = options.render_caches,
                                     .start_from = job.irradiance_cache.start_from,
                                     .cancel = options.callbacks.cancel};
        auto prepared = renderer.prepare(context);
        if (!prepared) return prepared.error();
        // The radiance cache is built in the same preparation, timed apart: the passes still sum.
        const double radiance_seconds = prepared->radiance ? prepared->radiance->seconds : 0.0;
        if (prepared->built) {
            RenderStatistics::IrradianceCacheFigures figures;
            figures.records = prepared->records;
            figures.records_reused = prepared->records_reused;
            figures.waves = prepared->waves;
            figures.cache = prepared->cache_outcome;
            figures.key = prepared->cache_key;
            figures.start_from = prepared->start_from;
            figures.seconds = seconds_since(pass_start) - radiance_seconds;
            stats.irradiance_cache = figures;
            stats.passes.push_back({std::string(preparation), figures.seconds});
        }
        if (prepared->radiance) {
            RenderStatistics::RadianceCacheFigures figures;
            figures.records = prepared->radiance->records;
            figures.waves = prepared->radiance->waves;
            figures.seconds = prepared->built ? radiance_seconds : seconds_since(pass_start);
            stats.radiance_cache = figures;
            stats.passes.push_back({"radiance_cache", figures.seconds});
        }
        stats.rays += prepared->counters.rays;
        stats.shadow_rays += prepared->counters.shadow_rays;
        stats.short_ray_bounces += prepared->counters.short_ray_bounces;
    }

    if (options.caches_only) {
        stats.total_seconds = seconds_since(start);
        return result;
    }

    TileSettings tiles = settings.tiles;
    tiles.threads = options.threads;
    pass_start = Clock::now();
    if (options.on_pass) options.on_pass("render");
    TileRenderResult rendered = render_tiles(**integrator, *camera, tiles, options.callbacks);
    stats.render_seconds = seconds_since(pass_start);
    stats.passes.push_back({"render", stats.render_seconds});
    stats.rays += rendered.counters.rays;
    stats.shadow_rays += rendered.counters.shadow_rays;
    stats.short_ray_bounces += rendered.counters.short_ray_bounces;
    stats.caustic_points = rendered.counters.caustic_points;
    stats.caustic_skipped = rendered.counters.caustic_skipped;
    if (stats.irradiance_cache) {
        stats.irradiance_cache->lookups = rendered.counters.irradiance_lookups;
        stats.irradiance_cache->misses = rendered.counters.irradiance_misses;
    }
    if (stats.radiance_cache) {
        stats.radiance_cache->lookups = rendered.counters.radiance_lookups;
        stats.radiance_cache->misses = rendered.counters.radiance_misses;
    }
    stats.cancelled = rendered.cancelled;
    stats.tiles_restored = rendered.tiles_restored;
    stats.total_seconds = seconds_since(start);
    result.layers = std::move(rendered.layers);
    return result;
}

ExrWriteOptions exr_options(const protocol::Job& job) { return protocol::to_render_settings(job).exr; }

Expected<std::vector<uint8_t>> encode_job_preview(const protocol::Job& job, const Image& image) {
    return encode_render_preview(image, protocol::to_render_settings(job).preview_exposure_ev);
}

}  // namespace photond::service
