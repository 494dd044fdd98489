#include "server/routes.h"

#include <stdexcept>
#include <string_view>
#include <utility>

#include "protocol/job_status.h"

namespace photond::service {
namespace {

using nlohmann::json;

// Pieces of OpenAPI 3.1 objects.

json ref(const std::string& schema) { return {{"$ref", "#/components/schemas/" + schema}}; }

json content(const std::string& type, json schema) {
    return {{type, {{"schema", std::move(schema)}}}};
}

json response(const std::string& description, json body = nullptr) {
    json r = {{"description", description}};
    if (!body.is_null()) r["content"] = std::move(body);
    return r;
}

json json_response(const std::string& description, const std::string& schema) {
    return response(description, content("application/json", ref(schema)));
}

json binary_response(const std::string& description, const std::string& type) {
    return response(description, content(type, {{"type", "string"}, {"contentMediaType", type}}));
}

json list_response(const std::string& description, const std::string& member, json items) {
    return response(
        description,
        content("application/json",
                {{"type", "object"},
                 {"properties", {{member, {{"type", "array"}, {"items", std::move(items)}}}}}}));
}

json problem(const std::string& description) {
    return response(description, content("application/problem+json", ref("Problem")));
}

json query_parameter(const std::string& name, const std::string& description, json schema) {
    return {{"name", name},
            {"in", "query"},
            {"required", false},
            {"description", description},
            {"schema", std::move(schema)}};
}

json header_parameter(const std::string& name, const std::string& description) {
    return {{"name", name},
            {"in", "header"},
            {"required", false},
            {"description", description},
            {"schema", {{"type", "string"}}}};
}

json binary_body(std::initializer_list<std::string> types) {
    json media = json::object();
    for (const std::string& type : types)
        media[type] = {{"schema", {{"type", "string"}, {"contentMediaType", type}}}};
    return {{"required", true}, {"content", std::move(media)}};
}

const PathParameter kJobId{"id", "[A-Za-z0-9_-]{1,128}", "the job's id"};
const PathParameter kSceneId{"id", "[^/]+", "sha256:<64 hex digits>"};
const PathParameter kTileColumn{"tx", "[0-9]{1,9}", "tile column"};
const PathParameter kTileRow{"ty", "[0-9]{1,9}", "tile row"};
// The tile endpoints' ?preview=true: the progressive preview of a tile not finished yet.
const json kPreviewParameter = query_parameter(
    "preview", "while the final tile is not finished, its progressive preview (the URL of a preview tile event)",
    {{"type", "boolean"}});

/// The routes of a cache of artifacts (photon maps, render caches): list, export, import.
void add_artifact_routes(std::vector<Route>& routes, const std::string& base,
                         const std::string& name, const std::string& plural,
                         const std::string& operation_suffix, const std::string& list_suffix,
                         const std::string& key_form) {
    const PathParameter key{"key", "[^/]+", key_form};
    routes.push_back(
        {.method = "GET",
         .path = base,
         .operation_id = "list" + list_suffix,
         .summary = "Keys of the " + plural + " cached here",
         .responses = {{"200", list_response("the keys", "keys", {{"type", "string"}})}}});
    routes.push_back(
        {.method = "GET",
         .path = base + "/{key}",
         .operation_id = "export" + operation_suffix,
         .summary = "Export " + plural + " (the photond " + name + " file format)",
         .path_parameters = {key},
         .responses = {{"200", binary_response("the file", "application/octet-stream")},
                       {"404", problem("unknown key")}}});
    routes.push_back(
        {.method = "PUT",
         .path = base + "/{key}",
         .operation_id = "import" + operation_suffix,
         .summary = "Import " + plural + " exported by another node (checked against the key)",
         .path_parameters = {key},
         .request_body = binary_body({"application/octet-stream"}),
         .responses = {{"201", response("imported")},
                       {"200", response("already cached; the bytes were checked")},
                       {"404", problem("not a " + name + " key")},
                       {"409", problem("a different valid " + name + " is kept under the key")},
                       {"413", problem("request body too large")},
                       {"422", problem("corrupt, truncated, or for another key")}}});
}

std::vector<Route> build_routes() {
    std::vector<Route> routes;
    // Jobs.
    routes.push_back(
        {.method = "POST",
         .path = "/v1/jobs",
         .operation_id = "submitJob",
         .summary = "Queue a render job",
         .query_and_header_parameters = json::array({header_parameter(
             "Idempotency-Key", "a retry with the same key and body returns the same job")}),
         .request_body = {{"required", true}, {"content", content("application/json", ref("Job"))}},
         .responses = {
             {"202", json_response("queued; Location: /v1/jobs/{id}", "JobStatus")},
             {"200",
              json_response("an earlier job with the same Idempotency-Key and body", "JobStatus")},
             {"400", problem("malformed JSON")},
             {"409", problem("the Idempotency-Key was used with another job description")},
             {"413", problem("request body too large (--max-body-mb)")},
             {"422", problem("invalid job: `field` names the offending field")},
             {"429", problem("the queue is full (--max-queued); Retry-After says when to retry")},
             {"503", problem("shutting down")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/jobs",
         .operation_id = "listJobs",
         .summary = "Jobs, newest first",
         .query_and_header_parameters =
             json::array({query_parameter("state", "only jobs in this state",
                                          {{"type", "string"}, {"enum", protocol::kJobStateNames}}),
                          query_parameter("limit", "at most this many",
                                          {{"type", "integer"}, {"minimum", 1}})}),
         .responses = {{"200", list_response("the jobs", "jobs", ref("JobStatus"))},
                       {"400", problem("bad query")}}});
    routes.push_back(
        {.method = "POST",
         .path = "/v1/batches",
         .operation_id = "submitBatch",
         .summary =
             "Queue views of one scene as a job each, in order: photon maps traced once, each "
             "view's irradiance cache starting from the one before",
         .request_body =
             {{"required", true},
              {"content",
               content("application/json",
                       {{"type", "object"},
                        {"required", json::array({"job", "cameras"})},
                        {"additionalProperties", false},
                        {"properties",
                         {{"job",
                           {{"description", "the job every view shares (without camera)"},
                            {"$ref", "#/components/schemas/Job"}}},
                          {"cameras",
                           {{"type", "array"},
                            {"minItems", 1},
                            {"maxItems", 1000},
                            {"description", "one camera per view (the Job's camera field)"}}}}}})}},
         .responses = {
             {"202", list_response("queued", "jobs", ref("JobStatus"))},
             {"400", problem("malformed JSON")},
             {"413", problem("request body too large (--max-body-mb)")},
             {"422", problem("invalid batch: `field` names job.<field> or cameras[k].<field>")},
             {"429", problem("the queue cannot take the whole batch (--max-queued)")},
             {"503", problem("shutting down")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/jobs/{id}",
         .operation_id = "getJob",
         .summary = "A job's state, progress, plan, timings, photon-map cache and error",
         .path_parameters = {kJobId},
         .responses = {{"200", json_response("the status", "JobStatus")},
                       {"404", problem("unknown job")}}});
    routes.push_back(
        {.method = "DELETE",
         .path = "/v1/jobs/{id}",
         .operation_id = "cancelJob",
         .summary = "Cancel a queued or running job (stops within about one tile)",
         .path_parameters = {kJobId},
         .responses = {
             {"200", json_response("cancelled", "JobStatus")},
             {"202", json_response("asked to stop; still finishing its current tile", "JobStatus")},
             {"404", problem("unknown job")},
             {"409", problem("the job is already done or failed")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/jobs/{id}/events",
         .operation_id = "jobEvents",
         .summary =
             "Server-Sent Events: state, progress, tile, done, failed, cancelled; the history "
             "first, then live; ends after done, failed or cancelled",
         .path_parameters = {kJobId},
         .query_and_header_parameters = json::array(
             {header_parameter("Last-Event-ID", "resume after this event id"),
              query_parameter("last_event_id", "as the header, for clients that cannot set it",
                              {{"type", "integer"}, {"minimum", 0}})}),
         .responses = {{"200", response("text/event-stream of JobEvent data",
                                        content("text/event-stream", ref("JobEvent")))},
                       {"400", problem("Last-Event-ID is not an event id")},
                       {"404", problem("unknown job")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/jobs/{id}/tiles",
         .operation_id = "jobTileStream",
         .summary =
             "multipart/mixed stream of tile EXRs as they finish (finished ones first); each part "
             "has Content-Type image/x-exr, Content-Length, X-Tile-X, X-Tile-Y and X-Tile-Rect "
             "(x0,y0,x1,y1); the closing boundary ends it when the job ends. Final tiles only: a "
             "progressive job's preview tiles come as tile events with preview: true",
         .path_parameters = {kJobId},
         .responses = {{"200", binary_response("the tile stream", "multipart/mixed")},
                       {"404", problem("unknown job")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/jobs/{id}/tiles/{tx}/{ty}.exr",
         .operation_id = "jobTile",
         .summary =
             "One finished tile as a small EXR (data window = the tile, display window = the "
             "frame); tiles count from the rendered area's top-left corner. With preview=true a "
             "tile not finished yet gives its progressive preview; X-Tile-Kind says which "
             "(preview or final)",
         .path_parameters = {kJobId, kTileColumn, kTileRow},
         .query_and_header_parameters = json::array({kPreviewParameter}),
         .responses = {
             {"200", binary_response("the tile", "image/x-exr")},
             {"404", problem("unknown job, tile outside the grid, or not finished yet (nor its preview)")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/jobs/{id}/tiles/{tx}/{ty}.png",
         .operation_id = "jobTilePng",
         .summary =
             "One finished tile as an 8-bit sRGB PNG made as preview.png is (exposure, filmic tone "
             "curve, sRGB; server/tile_png.h). Exposure: exposure_ev if given, else the job's "
             "output.exposure_ev, else the preview's automatic exposure at this moment; "
             "X-Exposure-EV says which was used, X-Tile-Rect where the tile lies (x0,y0,x1,y1). "
             "With preview=true a tile not finished yet gives its progressive preview; "
             "X-Tile-Kind says which (preview or final)",
         .path_parameters = {kJobId, kTileColumn, kTileRow},
         .query_and_header_parameters = json::array(
             {query_parameter("exposure_ev", "exposure in stops, e.g. the X-Exposure-EV of an earlier tile",
                              {{"type", "number"}, {"minimum", -64}, {"maximum", 64}}),
              kPreviewParameter}),
         .responses = {
             {"200", binary_response("the tile", "image/png")},
             {"400", problem("exposure_ev is not a number of stops in [-64, 64]")},
             {"404", problem("unknown job, tile outside the grid, or not finished yet (nor its preview)")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/jobs/{id}/image.exr",
         .operation_id = "jobImage",
         .summary = "The assembled image (tiled OpenEXR, as `photond render` writes it)",
         .path_parameters = {kJobId},
         .query_and_header_parameters = json::array(
             {query_parameter("wait", "block until the job ends", {{"type", "boolean"}})}),
         .responses = {{"200", binary_response("the image", "image/x-exr")},
                       {"404", problem("unknown job")},
                       {"409", problem("not done (without wait), failed or cancelled")},
                       {"503", problem("shutting down while waiting")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/jobs/{id}/layers/{layer}.exr",
         .operation_id = "jobLayer",
         .summary = "One AOV layer the job asked for (output.aovs) as an EXR of its own, its values "
                    "in R, G and B (image.exr holds it too, as <layer>.R, .G, .B)",
         .path_parameters = {kJobId, {"layer", "[a-z_]{1,32}", "the layer's name, e.g. albedo"}},
         .responses = {{"200", binary_response("the layer", "image/x-exr")},
                       {"404", problem("unknown job, or a layer the job did not ask for")},
                       {"409", problem("not done, failed or cancelled")}}});
    routes.push_back({.method = "GET",
                      .path = "/v1/jobs/{id}/preview.png",
                      .operation_id = "jobPreview",
                      .summary = "An sRGB PNG preview (while rendering: the tiles finished so far)",
                      .path_parameters = {kJobId},
                      .responses = {{"200", binary_response("the preview", "image/png")},
                                    {"404", problem("unknown job")},
                                    {"409", problem("queued, failed or cancelled: no pixels")}}});
    // Scenes.
    json scene_body = binary_body(
        {"model/gltf-binary", "application/zip", "application/x-tar", "application/gzip"});
    scene_body["content"]["model/gltf+json"] = {{"schema", {{"type", "object"}}}};
    routes.push_back(
        {.method = "POST",
         .path = "/v1/scenes",
         .operation_id = "uploadScene",
         .summary =
             "Upload a .glb, a self-contained .gltf, or a bundle: a zip, tar or tar.gz of a .gltf "
             "with its sibling files (buffers, textures, environment images), told apart by magic "
             "bytes. A bundle holds exactly one .gltf or .glb at its top level (or in its single "
             "top-level folder); only files and directories with relative paths inside the bundle "
             "(no '..', no links, no devices). The scene is validated by loading it; its id is the "
             "SHA-256 of the uploaded bytes",
         .request_body = std::move(scene_body),
         .responses = {
             {"201", json_response("stored; Location: /v1/scenes/{id}", "SceneInfo")},
             {"200", json_response("these bytes were already stored", "SceneInfo")},
             {"413", problem("request body too large, or a bundle beyond --max-bundle-mb unpacked "
                             "or --max-bundle-entries")},
             {"422", problem("not a loadable glTF scene, or a bundle entry against the rules: the "
                             "message names the entry")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/scenes",
         .operation_id = "listScenes",
         .summary = "The uploaded scenes",
         .responses = {{"200", list_response("the scenes", "scenes", ref("SceneInfo"))}}});
    routes.push_back({.method = "GET",
                      .path = "/v1/scenes/{id}",
                      .operation_id = "getScene",
                      .summary = "An uploaded scene's size, triangles, lights and cameras",
                      .path_parameters = {kSceneId},
                      .responses = {{"200", json_response("the metadata", "SceneInfo")},
                                    {"404", problem("unknown scene")}}});
    routes.push_back(
        {.method = "DELETE",
         .path = "/v1/scenes/{id}",
         .operation_id = "deleteScene",
         .summary = "Remove an uploaded scene",
         .path_parameters = {kSceneId},
         .responses = {{"204", response("removed")}, {"404", problem("unknown scene")}}});
    // Artifacts.
    add_artifact_routes(routes, "/v1/photon-maps", "photon-map", "photon maps", "PhotonMaps",
                        "PhotonMaps", "pm1-<64 hex digits> (photons.key in a job's status)");
    add_artifact_routes(routes, "/v1/render-caches", "render-cache", "irradiance caches",
                        "RenderCache", "RenderCaches",
                        "rc1-<64 hex digits> (statistics.irradiance_cache.key in a job's status)");
    // Operations.
    routes.push_back(
        {.method = "GET",
         .path = "/healthz",
         .operation_id = "healthz",
         .summary = "Liveness",
         .authenticated = false,
         .responses = {{"200", response("ok", content("text/plain", {{"type", "string"}}))}}});
    routes.push_back(
        {.method = "GET",
         .path = "/readyz",
         .operation_id = "readyz",
         .summary = "Readiness: the worker runs, the cache directory is writable and its disk has "
                    "--min-free-mb free",
         .authenticated = false,
         .responses = {{"200", response("ready")}, {"503", problem("not ready")}}});
    routes.push_back(
        {.method = "GET",
         .path = "/metrics",
         .operation_id = "metrics",
         .summary = "Prometheus text exposition",
         .responses = {{"200", response("metrics", content("text/plain", {{"type", "string"}}))}}});
    routes.push_back(
        {.method = "GET",
         .path = "/v1/openapi.json",
         .operation_id = "openapi",
         .summary = "This document",
         .responses = {
             {"200", response("OpenAPI 3.1", content("application/json", {{"type", "object"}}))}}});
    // The web page (server/web_handlers.h): public files without data; the data it shows comes
    // through the routes above, with the token.
    const json text = {{"schema", {{"type", "string"}}}};
    routes.push_back({.method = "GET",
                      .path = "/",
                      .operation_id = "webPage",
                      .summary = "The web page: jobs, submission, a job's image assembling live "
                                 "(asks for the token when the daemon has one)",
                      .authenticated = false,
                      .responses = {{"200", response("the page", {{"text/html", text}})}}});
    routes.push_back({.method = "GET",
                      .path = "/web/{file}",
                      .operation_id = "webAsset",
                      .summary = "The web page's scripts (ES modules) and style sheet",
                      .authenticated = false,
                      .path_parameters = {{"file", "[A-Za-z0-9_.-]{1,64}", "e.g. app.js, app.css"}},
                      .responses = {{"200", response("the file", {{"text/javascript", text}, {"text/css", text}})},
                                    {"404", problem("no such file")}}});
    return routes;
}

}  // namespace

std::string Route::path_regex() const {
    std::string regex;
    for (size_t i = 0; i < path.size(); ++i) {
        const char c = path[i];
        if (c == '{') {
            const size_t end = path.find('}', i);
            const std::string_view name = std::string_view(path).substr(i + 1, end - i - 1);
            const PathParameter* parameter = nullptr;
            for (const PathParameter& p : path_parameters)
                if (p.name == name) parameter = &p;
            if (end == std::string::npos || !parameter)
                throw std::logic_error("route " + path + ": no pattern for its parameter " +
                                       std::string(name));
            regex += "(" + parameter->pattern + ")";
            i = end;
        } else {
            if (std::string_view(".^$|()[]*+?\\").find(c) != std::string_view::npos) regex += '\\';
            regex += c;
        }
    }
    return regex;
}

const std::vector<Route>& api_routes() {
    static const std::vector<Route> routes = build_routes();
    return routes;
}

}  // namespace photond::service
