#include "server/web_handlers.h"

#include <httplib.h>

#include <cstdio>
#include <optional>

#include "server/http_server.h"
#include "server/job_layer_exr.h"
#include "server/parse_number.h"
#include "server/service_error.h"
#include "server/tile_png.h"
#include "server/web_assets.h"

namespace photond::service {
namespace {

using httplib::Request;
using httplib::Response;

/// The page's files are public (they hold no data: every job, scene and image comes through the
/// API with the token), and locked down: scripts and styles only from the daemon, no inline
/// script, requests only to the daemon, never framed, no Referer leaving it. The page keeps the
/// token in sessionStorage, so these rules are what keeps script of anyone else from reading it.
void send_asset(const WebAsset& asset, Response& res) {
    res.set_header("Content-Security-Policy",
                   "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' blob: "
                   "data:; connect-src 'self'; base-uri 'none'; form-action 'none'; "
                   "frame-ancestors 'none'");
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_header("Referrer-Policy", "no-referrer");
    res.set_header("Cache-Control", "no-cache");
    res.set_content(asset.bytes.data(), asset.bytes.size(), std::string(asset.content_type).c_str());
}

const WebAsset* find_asset(std::string_view name) {
    for (const WebAsset& asset : web_assets())
        if (asset.name == name) return &asset;
    return nullptr;
}

void web_page(const HttpServices&, const Request&, Response& res) {
    const WebAsset* page = find_asset("index.html");
    if (!page) throw ServiceError(ErrorKind::Internal, "the web page was not compiled in");
    send_asset(*page, res);
}

void web_asset(const HttpServices&, const Request& req, Response& res) {
    const std::string name = req.matches[1];
    const WebAsset* asset = find_asset(name);
    // index.html is served as / only: one address for the page.
    if (!asset || name == "index.html")
        throw ServiceError(ErrorKind::NotFound, "the web page has no file '" + name + "'");
    send_asset(*asset, res);
}

void job_tile_png(const HttpServices& services, const Request& req, Response& res) {
    const protocol::TileIndex tile{parse_number<int>(req.matches[2].str()).value_or(-1),
                                   parse_number<int>(req.matches[3].str()).value_or(-1)};
    std::optional<float> exposure_ev;
    if (req.has_param("exposure_ev")) {
        const std::string text = req.get_param_value("exposure_ev");
        exposure_ev = parse_number<float>(text);
        if (!exposure_ev)
            throw ServiceError(ErrorKind::MalformedRequest,
                               "exposure_ev: expected a number of stops, got '" + text + "'");
    }
    const bool or_preview = req.has_param("preview") && is_true(req.get_param_value("preview"));
    TilePng png = make_tile_png(services.jobs, req.matches[1], tile, exposure_ev, or_preview);
    char exposure[32];
    std::snprintf(exposure, sizeof exposure, "%.9g", png.exposure_ev);  // reads back as the same float
    const PixelRect& r = png.rect;
    res.set_header("X-Exposure-EV", exposure);
    res.set_header("X-Tile-Rect", std::to_string(r.x0) + "," + std::to_string(r.y0) + "," +
                                      std::to_string(r.x1) + "," + std::to_string(r.y1));
    res.set_header("X-Tile-Kind", png.preview ? "preview" : "final");
    res.set_header("Cache-Control", "no-cache");
    res.set_content(reinterpret_cast<const char*>(png.bytes.data()), png.bytes.size(), "image/png");
}

void job_layer(const HttpServices& services, const Request& req, Response& res) {
    const std::string id = req.matches[1];
    const std::string layer = req.matches[2];
    const std::vector<uint8_t> bytes = make_layer_exr(services.jobs, id, layer);
    res.set_header("Content-Disposition", "attachment; filename=\"" + id + "." + layer + ".exr\"");
    res.set_content(reinterpret_cast<const char*>(bytes.data()), bytes.size(), "image/x-exr");
}

}  // namespace

const std::map<std::string, ServiceHandler>& web_handlers() {
    static const std::map<std::string, ServiceHandler> handlers = {{"webPage", web_page},
                                                                   {"webAsset", web_asset},
                                                                   {"jobTilePng", job_tile_png},
                                                                   {"jobLayer", job_layer}};
    return handlers;
}

}  // namespace photond::service
