// Job status documents (GET /v1/jobs/{id}) as text for people: the `status` and `list`
// commands and the progress bar. Lenient by design: a field the server leaves out is skipped,
// an unknown one is ignored (`--json` shows everything).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace photond::client {

struct JobProgress {
    int64_t tiles_done = 0;
    int64_t tiles_total = 0;
    double fraction = 0.0;  ///< in [0, 1]
};

/// The "state" member, or "" when absent.
std::string job_state(const nlohmann::json& status);

/// done, failed and cancelled: the job will not change any more.
bool is_terminal_state(std::string_view state);

/// The progress of a status document or of a progress event: from its "progress" member or
/// from the document itself (tiles_done, tiles_total, fraction); nullopt when neither has one.
std::optional<JobProgress> read_progress(const nlohmann::json& document);

/// "builtin:cornell-box", "path:rel/scene.glb", "sha256:..." for a job's "scene" object.
std::string describe_scene(const nlohmann::json& scene);

/// A job's "error" member (a string, a problem object or anything else) as one line.
std::string describe_job_error(const nlohmann::json& error);

/// A status document as aligned "name: value" lines, each ending in '\n'.
std::string format_status(const nlohmann::json& status);

/// A list of status documents as a table with a header line, or "no jobs\n".
std::string format_job_list(const nlohmann::json& jobs);

/// "[#######-------]  50%  24/48 tiles" with a bar of `width` characters.
std::string progress_bar(const JobProgress& progress, int width);

}  // namespace photond::client
