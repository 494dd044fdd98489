// One job from description to image: load the scene, build its acceleration structure and
// lights, set up the camera and integrator, render the tiles. Shared by `photond render` and the
// daemon, so both produce the same bytes for the same job.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>

#include "core/accel/ray_tracer.h"
#include "core/image/image.h"
#include "core/render/statistics.h"
#include "core/render/tile_renderer.h"
#include "core/scene/scene.h"
#include "protocol/job.h"

namespace photond::service {

struct PipelineOptions {
    int threads = 0;                    // 0 = every core
    std::filesystem::path scene_root;   // {"path": ...} scenes are read below this directory only
    RenderCallbacks callbacks;          // per-tile progress and cancellation
};

struct PipelineResult {
    ImageLayers layers;
    RenderStatistics statistics;
};

/// Loads the scene a job names (builtin, or a glTF file below the scene root).
Expected<std::shared_ptr<const Scene>> load_job_scene(const protocol::SceneRef& ref,
                                                      const std::filesystem::path& scene_root);

/// The camera a job asks for: its own, the scene's glTF camera, or a view of the whole scene.
Expected<CameraDesc> resolve_camera(const protocol::Job& job, const Scene& scene);

/// Renders a validated job.
Expected<PipelineResult> run_job(const protocol::Job& job, std::shared_ptr<EmbreeDevice> device,
                                 const PipelineOptions& options);

}  // namespace photond::service
