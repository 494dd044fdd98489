// One job from description to image: load the scene, build its acceleration structure and
// lights, set up the camera and integrator, render the tiles. Shared by `photond render` and the
// daemon, so both produce the same bytes for the same job.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/accel/ray_tracer.h"
#include "core/photon/photon_tracer.h"
#include "core/image/exr_io.h"
#include "core/image/image.h"
#include "core/integrators/irradiance_cache.h"
#include "core/integrators/render_cache_store.h"
#include "core/render/render_plan.h"
#include "core/render/statistics.h"
#include "core/render/tile_renderer.h"
#include "core/scene/scene.h"
#include "core/scene/scene_lighting.h"
#include "protocol/job.h"
#include "protocol/render_settings.h"

namespace photond::service {

/// Where built photon maps are kept between jobs. `get_or_build` returns the maps for `key`
/// (from memory or disk) or calls `build` and keeps what it returns; it reports whether the maps
/// came from the cache. Implementations must be thread-safe.
class PhotonMapStore {
public:
    virtual ~PhotonMapStore() = default;
    virtual Expected<std::shared_ptr<const PhotonMaps>> get_or_build(
        const std::string& key, const std::function<Expected<PhotonMaps>()>& build, bool* cache_hit) = 0;
};

/// Resolves {"id": "sha256:..."} scenes (uploaded to the daemon).
using SceneLookup = std::function<Expected<std::shared_ptr<const Scene>>(const std::string& id)>;

/// The directory holding an uploaded scene's bundle files (environment images), if it has one.
using SceneBundleLookup = std::function<std::optional<std::filesystem::path>(const std::string& id)>;

/// Called when a pass starts ("scene", "acceleration", "photon_tracing", "preview",
/// "irradiance_cache", "render"), for status.
using PassCallback = std::function<void(const std::string& pass)>;

struct PipelineOptions {
    int threads = 0;                    // 0 = every core
    std::filesystem::path scene_root;   // {"path": ...} scenes are read below this directory only
    RenderCallbacks callbacks;          // per-tile progress and cancellation
    PhotonMapStore* photon_maps = nullptr;  // null: photon maps are built for this job only
    RenderCacheStore* render_caches = nullptr;  // null: irradiance caches are built for this job only
    bool caches_only = false;  // stop after the photon maps and the irradiance cache (no image)
    /// Render the progressive preview of a job that asks for one (job.progressive) before its
    /// irradiance cache and tiles, reported through callbacks.on_tile with TileEvent::preview:
    /// the daemon's jobs (their tiles stream); `photond render` leaves it off.
    bool previews = false;
    SceneLookup scene_lookup;               // null: {"id": ...} scenes are refused
    SceneBundleLookup bundle_lookup;        // null: uploaded scenes have no files for the job
    PassCallback on_pass;
};

struct PipelineResult {
    ImageLayers layers;
    RenderStatistics statistics;
};

/// Loads the scene a job names (builtin, or a glTF file below the scene root).
Expected<std::shared_ptr<const Scene>> load_job_scene(const protocol::SceneRef& ref,
                                                      const PipelineOptions& options);

/// The photon tracing settings of a photon-map job under its plan.
PhotonTracingSettings photon_settings(const protocol::RenderSettings& render_settings, const RenderPlan& plan,
                                      const PipelineOptions& options);

/// The lights and environment a job adds to `scene` (reading an environment image under the
/// scene root or the uploaded bundle), with the default environment for a scene without light;
/// `decision` receives the plan's "environment" entry. An error for `"environment": null` on a
/// scene without light, naming what to add.
Expected<AddedLighting> job_lighting(const protocol::Job& job, const Scene& scene, const PipelineOptions& options,
                                     PassDecision* decision);

/// What job_lighting would refuse, checked before a job is queued (so that the daemon answers
/// 422 at once): an environment image that is missing or outside the scene root or bundle, and
/// `"environment": null` on a scene without light (this one loads the scene).
std::optional<protocol::FieldError> check_job_lighting(const protocol::Job& job, const PipelineOptions& options);
/// What the job's material_media would refuse, checked before a job is queued (this loads the
/// scene when the job has entries): a material name the scene lacks, or one that is not
/// transmissive.
std::optional<protocol::FieldError> check_job_media(const protocol::Job& job, const PipelineOptions& options);
/// Whether the caustic map stopped early because its photons carry a negligible share of the
/// light (kNegligibleCausticShare; core/photon/photon_tracer.h), not at the emission cap.
bool caustic_stopped_as_negligible(const PhotonTracingStatistics& photons, const PhotonTracingSettings& settings);
/// A warning per photon map the emission cap stopped short, with what to change.
std::vector<std::string> incomplete_photon_map_warnings(const PhotonTracingStatistics& photons,
                                                        const PhotonTracingSettings& settings);

/// The camera a job asks for: its own, the scene's glTF camera, or a view of the whole scene.
Expected<CameraDesc> resolve_camera(const protocol::Job& job, const Scene& scene);

/// Renders a validated job.
Expected<PipelineResult> run_job(const protocol::Job& job, std::shared_ptr<EmbreeDevice> device,
                                 const PipelineOptions& options);

/// How a job's EXR is written: its pixel type and tile size, and a region render's region as
/// the data window (so that `photond assemble` can join the regions of a frame).
ExrWriteOptions exr_options(const protocol::Job& job);

/// The PNG preview of a job's image (encode_render_preview with the job's output.exposure_ev):
/// every preview, `photond render --preview` and the daemon's preview.png (finished, or the
/// tiles so far), is made here.
Expected<std::vector<uint8_t>> encode_job_preview(const protocol::Job& job, const Image& image);

}  // namespace photond::service
