#include "server/render_pipeline.h"

#include <tbb/info.h>

#include <chrono>
#include <cstdio>

#include "core/camera/camera.h"
#include "core/integrators/direct.h"
#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/render/render_plan.h"
#include "core/render/render_scene.h"
#include "core/scene/builtin_scenes.h"
#include "core/scene/gltf_loader.h"
#include "core/scene/scene_hash.h"

namespace photond::service {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

Vec3 to_vec3(const std::array<double, 3>& a) {
    return Vec3(static_cast<float>(a[0]), static_cast<float>(a[1]), static_cast<float>(a[2]));
}

/// Plans the photon pass of a photon-map job and gets its maps: from the store when one is
/// given (a hit skips tracing), else traced for this job. Records it all in the statistics.
Expected<std::shared_ptr<const PhotonMaps>> build_photon_maps(const protocol::Job& job, const RenderScene& scene,
                                                              const PipelineOptions& options,
                                                              RenderStatistics& stats) {
    const RenderPlan plan = plan_photon_passes(*scene.scene, *scene.lights,
                                               {job.photons.global, job.photons.caustic});
    stats.plan = plan.decisions;
    const PhotonTracingSettings settings = photon_settings(job, plan, options);
    if (settings.global_photons == 0 && settings.caustic_photons == 0) {
        stats.photons = PhotonTracingStatistics{};
        return std::make_shared<const PhotonMaps>();
    }
    if (options.on_pass) options.on_pass("photon_tracing");
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
    for (std::string& warning : incomplete_photon_map_warnings(maps->statistics, settings))
        stats.warnings.push_back(std::move(warning));
    const bool traced_here = stats.photon_cache != "hit";
    stats.passes.push_back({"photon_tracing", traced_here ? maps->statistics.tracing_seconds : 0.0});
    stats.passes.push_back({"photon_kdtree", traced_here ? maps->statistics.build_seconds : 0.0});
    return maps;
}

Expected<std::unique_ptr<Integrator>> make_integrator(const protocol::Job& job,
                                                      std::shared_ptr<const RenderScene> scene,
                                                      const PipelineOptions& options,
                                                      RenderStatistics& stats) {
    if (job.integrator == "path") return std::unique_ptr<Integrator>(new PathIntegrator(scene));
    if (job.integrator == "direct") return std::unique_ptr<Integrator>(new DirectIntegrator(scene));
    if (job.integrator == "photon-map") {
        auto maps = build_photon_maps(job, *scene, options, stats);
        if (!maps) return maps.error();
        PhotonMapIntegratorSettings settings;
        settings.k_global = job.photons.k_global;
        settings.k_caustic = job.photons.k_caustic;
        settings.gather.rays = job.gather.rays;
        settings.irradiance_cache = job.irradiance_cache.enabled;
        settings.cache.cache.accuracy = static_cast<float>(job.irradiance_cache.a);
        settings.cache.cache.gradients = job.irradiance_cache.gradients;
        settings.cache.min_spacing_px = static_cast<float>(job.irradiance_cache.min_spacing_px);
        settings.cache.max_spacing_px = static_cast<float>(job.irradiance_cache.max_spacing_px);
        settings.cache.seed = job.seed;
        settings.cache.threads = options.threads;
        settings.cache.cancel = options.callbacks.cancel;
        if (job.image.region) {
            const auto& r = *job.image.region;
            settings.cache.region = PixelRect{r[0], r[1], r[2], r[3]};
        }
        return std::unique_ptr<Integrator>(new PhotonMapIntegrator(scene, *maps, settings));
    }
    return Error{"integrator: unknown integrator '" + job.integrator + "'"};
}

}  // namespace

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
    if (settings.caustic_photons > 0 && !photons.caustic_complete) {
        warnings.push_back("photon map incomplete: the caustic map holds " + grouped(photons.stored_caustic) +
                           " of the " + grouped(settings.caustic_photons) + " photons requested (" +
                           rate(photons.stored_caustic, photons.emitted_caustic) + "; emission stopped at " +
                           millions(photons.emitted_caustic) + " photons, the cap of " +
                           grouped(settings.max_emitted_per_stored) +
                           " per requested photon): little light reaches a diffuse surface through the specular "
                           "ones, so its caustics are noisy. Set photons.caustic=0 to skip the caustic map, or "
                           "give the scene more specular surfaces in the lights' reach");
    }
    if (settings.global_photons > 0 && !photons.global_complete) {
        warnings.push_back("photon map incomplete: the global map holds " + grouped(photons.stored_global) +
                           " of the " + grouped(settings.global_photons) + " photons requested (" +
                           rate(photons.stored_global, photons.emitted_global) + "; emission stopped at " +
                           millions(photons.emitted_global) + " photons, the cap of " +
                           grouped(settings.max_emitted_per_stored) +
                           " per requested photon): most photons leave the scene or land on nothing, so "
                           "indirect light is noisy. Aim the lights at the geometry or close the scene");
    }
    return warnings;
}

