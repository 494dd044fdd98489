// From the job description to the renderer's settings: the one place where a job's fields become
// the settings of the core passes (photon tracing, the photon-map integrator and its irradiance
// cache, the tiles, the EXR and its preview). What a job does not decide (threads, cancellation)
// is left at its default for the caller to set.
#pragma once

#include <optional>
#include <string>

#include "core/image/exr_io.h"
#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"
#include "core/render/preview_renderer.h"
#include "core/render/tile_renderer.h"
#include "protocol/job.h"

namespace photond::protocol {

struct RenderSettings {
    std::string integrator;  // one of kIntegratorNames
    /// The photon counts the job asks for; the render plan drops a map the scene does not need.
    PhotonTracingSettings photon_tracing;
    /// How next-event estimation picks lights (RenderScene::create builds the lights with it).
    LightSelection light_selection = LightSelection::Tree;
    PhotonMapIntegratorSettings photon_map;
    TileSettings tiles;
    /// The progressive preview before the tiles (job.progressive); the daemon renders it, the
    /// offline `photond render` never does (nothing streams its tiles).
    std::optional<PreviewSettings> preview;
    ExrWriteOptions exr;
    std::optional<float> preview_exposure_ev;  // nullopt: automatic
};

RenderSettings to_render_settings(const Job& job);

}  // namespace photond::protocol
