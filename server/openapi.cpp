#include "server/openapi.h"

#include <cctype>
#include <string>
#include <utility>
#include <vector>

#include "protocol/job.h"
#include "protocol/job_status.h"
#include "server/routes.h"

namespace photond::service {
namespace {

using nlohmann::json;

json problem(const std::string& description) {
    return {
        {"description", description},
        {"content",
         {{"application/problem+json", {{"schema", {{"$ref", "#/components/schemas/Problem"}}}}}}}};
}

/// Every operation answers these when they apply.
json with_common_errors(json responses, bool authenticated) {
    if (authenticated)
        responses["401"] = problem("missing or invalid bearer token (WWW-Authenticate: Bearer)");
    responses["405"] = problem("method not allowed on this path (Allow lists the methods)");
    responses["500"] = problem("internal error");
    return responses;
}

json operation(const Route& route) {
    json parameters = json::array();
    for (const PathParameter& p : route.path_parameters)
        parameters.push_back(
            {{"name", p.name},
             {"in", "path"},
             {"required", true},
             {"description", p.description},
             {"schema", {{"type", "string"}, {"pattern", "^" + p.pattern + "$"}}}});
    for (const json& p : route.query_and_header_parameters) parameters.push_back(p);
    json op = {{"operationId", route.operation_id},
               {"summary", route.summary},
               {"responses", with_common_errors(route.responses, route.authenticated)}};
    if (!parameters.empty()) op["parameters"] = std::move(parameters);
    if (!route.request_body.is_null()) op["requestBody"] = route.request_body;
    if (!route.authenticated) op["security"] = json::array();
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
    json paths = json::object();
    for (const Route& route : api_routes()) {
        std::string method = route.method;
        for (char& c : method) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        paths[route.path][method] = operation(route);
    }
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
            // Relative: the daemon that serves this document serves the API.
            {"servers", json::array({{{"url", "/"}, {"description", "this daemon"}}})},
            {"paths", std::move(paths)},
            {"components",
             {{"schemas", std::move(schemas)},
              {"securitySchemes", {{"bearer", {{"type", "http"}, {"scheme", "bearer"}}}}}}},
            {"security", json::array({{{"bearer", json::array()}}})}};
}

}  // namespace photond::service