PhotonTracingSettings photon_settings(const protocol::Job& job, const RenderPlan& plan,
                                      const PipelineOptions& options) {
    PhotonTracingSettings settings;
    settings.global_photons = plan.global_map ? job.photons.global : 0;
    settings.caustic_photons = plan.caustic_map ? job.photons.caustic : 0;
    settings.seed = job.photons.seed;
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
            const std::filesystem::path root = std::filesystem::weakly_canonical(scene_root);
            const std::filesystem::path file = std::filesystem::weakly_canonical(root / ref.value);
            const auto [root_end, file_it] = std::mismatch(root.begin(), root.end(), file.begin(), file.end());
            if (root_end != root.end())
                return Error{"scene.path: '" + ref.value + "' lies outside the scene root"};
            GltfLoadOptions options;
            options.bundle_root = file.parent_path();
            auto scene = load_gltf_file(file, options);
            if (!scene) return scene.error();
            return std::make_shared<const Scene>(std::move(scene).value());
        }
        case protocol::SceneRef::Kind::Id:
            if (!options.scene_lookup) return Error{"scene.id: uploaded scenes are served by the daemon only"};
            return options.scene_lookup(ref.value);
    }
    return Error{"scene: unknown kind"};
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

    if (!job.output.aovs.empty())
        return Error{"output.aovs: the " + job.integrator + " integrator does not produce AOVs yet"};

    Clock::time_point pass_start = Clock::now();
    if (options.on_pass) options.on_pass("scene");
    auto scene = load_job_scene(job.scene, options);
    if (!scene) return scene.error();
    stats.passes.push_back({"scene", seconds_since(pass_start)});
    stats.warnings = (*scene)->warnings;

    pass_start = Clock::now();
    if (options.on_pass) options.on_pass("acceleration");
    auto render_scene = RenderScene::create(device, *scene);
    if (!render_scene) return render_scene.error();
    stats.passes.push_back({"acceleration", seconds_since(pass_start)});

    auto camera_desc = resolve_camera(job, **scene);
    if (!camera_desc) return camera_desc.error();
    auto camera = Camera::create(*camera_desc, job.image.width, job.image.height);
    if (!camera) return camera.error();
    auto integrator = make_integrator(job, *render_scene, options, stats);
    if (!integrator) return integrator.error();

    if (auto* photon_map = dynamic_cast<PhotonMapIntegrator*>(integrator->get())) {
        if (options.on_pass) options.on_pass("irradiance_cache");
        CacheBuildStatistics cache_stats;
        photon_map->prepare(*camera, &cache_stats);
        if (photon_map->cache()) {
            stats.irradiance_cache = RenderStatistics::IrradianceCacheFigures{};
            stats.irradiance_cache->records = cache_stats.records;
            stats.irradiance_cache->waves = cache_stats.waves;
            stats.irradiance_cache->seconds = cache_stats.seconds;
            stats.passes.push_back({"irradiance_cache", cache_stats.seconds});
            stats.rays += cache_stats.counters.rays;
            stats.shadow_rays += cache_stats.counters.shadow_rays;
        }
    }

    TileSettings tiles;
    tiles.tile_size = job.image.tile_size;
    tiles.samples_per_pixel = job.image.spp;
    tiles.seed = job.seed;
    tiles.threads = options.threads;
    if (job.image.region) {
        const auto& r = *job.image.region;
        tiles.region = PixelRect{r[0], r[1], r[2], r[3]};
    }
    pass_start = Clock::now();
    if (options.on_pass) options.on_pass("render");
    TileRenderResult rendered = render_tiles(**integrator, *camera, tiles, options.callbacks);
    stats.render_seconds = seconds_since(pass_start);
    stats.passes.push_back({"render", stats.render_seconds});
    stats.rays += rendered.counters.rays;
    stats.shadow_rays += rendered.counters.shadow_rays;
    if (stats.irradiance_cache) {
        stats.irradiance_cache->lookups = rendered.counters.irradiance_lookups;
        stats.irradiance_cache->misses = rendered.counters.irradiance_misses;
    }
    stats.cancelled = rendered.cancelled;
    stats.total_seconds = seconds_since(start);
    result.layers.beauty = std::move(rendered.image);
    return result;
}

}  // namespace photond::service
