#include "protocol/job_status.h"

#include <algorithm>
#include <cstdio>
#include <ctime>

#include "protocol/json_text.h"

namespace photond::protocol {
namespace {

using nlohmann::json;

template <size_t N>
std::optional<size_t> index_of(const std::array<std::string_view, N>& names,
                               std::string_view name) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) return std::nullopt;
    return static_cast<size_t>(it - names.begin());
}

json enum_schema(std::span<const std::string_view> names, std::string description) {
    json values = json::array();
    for (std::string_view name : names) values.push_back(std::string(name));
    return {{"type", "string"}, {"enum", values}, {"description", std::move(description)}};
}

json timestamp_schema(std::string description) {
    return {{"type", "string"}, {"format", "date-time"}, {"description", std::move(description)}};
}

json progress_schema() {
    return {{"type", "object"},
            {"required", {"tiles_done", "tiles_total", "fraction"}},
            {"properties",
             {{"tiles_done", {{"type", "integer"}, {"minimum", 0}}},
              {"tiles_total", {{"type", "integer"}, {"minimum", 0}}},
              {"fraction", {{"type", "number"}, {"minimum", 0}, {"maximum", 1}}}}}};
}

}  // namespace

std::string_view to_string(JobState state) { return kJobStateNames[static_cast<size_t>(state)]; }

std::optional<JobState> parse_job_state(std::string_view name) {
    const auto index = index_of(kJobStateNames, name);
    if (!index) return std::nullopt;
    return static_cast<JobState>(*index);
}

bool is_terminal(JobState state) {
    return state == JobState::Done || state == JobState::Failed || state == JobState::Cancelled;
}

double JobProgress::fraction() const {
    if (tiles_total == 0) return 0.0;
    return std::min(1.0, static_cast<double>(tiles_done) / static_cast<double>(tiles_total));
}

std::string_view to_string(JobEventType type) {
    return kJobEventTypeNames[static_cast<size_t>(type)];
}

std::optional<JobEventType> parse_job_event_type(std::string_view name) {
    const auto index = index_of(kJobEventTypeNames, name);
    if (!index) return std::nullopt;
    return static_cast<JobEventType>(*index);
}

std::string format_timestamp(int64_t unix_ms) {
    if (unix_ms <= 0) return {};
    const std::time_t seconds = static_cast<std::time_t>(unix_ms / 1000);
    std::tm utc{};
    gmtime_r(&seconds, &utc);
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", utc.tm_year + 1900,
                  utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec,
                  static_cast<int>(unix_ms % 1000));
    return buffer;
}

std::optional<int64_t> parse_timestamp(std::string_view text) {
    const std::string s(text);
    std::tm utc{};
    int milliseconds = 0;
    int consumed = 0;
    if (std::sscanf(s.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d.%3dZ%n", &utc.tm_year, &utc.tm_mon,
                    &utc.tm_mday, &utc.tm_hour, &utc.tm_min, &utc.tm_sec, &milliseconds,
                    &consumed) != 7 ||
        static_cast<size_t>(consumed) != s.size())
        return std::nullopt;
    utc.tm_year -= 1900;
    utc.tm_mon -= 1;
    const std::time_t seconds = timegm(&utc);
    if (seconds < 0) return std::nullopt;
    return int64_t{seconds} * 1000 + milliseconds;
}

json job_links(const std::string& id) {
    const std::string self = "/v1/jobs/" + id;
    return {{"self", self},
            {"events", self + "/events"},
            {"tiles", self + "/tiles"},
            {"image", self + "/image.exr"},
            {"preview", self + "/preview.png"}};
}

json to_json(const JobStatus& s, bool links) {
    json document = {
        {"id", s.id},
        {"state", std::string(to_string(s.state))},
        {"priority", s.priority},
        {"progress",
         {{"tiles_done", s.progress.tiles_done},
          {"tiles_total", s.progress.tiles_total},
          {"fraction", s.progress.fraction()}}},
        {"created_at", format_timestamp(s.created_at_ms)},
    };
    if (!s.pass.empty()) document["pass"] = s.pass;
    if (s.started_at_ms > 0) document["started_at"] = format_timestamp(s.started_at_ms);
    if (s.finished_at_ms > 0) document["finished_at"] = format_timestamp(s.finished_at_ms);
    if (!s.error.empty()) document["error"] = s.error;
    if (s.crashes > 0) document["crashes"] = s.crashes;
    if (!s.plan.empty()) {
        json plan = json::array();
        for (const PlanEntry& e : s.plan)
            plan.push_back({{"pass", e.pass}, {"enabled", e.enabled}, {"reason", e.reason}});
        document["plan"] = std::move(plan);
    }
    if (!s.warnings.empty()) document["warnings"] = s.warnings;
    if (!s.timings.empty()) {
        json timings = json::object();
        for (const PassTime& t : s.timings) timings[t.name] = t.seconds;
        document["timings"] = std::move(timings);
    }
    // A short photon summary at the top, so that `jq .photons.cache` answers "was it a hit?".
    json photons = json::object();
    if (s.statistics && s.statistics->contains("photons")) photons = s.statistics->at("photons");
    if (!s.photon_cache.empty()) photons["cache"] = s.photon_cache;
    if (!s.photon_map_key.empty()) photons["key"] = s.photon_map_key;
    if (!photons.empty()) document["photons"] = std::move(photons);
    if (s.statistics) document["statistics"] = *s.statistics;
    if (s.job) document["job"] = to_json(*s.job);
    if (links) document["links"] = job_links(s.id);
    return document;
}

