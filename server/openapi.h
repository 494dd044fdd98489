// The OpenAPI 3.1 document of the HTTP API v1, served at GET /v1/openapi.json. Its paths are the
// route table the server registers from (server/routes.h) and its schemas are the protocol's own:
// components.schemas.Job IS protocol::job_json_schema(), and the status, event and problem
// schemas come from protocol/job_status.h, so the document cannot drift from what the daemon
// serves, validates and answers.
#pragma once

#include <nlohmann/json.hpp>

namespace photond::service {

nlohmann::json openapi_document();

}  // namespace photond::service
