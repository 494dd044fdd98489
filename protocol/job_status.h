// The daemon's answers (README.md, "Using the daemon with curl"; docs/ARCHITECTURE.md): a job's status, the events of its SSE stream
// and RFC 9457 problem details, as plain structs with their JSON mapping, plus JSON Schemas of
// them for the OpenAPI document. Shared by the daemon and its clients. Versioned by adding
// fields, never by changing what a field means.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/util/expected.h"
#include "protocol/job.h"

namespace photond::protocol {

/// queued -> running -> done | failed | cancelled; a queued job may also go straight to
/// cancelled.
enum class JobState { Queued, Running, Done, Failed, Cancelled };

inline constexpr std::array<std::string_view, 5> kJobStateNames{"queued", "running", "done",
                                                                "failed", "cancelled"};

std::string_view to_string(JobState state);
std::optional<JobState> parse_job_state(std::string_view name);
/// done, failed and cancelled: the job never changes again.
bool is_terminal(JobState state);

struct JobProgress {
    uint64_t tiles_done = 0;
    uint64_t tiles_total = 0;

    /// tiles_done / tiles_total in [0, 1] (0 for a job without tiles).
    double fraction() const;
    bool operator==(const JobProgress&) const = default;
};

/// One pass's duration ("scene", "acceleration", "photon_tracing", "photon_kdtree", "render",
/// "writing"); a pass whose photon maps came from the cache lasts 0 s.
struct PassTime {
    std::string name;
    double seconds = 0.0;
    bool operator==(const PassTime&) const = default;
};

/// One entry of the render plan: a pass and why it runs or is skipped.
struct PlanEntry {
    std::string pass;
    bool enabled = false;
    std::string reason;
    bool operator==(const PlanEntry&) const = default;
};

/// GET /v1/jobs/{id}. Times are milliseconds since the Unix epoch (0: not yet), written as
/// RFC 3339 UTC strings.
struct JobStatus {
    std::string id;
    JobState state = JobState::Queued;
    /// The pass running now; empty unless the job is running.
    std::string pass;
    JobProgress progress;
    int priority = 0;
    int64_t created_at_ms = 0;
    int64_t started_at_ms = 0;
    int64_t finished_at_ms = 0;
    /// Why the job failed (or was cancelled by whom); empty otherwise.
    std::string error;
    /// How many times the daemon died (a crash, kill -9, power loss) while this job was running;
    /// the job resumes from its finished tiles after each, up to a limit (a poison job).
    int crashes = 0;
    /// "hit" when the photon maps came from the cache, "miss" when traced, empty otherwise.
    std::string photon_cache;
    std::string photon_map_key;
    /// The plan of passes (photon-map jobs), once decided.
    std::vector<PlanEntry> plan;
    /// Pass durations so far, in the order the passes ran.
    std::vector<PassTime> timings;
    /// What the user should know about the render (ignored glTF features, an incomplete photon
    /// map, ...), one sentence each, once the render ended; the same as statistics.warnings.
    std::vector<std::string> warnings;
    /// The render statistics (protocol::to_json(RenderStatistics)) once the render ended.
    std::optional<nlohmann::json> statistics;
    /// The job description with every default filled (absent in job lists).
    std::optional<Job> job;

    bool operator==(const JobStatus&) const = default;
};

/// The links of a job: "self", "events", "tiles", "image", "preview".
nlohmann::json job_links(const std::string& id);

/// The status document; `links` adds the job's URLs.
nlohmann::json to_json(const JobStatus& status, bool links = true);
/// Reads a status document written by to_json (unknown members are ignored, so newer daemons
/// stay readable).
Expected<JobStatus> job_status_from_json(const nlohmann::json& document);

/// RFC 3339 UTC with milliseconds ("2024-06-12T10:15:30.123Z"); empty for 0.
std::string format_timestamp(int64_t unix_ms);
/// The inverse of format_timestamp; nullopt for anything else.
std::optional<int64_t> parse_timestamp(std::string_view text);

/// The SSE event types of GET /v1/jobs/{id}/events:
///   state      {"state", "reason"?}                    every state change
///   progress   {"tiles_done", "tiles_total", "fraction", "pass"}
///   tile       {"tx", "ty", "rect": [x0, y0, x1, y1], "url", "tiles_done", "tiles_total"}; a
///              tile of the progressive preview adds "preview": true and "preview_tiles_done"
///              (its final tile follows later as a tile event without them)
///   done       the final status document
///   failed     {"error"} and the final status document's members
///   cancelled  the final status document
/// A stream ends after done, failed or cancelled.
enum class JobEventType { State, Progress, Tile, Done, Failed, Cancelled };

inline constexpr std::array<std::string_view, 6> kJobEventTypeNames{
    "state", "progress", "tile", "done", "failed", "cancelled"};

std::string_view to_string(JobEventType type);
std::optional<JobEventType> parse_job_event_type(std::string_view name);

/// One event; ids increase by one from 1 within a job.
struct JobEvent {
    uint64_t id = 0;
    JobEventType type = JobEventType::State;
    nlohmann::json data;

    bool operator==(const JobEvent&) const = default;
};

/// Tiles count from the top-left corner of the rendered area (the region's, else the frame's):
/// tile (tx, ty) covers [x0 + tx * size, ...) clipped to the area.
struct TileIndex {
    int tx = 0;
    int ty = 0;
    bool operator==(const TileIndex&) const = default;
    auto operator<=>(const TileIndex&) const = default;
};

/// "/v1/jobs/{id}/tiles/{tx}/{ty}.exr", with `preview` "...exr?preview=true" (the tile's
/// progressive preview until its final pixels replace it).
std::string tile_url(const std::string& job_id, TileIndex tile, bool preview = false);

/// The event as Server-Sent Events text: "id: N\nevent: TYPE\ndata: JSON\n\n".
std::string format_sse(const JobEvent& event);

/// RFC 9457 problem details (application/problem+json). `field` names the offending field of a
/// job for validation errors ("irradiance_cache.a"); empty otherwise.
struct Problem {
    std::string type = "about:blank";
    std::string title;
    int status = 500;
    std::string detail;
    std::string field;
    std::string instance;

    bool operator==(const Problem&) const = default;
};

nlohmann::json to_json(const Problem& problem);
Expected<Problem> problem_from_json(const nlohmann::json& document);

/// JSON Schemas (draft 2020-12) of the documents above, for the OpenAPI document.
nlohmann::json job_status_json_schema();
nlohmann::json job_event_json_schema();
nlohmann::json problem_json_schema();

}  // namespace photond::protocol
