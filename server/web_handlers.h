// The handlers of the web page's routes (server/routes.cpp): the page itself (`GET /`), its
// script and style sheet (`GET /web/{file}`, server/web_assets.h) and the tiles it draws as PNGs
// (`GET /v1/jobs/{id}/tiles/{tx}/{ty}.png`, server/tile_png.h), and a job's AOV layers as EXRs of
// their own for its downloads (`GET /v1/jobs/{id}/layers/{layer}.exr`, server/job_layer_exr.h).
// server/http_server.cpp registers them by operation id beside its own handlers, with the same
// token check and error handling.
//
// httplib.h stays out of this header (server/httplib_forward.h).
#pragma once

#include <functional>
#include <map>
#include <string>

#include "server/httplib_forward.h"

namespace photond::service {

struct HttpServices;

using ServiceHandler =
    std::function<void(const HttpServices&, const httplib::Request&, httplib::Response&)>;

/// The web page's handlers by operation id: webPage, webAsset, jobTilePng, jobLayer.
const std::map<std::string, ServiceHandler>& web_handlers();

}  // namespace photond::service