Expected<JobStatus> job_status_from_json(const json& d) {
    try {
        JobStatus s;
        s.id = d.at("id").get<std::string>();
        const auto state = parse_job_state(d.at("state").get<std::string>());
        if (!state) return Error{"status: unknown state " + json_text(d.at("state"))};
        s.state = *state;
        s.pass = d.value("pass", std::string());
        s.priority = d.value("priority", 0);
        if (const auto it = d.find("progress"); it != d.end()) {
            s.progress.tiles_done = it->value("tiles_done", uint64_t{0});
            s.progress.tiles_total = it->value("tiles_total", uint64_t{0});
        }
        auto time_of = [&](const char* name) -> int64_t {
            const auto it = d.find(name);
            if (it == d.end() || !it->is_string()) return 0;
            return parse_timestamp(it->get<std::string>()).value_or(0);
        };
        s.created_at_ms = time_of("created_at");
        s.started_at_ms = time_of("started_at");
        s.finished_at_ms = time_of("finished_at");
        s.error = d.value("error", std::string());
        s.crashes = d.value("crashes", 0);
        if (const auto it = d.find("photons"); it != d.end() && it->is_object()) {
            s.photon_cache = it->value("cache", std::string());
            s.photon_map_key = it->value("key", std::string());
        }
        if (const auto it = d.find("plan"); it != d.end()) {
            for (const json& e : *it)
                s.plan.push_back({e.at("pass").get<std::string>(), e.at("enabled").get<bool>(),
                                  e.value("reason", std::string())});
        }
        if (const auto it = d.find("warnings"); it != d.end() && it->is_array())
            for (const json& w : *it)
                if (w.is_string()) s.warnings.push_back(w.get<std::string>());
        if (const auto it = d.find("statistics"); it != d.end()) {
            s.statistics = *it;
            // The pass order lives in the statistics; the "timings" object is sorted by name.
            for (const json& p : it->value("passes", json::array()))
                s.timings.push_back(
                    {p.at("name").get<std::string>(), p.at("seconds").get<double>()});
        }
        if (s.timings.empty()) {
            if (const auto it = d.find("timings"); it != d.end() && it->is_object())
                for (const auto& [name, seconds] : it->items())
                    s.timings.push_back({name, seconds.get<double>()});
        }
        if (const auto it = d.find("job"); it != d.end()) {
            auto job = parse_job(*it);
            if (!job) return Error{"status: job: " + job.error().message};
            s.job = std::move(job).value();
        }
        return s;
    } catch (const json::exception& e) {
        return Error{std::string("status: ") + e.what()};
    }
}

std::string tile_url(const std::string& job_id, TileIndex tile, bool preview) {
    return "/v1/jobs/" + job_id + "/tiles/" + std::to_string(tile.tx) + "/" +
           std::to_string(tile.ty) + ".exr" + (preview ? "?preview=true" : "");
}

std::string format_sse(const JobEvent& event) {
    // dump() escapes control characters, so the data is one line and needs one "data:" field.
    return "id: " + std::to_string(event.id) + "\nevent: " + std::string(to_string(event.type)) +
           "\ndata: " + json_text(event.data) + "\n\n";
}

json to_json(const Problem& p) {
    json document = {{"type", p.type}, {"title", p.title}, {"status", p.status}};
    if (!p.detail.empty()) document["detail"] = p.detail;
    // An invalid field is always named; "" is the whole document (e.g. not a JSON object).
    if (!p.field.empty() || p.status == 422) document["field"] = p.field;
    if (!p.instance.empty()) document["instance"] = p.instance;
    return document;
}

Expected<Problem> problem_from_json(const json& d) {
    if (!d.is_object()) return Error{"problem: not a JSON object"};
    Problem p;
    p.type = d.value("type", std::string("about:blank"));
    p.title = d.value("title", std::string());
    p.status = d.value("status", 0);
    p.detail = d.value("detail", std::string());
    p.field = d.value("field", std::string());
    p.instance = d.value("instance", std::string());
    return p;
}

