#include "server/tile_png.h"

#include <cmath>

#include "core/image/png_preview.h"
#include "server/job_manager.h"
#include "server/service_error.h"

namespace photond::service {

TilePng make_tile_png(JobManager& jobs, const std::string& id, protocol::TileIndex tile,
                      std::optional<float> exposure_ev, bool or_preview) {
    if (exposure_ev && !(std::isfinite(*exposure_ev) && std::abs(*exposure_ev) <= kMaxAutomaticExposureEv))
        throw ServiceError(ErrorKind::MalformedRequest,
                           "exposure_ev: expected a number of stops in [-64, 64]");
    const std::string name =
        "tile (" + std::to_string(tile.tx) + ", " + std::to_string(tile.ty) + ") of job " + id;
    const auto geometry = jobs.tile_geometry(id, tile);  // NotFound for an unknown job
    if (!geometry) throw ServiceError(ErrorKind::NotFound, name + " is outside its tile grid");
    bool preview = false;
    const std::optional<ImageLayers> layers = jobs.tile_layers(id, tile, or_preview, &preview);
    if (!layers) {
        const protocol::JobStatus status = jobs.status(id);
        throw ServiceError(ErrorKind::NotFound,
                           protocol::is_terminal(status.state)
                               ? name + ": the job is " + std::string(protocol::to_string(status.state)) +
                                     " and its tiles are gone"
                               : name + " is not finished yet");
    }
    if (!exposure_ev) {
        const protocol::JobStatus status = jobs.status(id);
        if (status.job && status.job->output.exposure_ev)
            exposure_ev = static_cast<float>(*status.job->output.exposure_ev);
        else
            exposure_ev = automatic_exposure_ev(*jobs.preview_frame(id));
    }
    auto png = encode_render_preview(layers->beauty, exposure_ev);
    if (!png) throw ServiceError(ErrorKind::Internal, name + ": " + png.error().message);
    return {std::move(png).value(), *exposure_ev, geometry->rect, preview};
}

}  // namespace photond::service
