// One AOV layer of a done job (output.aovs) as an EXR of its own, its values in R, G and B, for
// those who want the layer without the beauty and the other layers: the web page's download
// buttons, GET /v1/jobs/{id}/layers/{layer}.exr (server/web_handlers.cpp). Written as the job's
// image is (exr_options in server/render_pipeline.h: pixel type, tiles, region).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace photond::service {

class JobManager;

/// The layer's EXR. Throws ServiceError: NotFound for an unknown job or a layer the job did not
/// ask for (naming those it did); Conflict while the job is not done (as its image.exr).
std::vector<uint8_t> make_layer_exr(JobManager& jobs, const std::string& id, const std::string& layer);

}  // namespace photond::service