json job_status_json_schema() {
    json plan_entry = {{"type", "object"},
                       {"required", {"pass", "enabled", "reason"}},
                       {"properties",
                        {{"pass", {{"type", "string"}}},
                         {"enabled", {{"type", "boolean"}}},
                         {"reason", {{"type", "string"}}}}}};
    json properties = {
        {"id", {{"type", "string"}, {"description", "the job's id"}}},
        {"state", enum_schema(kJobStateNames, "where the job stands")},
        {"pass",
         {{"type", "string"},
          {"description",
           "the pass running now: scene, acceleration, photon_tracing, render, writing"}}},
        {"priority", {{"type", "integer"}}},
        {"progress", progress_schema()},
        {"created_at", timestamp_schema("when the job was submitted")},
        {"started_at", timestamp_schema("when its render started")},
        {"finished_at", timestamp_schema("when it ended")},
        {"error", {{"type", "string"}, {"description", "why the job failed"}}},
        {"crashes",
         {{"type", "integer"},
          {"minimum", 1},
          {"description",
           "how many times the daemon died while the job was running (absent: never); it resumes "
           "from its finished tiles after each"}}},
        {"plan", {{"type", "array"}, {"items", plan_entry}}},
        {"warnings",
         {{"type", "array"},
          {"items", {{"type", "string"}}},
          {"description",
           "what the render ignored or could not do as asked (unsupported glTF features, an "
           "incomplete photon map), with what to change"}}},
        {"timings",
         {{"type", "object"},
          {"additionalProperties", {{"type", "number"}, {"minimum", 0}}},
          {"description", "seconds per pass; photon_tracing is 0 on a photon-map cache hit"}}},
        {"photons",
         {{"type", "object"},
          {"description", "the photon pass: cache hit or miss, content key, photon counts"},
          {"properties",
           {{"cache", {{"type", "string"}, {"enum", {"hit", "miss"}}}},
            {"key", {{"type", "string"}}}}}}},
        {"statistics", {{"type", "object"}, {"description", "the render statistics"}}},
        {"job", {{"$ref", "#/components/schemas/Job"}}},
        {"links", {{"type", "object"}, {"additionalProperties", {{"type", "string"}}}}},
    };
    return {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
            {"title", "photond job status v1"},
            {"type", "object"},
            {"required", {"id", "state", "priority", "progress", "created_at"}},
            {"properties", properties}};
}

json job_event_json_schema() {
    return {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
            {"title", "photond job event v1"},
            {"description",
             "one Server-Sent Event: `id:` the event id, `event:` the type, `data:` this JSON. "
             "state: {state, reason?}; progress: {tiles_done, tiles_total, fraction, pass}; tile: "
             "{tx, ty, rect, url, tiles_done, tiles_total}, and for a tile of the progressive preview "
             "preview: true and preview_tiles_done (its final tile follows as a tile event without "
             "them); done and cancelled: the final status; failed: the final status (with error)."},
            {"type", "object"},
            {"properties",
             {{"state", enum_schema(kJobStateNames, "state events: the new state")},
              {"reason", {{"type", "string"}}},
              {"pass", {{"type", "string"}}},
              {"tiles_done", {{"type", "integer"}, {"minimum", 0}}},
              {"tiles_total", {{"type", "integer"}, {"minimum", 0}}},
              {"fraction", {{"type", "number"}, {"minimum", 0}, {"maximum", 1}}},
              {"tx", {{"type", "integer"}, {"minimum", 0}}},
              {"ty", {{"type", "integer"}, {"minimum", 0}}},
              {"rect",
               {{"type", "array"},
                {"items", {{"type", "integer"}}},
                {"minItems", 4},
                {"maxItems", 4},
                {"description", "[x0, y0, x1, y1], half-open, frame pixels"}}},
              {"url", {{"type", "string"}}},
              {"preview",
               {{"type", "boolean"},
                {"description", "tile events: a tile of the progressive preview (absent: a final tile)"}}},
              {"preview_tiles_done", {{"type", "integer"}, {"minimum", 0}}},
              {"error", {{"type", "string"}}}}},
            {"x-event-types", enum_schema(kJobEventTypeNames, "the SSE `event:` field")}};
}

json problem_json_schema() {
    return {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
            {"title", "RFC 9457 problem details"},
            {"type", "object"},
            {"required", {"type", "title", "status"}},
            {"properties",
             {{"type", {{"type", "string"}, {"format", "uri-reference"}}},
              {"title", {{"type", "string"}}},
              {"status", {{"type", "integer"}, {"minimum", 400}, {"maximum", 599}}},
              {"detail", {{"type", "string"}}},
              {"field",
               {{"type", "string"},
                {"description", "the offending job field's path, e.g. irradiance_cache.a"}}},
              {"instance", {{"type", "string"}, {"format", "uri-reference"}}}}}};
}

}  // namespace photond::protocol
