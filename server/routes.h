// The routes of the HTTP API v1 in one table. The server registers a handler for each
// (http_server.cpp, found by operation id), the OpenAPI document builds its `paths` from it
// (openapi.cpp) and the daemon tests walk it, so a route cannot be served without being
// documented, nor documented without being served.
//
// The table is built once and never changed: safe to read from any thread.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace photond::service {

/// A `{name}` segment of a route's path and the values it matches.
struct PathParameter {
    std::string name;
    std::string pattern;  // ECMAScript regex without groups, e.g. "[0-9]{1,9}"
    std::string description;
};

struct Route {
    std::string method;        // "GET", "POST", "PUT" or "DELETE"
    std::string path;          // as OpenAPI writes it: "/v1/jobs/{id}/tiles/{tx}/{ty}.exr"
    std::string operation_id;  // OpenAPI operationId, also the key of the server's handler
    std::string summary;
    bool authenticated = true;  // false: answered without the bearer token (health checks)
    std::vector<PathParameter> path_parameters;                            // in the order of `path`
    nlohmann::json query_and_header_parameters = nlohmann::json::array();  // OpenAPI objects
    nlohmann::json request_body;  // OpenAPI requestBody object; null: the route takes no body
    nlohmann::json responses;     // OpenAPI responses by status, without the errors every route has

    /// The regex cpp-httplib matches request paths with: `path` with each parameter as a
    /// capture group of its pattern, and the rest literal.
    std::string path_regex() const;
};

/// Every route of the daemon, in the order a reader meets them: jobs, batches, scenes, photon
/// maps, render caches, operations, the web page.
const std::vector<Route>& api_routes();

}  // namespace photond::service
