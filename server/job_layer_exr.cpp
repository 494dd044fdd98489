#include "server/job_layer_exr.h"

#include <algorithm>

#include "core/image/exr_io.h"
#include "server/job_manager.h"
#include "server/render_pipeline.h"
#include "server/service_error.h"

namespace photond::service {

std::vector<uint8_t> make_layer_exr(JobManager& jobs, const std::string& id, const std::string& layer) {
    const protocol::JobStatus status = jobs.status(id);
    const protocol::Job& job = *status.job;
    const std::vector<std::string>& aovs = job.output.aovs;
    if (std::find(aovs.begin(), aovs.end(), layer) == aovs.end()) {
        std::string asked;
        for (const std::string& name : aovs) asked += (asked.empty() ? "" : ", ") + name;
        throw ServiceError(ErrorKind::NotFound,
                           "job " + id + " has no layer '" + layer + "' (its output.aovs: " +
                               (asked.empty() ? "none" : asked) + ")");
    }
    auto image = read_exr(jobs.image_file(id));  // Conflict unless done
    if (!image) throw ServiceError(ErrorKind::Internal, image.error().message);
    const Image* values = image->find_aov(layer);
    if (!values) throw ServiceError(ErrorKind::Internal, "job " + id + ": its image has no layer " + layer);
    ImageLayers alone;
    alone.beauty = *values;
    auto bytes = encode_exr(alone, exr_options(job));
    if (!bytes) throw ServiceError(ErrorKind::Internal, bytes.error().message);
    return std::move(bytes).value();
}

}  // namespace photond::service
