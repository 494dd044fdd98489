#include "server/openapi.h"

#include <string>
#include <utility>
#include <vector>

#include "protocol/job.h"
#include "protocol/job_status.h"
#include "server/scene_store.h"

namespace photond::service {
namespace {

using nlohmann::json;

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

json problem(const std::string& description) {
    return response(description, content("application/problem+json", ref("Problem")));
}

json path_parameter(const std::string& name, const std::string& description) {
    return {{"name", name},
            {"in", "path"},
            {"required", true},
            {"description", description},
            {"schema", {{"type", "string"}}}};
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

/// Every operation answers these when they apply.
json with_common_errors(json responses, bool authenticated = true) {
    if (authenticated)
        responses["401"] = problem("missing or invalid bearer token (WWW-Authenticate: Bearer)");
    responses["405"] = problem("method not allowed on this path (Allow lists the methods)");
    responses["500"] = problem("internal error");
    return responses;
}

json operation(const std::string& id, const std::string& summary, json responses,
               json parameters = json::array(), bool authenticated = true) {
    json op = {{"operationId", id},
               {"summary", summary},
               {"responses", with_common_errors(std::move(responses), authenticated)}};
    if (!parameters.empty()) op["parameters"] = std::move(parameters);
    if (!authenticated) op["security"] = json::array();
    return op;
}

json scene_info_schema() {
    json count = {{"type", "integer"}, {"minimum", 0}};
    return {{"type", "object"},
            {"required", {"id", "format", "bytes", "triangles", "lights", "cameras"}},
            {"properties",
             {{"id", {{"type", "string"}, {"pattern", "^sha256:[0-9a-f]{64}$"}}},
              {"format", {{"type", "string"}, {"enum", {"glb", "gltf"}}}},
              {"bytes", count},
              {"name", {{"type", "string"}}},
              {"triangles", count},
              {"vertices", count},
              {"materials", count},
              {"textures", count},
              {"lights", count},
              {"emissive_triangles", count},
              {"cameras", count},
              {"bundle",
               {{"type", "string"},
                {"enum", {"zip", "tar", "tar.gz", "unknown"}},
                {"description", "bundles only: the archive's format"}}},
              {"entry",
               {{"type", "string"},
                {"description", "bundles only: the glTF file's path inside the bundle"}}},
              {"files", count},
              {"warnings",
               {{"type", "array"},
                {"items", {{"type", "string"}}},
                {"description", "glTF features of the file that the renderer ignores"}}},
              {"bounds", {{"type", "object"}}}}}};
}

}  // namespace

json openapi_document() {
    const json job_id = path_parameter("id", "the job's id");
    json paths;
    paths["/v1/jobs"] = {
        {"post",
         operation(
             "submitJob", "Queue a render job",
             {{"202", json_response("queued; Location: /v1/jobs/{id}", "JobStatus")},
              {"200",
               json_response("an earlier job with the same Idempotency-Key and body", "JobStatus")},
              {"400", problem("malformed JSON")},
              {"409", problem("the Idempotency-Key was used with another job description")},
              {"413", problem("request body too large (--max-body-mb)")},
              {"422", problem("invalid job: `field` names the offending field")},
              {"429", problem("the queue is full (--max-queued); Retry-After says when to retry")},
              {"503", problem("shutting down")}},
             json::array({header_parameter(
                 "Idempotency-Key", "a retry with the same key and body returns the same job")}))},
        {"get",
         operation(
             "listJobs", "Jobs, newest first",
             {{"200",
               response("the jobs",
                        content("application/json",
                                {{"type", "object"},
                                 {"properties",
                                  {{"jobs", {{"type", "array"}, {"items", ref("JobStatus")}}}}}}))},
              {"400", problem("bad query")}},
             json::array({query_parameter("state", "only jobs in this state",
                                          {{"type", "string"}, {"enum", protocol::kJobStateNames}}),
                          query_parameter("limit", "at most this many",
                                          {{"type", "integer"}, {"minimum", 1}})}))}};
    paths["/v1/jobs/{id}"] = {
        {"get",
         operation(
             "getJob", "A job's state, progress, plan, timings, photon-map cache and error",
             {{"200", json_response("the status", "JobStatus")}, {"404", problem("unknown job")}},
             json::array({job_id}))},
        {"delete",
         operation("cancelJob", "Cancel a queued or running job (stops within about one tile)",
                   {{"200", json_response("cancelled", "JobStatus")},
                    {"202",
                     json_response("asked to stop; still finishing its current tile", "JobStatus")},
                    {"404", problem("unknown job")},
                    {"409", problem("the job is already done or failed")}},
                   json::array({job_id}))}};
    paths["/v1/jobs/{id}/events"] = {
        {"get",
         operation(
             "jobEvents",
             "Server-Sent Events: state, progress, tile, done, failed, cancelled; the history "
             "first, then live; ends after done, failed or cancelled",
             {{"200", response("text/event-stream of JobEvent data",
                               content("text/event-stream", ref("JobEvent")))},
              {"400", problem("Last-Event-ID is not an event id")},
              {"404", problem("unknown job")}},
             json::array(
                 {job_id, header_parameter("Last-Event-ID", "resume after this event id"),
                  query_parameter("last_event_id", "as the header, for clients that cannot set it",
                                  {{"type", "integer"}, {"minimum", 0}})}))}};
    paths["/v1/jobs/{id}/tiles"] = {
        {"get",
         operation(
             "jobTileStream",
             "multipart/mixed stream of tile EXRs as they finish (finished ones first); each part "
             "has Content-Type image/x-exr, Content-Length, X-Tile-X, X-Tile-Y and X-Tile-Rect "
             "(x0,y0,x1,y1); the closing boundary ends it when the job ends",
             {{"200", binary_response("the tile stream", "multipart/mixed")},
              {"404", problem("unknown job")}},
             json::array({job_id}))}};
    paths["/v1/jobs/{id}/tiles/{tx}/{ty}.exr"] = {
        {"get",
         operation("jobTile",
                   "One finished tile as a small EXR (data window = the tile, display window = the "
                   "frame); tiles count from the rendered area's top-left corner",
                   {{"200", binary_response("the tile", "image/x-exr")},
                    {"404", problem("unknown job, tile outside the grid, or not finished yet")}},
                   json::array({job_id, path_parameter("tx", "tile column"),
                                path_parameter("ty", "tile row")}))}};
    paths["/v1/jobs/{id}/image.exr"] = {
        {"get",
         operation("jobImage", "The assembled image (tiled OpenEXR, as `photond render` writes it)",
                   {{"200", binary_response("the image", "image/x-exr")},
                    {"404", problem("unknown job")},
                    {"409", problem("not done (without wait), failed or cancelled")},
                    {"503", problem("shutting down while waiting")}},
                   json::array({job_id, query_parameter("wait", "block until the job ends",
                                                        {{"type", "boolean"}})}))}};
    paths["/v1/jobs/{id}/preview.png"] = {
        {"get",
         operation("jobPreview", "An sRGB PNG preview (while rendering: the tiles finished so far)",
                   {{"200", binary_response("the preview", "image/png")},
                    {"404", problem("unknown job")},
                    {"409", problem("queued, failed or cancelled: no pixels")}},
                   json::array({job_id}))}};
    paths["/v1/scenes"] = {
        {"post",
         operation("uploadScene",
                   "Upload a .glb, a self-contained .gltf, or a bundle: a zip, tar or tar.gz "
                   "of a .gltf with its sibling files (buffers, textures, environment images), "
                   "told apart by magic bytes. A bundle holds exactly one .gltf or .glb at its "
                   "top level (or in its single top-level folder); only files and directories "
                   "with relative paths inside the bundle (no '..', no links, no devices). The "
                   "scene is validated by loading it; its id is the SHA-256 of the uploaded "
                   "bytes",
                   {{"201", json_response("stored; Location: /v1/scenes/{id}", "SceneInfo")},
                    {"200", json_response("these bytes were already stored", "SceneInfo")},
                    {"413", problem("request body too large, or a bundle beyond "
                                    "--max-bundle-mb unpacked or --max-bundle-entries")},
                    {"422", problem("not a loadable glTF scene, or a bundle entry against the "
                                    "rules: the message names the entry")}})},
        {"get", operation("listScenes", "The uploaded scenes",
                          {{"200", response("the scenes",
                                            content("application/json",
                                                    {{"type", "object"},
                                                     {"properties",
                                                      {{"scenes",
                                                        {{"type", "array"},
                                                         {"items", ref("SceneInfo")}}}}}}))}})}};
    paths["/v1/scenes"]["post"]["requestBody"] = {
        {"required", true},
        {"content",
         {{"model/gltf-binary",
           {{"schema", {{"type", "string"}, {"contentMediaType", "model/gltf-binary"}}}}},
          {"model/gltf+json", {{"schema", {{"type", "object"}}}}},
          {"application/zip",
           {{"schema", {{"type", "string"}, {"contentMediaType", "application/zip"}}}}},
          {"application/x-tar",
           {{"schema", {{"type", "string"}, {"contentMediaType", "application/x-tar"}}}}},
          {"application/gzip",
           {{"schema", {{"type", "string"}, {"contentMediaType", "application/gzip"}}}}}}}};
    const json scene_id = path_parameter("id", "sha256:<64 hex digits>");
    paths["/v1/scenes/{id}"] = {
        {"get", operation("getScene", "An uploaded scene's size, triangles, lights and cameras",
                          {{"200", json_response("the metadata", "SceneInfo")},
                           {"404", problem("unknown scene")}},
                          json::array({scene_id}))},
        {"delete", operation("deleteScene", "Remove an uploaded scene",
                             {{"204", response("removed")}, {"404", problem("unknown scene")}},
                             json::array({scene_id}))}};
    // The routes of a cache of artifacts: list, export, import.
    const auto artifact_paths = [&](const std::string& base, const std::string& name, const std::string& plural,
                                    const std::string& operation_suffix, const std::string& list_suffix,
                                    const std::string& key_form) {
        paths[base] = {
            {"get",
             operation(
                 "list" + list_suffix, "Keys of the " + plural + " cached here",
                 {{"200", response("the keys", content("application/json",
                                                       {{"type", "object"},
                                                        {"properties",
                                                         {{"keys",
                                                           {{"type", "array"},
                                                            {"items", {{"type", "string"}}}}}}}}))}})}};
        const json key = path_parameter("key", key_form);
        paths[base + "/{key}"] = {
            {"get", operation("export" + operation_suffix, "Export " + plural + " (the photond " + name + " file format)",
                              {{"200", binary_response("the file", "application/octet-stream")},
                               {"404", problem("unknown key")}},
                              json::array({key}))},
            {"put", operation("import" + operation_suffix,
                              "Import " + plural + " exported by another node (checked against the key)",
                              {{"201", response("imported")},
                               {"200", response("already cached; the bytes were checked")},
                               {"404", problem("not a " + name + " key")},
                               {"409", problem("a different valid " + name + " is kept under the key")},
                               {"413", problem("request body too large")},
                               {"422", problem("corrupt, truncated, or for another key")}},
                              json::array({key}))}};
        paths[base + "/{key}"]["put"]["requestBody"] = {
            {"required", true},
            {"content",
             {{"application/octet-stream",
               {{"schema", {{"type", "string"}, {"contentMediaType", "application/octet-stream"}}}}}}}};
    };
    artifact_paths("/v1/photon-maps", "photon-map", "photon maps", "PhotonMaps", "PhotonMaps",
                   "pm1-<64 hex digits> (photons.key in a job's status)");
    artifact_paths("/v1/render-caches", "render-cache", "irradiance caches", "RenderCache", "RenderCaches",
                   "rc1-<64 hex digits> (statistics.irradiance_cache.key in a job's status)");
    paths["/v1/jobs"]["post"]["requestBody"] = {
        {"required", true}, {"content", {{"application/json", {{"schema", ref("Job")}}}}}};
    paths["/v1/batches"] = {
        {"post",
         operation("submitBatch",
                   "Queue views of one scene as a job each, in order: photon maps traced once, each view's "
                   "irradiance cache starting from the one before",
                   {{"202", response("queued", content("application/json",
                                                       {{"type", "object"},
                                                        {"properties",
                                                         {{"jobs", {{"type", "array"}, {"items", ref("JobStatus")}}}}}}))},
                    {"400", problem("malformed JSON")},
                    {"413", problem("request body too large (--max-body-mb)")},
                    {"422", problem("invalid batch: `field` names job.<field> or cameras[k].<field>")},
                    {"429", problem("the queue cannot take the whole batch (--max-queued)")},
                    {"503", problem("shutting down")}})}};
    paths["/v1/batches"]["post"]["requestBody"] = {
        {"required", true},
        {"content",
         {{"application/json",
           {{"schema",
             {{"type", "object"},
              {"required", json::array({"job", "cameras"})},
              {"additionalProperties", false},
              {"properties",
               {{"job", {{"description", "the job every view shares (without camera)"}, {"$ref", "#/components/schemas/Job"}}},
                {"cameras",
                 {{"type", "array"}, {"minItems", 1}, {"maxItems", 1000},
                  {"description", "one camera per view (the Job's camera field)"}}}}}}}}}}}};
    paths["/healthz"] = {
        {"get", operation("healthz", "Liveness",
                          {{"200", response("ok", content("text/plain", {{"type", "string"}}))}},
                          json::array(), false)}};
    paths["/readyz"] = {
        {"get",
         operation("readyz",
                   "Readiness: the worker runs, the cache directory is writable and its disk has --min-free-mb free",
                   {{"200", response("ready")}, {"503", problem("not ready")}}, json::array(),
                   false)}};
    paths["/metrics"] = {
        {"get",
         operation("metrics", "Prometheus text exposition",
                   {{"200", response("metrics", content("text/plain", {{"type", "string"}}))}})}};
    paths["/v1/openapi.json"] = {
        {"get", operation("openapi", "This document",
                          {{"200", response("OpenAPI 3.1",
                                            content("application/json", {{"type", "object"}}))}})}};

    json schemas = {{"Job", protocol::job_json_schema()},
                    {"JobStatus", protocol::job_status_json_schema()},
                    {"JobEvent", protocol::job_event_json_schema()},
                    {"Problem", protocol::problem_json_schema()},
                    {"SceneInfo", scene_info_schema()}};
    return {{"openapi", "3.1.0"},
            {"jsonSchemaDialect", "https://json-schema.org/draft/2020-12/schema"},
            {"info",
             {{"title", "photond"},
              {"version", "1"},
              {"description",
               "Render service for global illumination with photon maps and an irradiance cache. "
               "Errors are RFC 9457 application/problem+json."}}},
            {"paths", std::move(paths)},
            {"components",
             {{"schemas", std::move(schemas)},
              {"securitySchemes", {{"bearer", {{"type", "http"}, {"scheme", "bearer"}}}}}}},
            {"security", json::array({{{"bearer", json::array()}}})}};
}

}  // namespace photond::service
