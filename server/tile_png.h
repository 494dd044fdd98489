// One finished tile of a job as an 8-bit sRGB PNG, made as the job's preview is made
// (encode_render_preview in core/image/png_preview.h: exposure, filmic tone curve, sRGB), so
// that tiles drawn side by side are the pixels of preview.png. Served as
// GET /v1/jobs/{id}/tiles/{tx}/{ty}.png (server/web_handlers.cpp) for the web page.
//
// The exposure, in this order: the one asked for (a client that draws many tiles pins one, so
// that they all match); the job's output.exposure_ev; else the automatic exposure of the
// preview at this moment (automatic_exposure_ev of the finished tiles while the job renders, of
// the final image when it is done), so that the tile equals that rectangle of preview.png. The
// automatic one reads every finished pixel: one request, not one per tile.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "protocol/job_status.h"

namespace photond::service {

class JobManager;

struct TilePng {
    std::vector<uint8_t> bytes;
    float exposure_ev = 0.0f;  // the exposure it was made with
    PixelRect rect;            // the tile's pixels in the frame
    bool preview = false;      // the progressive preview's pixels, not the final tile's
};

/// The tile's PNG; with `or_preview`, a tile not finished yet gives its progressive preview when
/// there is one (TilePng::preview). Throws ServiceError: NotFound for an unknown job, a tile
/// outside the grid, or one not finished yet (or gone: the job failed or was cancelled);
/// MalformedRequest for an exposure beyond +-kMaxAutomaticExposureEv or not finite.
TilePng make_tile_png(JobManager& jobs, const std::string& id, protocol::TileIndex tile,
                      std::optional<float> exposure_ev, bool or_preview = false);

}  // namespace photond::service
