#include "server/http_server.h"

#include <httplib.h>
#include <sys/socket.h>

#include <algorithm>
#include <cstdlib>
#include <charconv>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <stdexcept>
#include <vector>

#include "core/util/json_depth.h"
#include "protocol/job.h"
#include "protocol/job_status.h"
#include "protocol/json_text.h"
#include "server/http_problems.h"
#include "server/parse_number.h"
#include "server/http_thread_pool.h"
#include "server/job_manager.h"
#include "server/metrics.h"
#include "server/openapi.h"
#include "server/photon_map_cache.h"
#include "server/render_cache_directory.h"
#include "server/routes.h"
#include "server/scene_store.h"
#include "server/service_error.h"
#include "server/web_handlers.h"

namespace photond::service {
namespace {

using httplib::Request;
using httplib::Response;
using nlohmann::json;
using Handler = std::function<void(const Request&, Response&)>;

constexpr const char* kJsonType = "application/json";
constexpr const char* kExrType = "image/x-exr";
/// The most views one batch may carry.
constexpr size_t kMaxBatchViews = 1000;
// HTTP threads kept waiting for the next burst of connections; the others end after the timeout.
constexpr size_t kKeptHttpThreads = 8;
constexpr std::chrono::milliseconds kHttpThreadIdleTimeout{10000};

// ---------------------------------------------------------------------------------------------
// Small decoding and encoding helpers

void send_json(Response& res, const json& document, int status = 200) {
    res.status = status;
    res.set_content(protocol::json_text(document, 2) + "\n", kJsonType);
}

void send_bytes(Response& res, std::vector<uint8_t> bytes, const char* type) {
    res.set_content(reinterpret_cast<const char*>(bytes.data()), bytes.size(), type);
}

/// Constant-time comparison, so that the token cannot be guessed byte by byte from timings.
bool same_secret(std::string_view given, std::string_view expected) {
    if (expected.empty()) return false;
    unsigned char difference = given.size() == expected.size() ? 0 : 1;
    for (size_t i = 0; i < given.size(); ++i)
        difference |= static_cast<unsigned char>(given[i] ^ expected[i % expected.size()]);
    return difference == 0;
}

/// A JSON request body; refused when empty (`expected` says what to send), nested deeper than
/// kMaxJsonNesting or malformed (with the line and column).
json decode_json_body(const std::string& body, const std::string& expected) {
    if (body.empty()) throw ServiceError(ErrorKind::MalformedRequest, "the request has no body: send " + expected);
    if (json_nesting_depth(body) > kMaxJsonNesting)
        throw ServiceError(ErrorKind::MalformedRequest, json_nesting_message());
    json document = json::parse(body, nullptr, false);
    if (document.is_discarded()) {
        // Parsed again for the message with line and column.
        const auto parsed = protocol::parse_job_text_detailed(body);
        const auto* error = std::get_if<protocol::FieldError>(&parsed);
        throw ServiceError(ErrorKind::MalformedRequest, error ? error->message : std::string("malformed JSON"));
    }
    return document;
}

protocol::Job decode_job(const std::string& body) {
    const json document = decode_json_body(body, "the job description as JSON");
    auto parsed = protocol::parse_job_detailed(document);
    if (auto* error = std::get_if<protocol::FieldError>(&parsed))
        throw ServiceError(ErrorKind::InvalidField, protocol::describe(*error), error->path);
    return std::get<protocol::Job>(std::move(parsed));
}

std::string random_boundary() {
    static thread_local std::mt19937_64 random{std::random_device{}()};
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "photond-tiles-%016llx",
                  static_cast<unsigned long long>(random()));
    return buffer;
}

std::string rect_header(const PixelRect& r) {
    return std::to_string(r.x0) + "," + std::to_string(r.y0) + "," + std::to_string(r.x1) + "," +
           std::to_string(r.y1);
}

/// cpp-httplib's server with two of its protected members put to use: a longer queue of
/// connections waiting to be accepted (it listens with a backlog of 5, so a burst of clients had
/// their SYNs dropped and waited a second for each retry), and process_request for
/// handle_raw_request.
class ListeningServer : public httplib::Server {
public:
    /// Call after binding; listen() on a listening socket sets its backlog anew.
    void widen_backlog() {
        if (svr_sock_ != INVALID_SOCKET) ::listen(svr_sock_, SOMAXCONN);
    }
    using httplib::Server::process_request;
};

}  // namespace

// ---------------------------------------------------------------------------------------------

struct HttpServer::Impl {
    HttpServerOptions options;
    HttpServices services;
    ListeningServer server;

    struct BoundRoute {
        std::string method;
        std::string pattern;
        Handler handler;
        bool open = false;  // served without the bearer token (health checks)
    };
    std::vector<BoundRoute> routes;
    std::vector<std::pair<std::regex, std::set<std::string>>> known_paths;  // for 405 answers

    Impl(HttpServerOptions o, HttpServices s) : options(std::move(o)), services(s) {}

    void log(const std::string& line) const {
        if (options.log) options.log(line);
    }

    void route(std::string method, std::string pattern, Handler handler, bool open = false) {
        routes.push_back({std::move(method), std::move(pattern), std::move(handler), open});
    }

    void check_token(const Request& req) const {
        if (options.token.empty()) return;
        const std::string header = req.get_header_value("Authorization");
        constexpr std::string_view kScheme = "Bearer ";
        if (header.empty())
            throw ServiceError(
                ErrorKind::Unauthorized,
                "this daemon needs a bearer token: send 'Authorization: Bearer <token>'")
                .with_header("WWW-Authenticate", "Bearer realm=\"photond\"");
        if (header.size() <= kScheme.size() ||
            !std::equal(kScheme.begin(), kScheme.end(), header.begin(),
                        [](char a, char b) { return std::tolower(a) == std::tolower(b); }) ||
            !same_secret(std::string_view(header).substr(kScheme.size()), options.token))
            throw ServiceError(ErrorKind::Unauthorized, "the bearer token is not valid")
                .with_header("WWW-Authenticate",
                             "Bearer realm=\"photond\", error=\"invalid_token\"");
    }

    void register_routes();
    /// Routes, error handlers and connection settings handed to cpp-httplib.
    void install();
    httplib::Server::HandlerWithContentReader with_body(Handler handler);
    void add_route(const std::string& method, const std::string& pattern, Handler handler);
    void install_routes();
    void install_error_handlers();
    httplib::Server::HandlerResponse answer_own_error(const Request& req, Response& res) const;
    void configure_connections();

    // Handlers, in the order of the route table (server/routes.cpp).
    void submit_job(const Request& req, Response& res);
    void list_jobs(const Request& req, Response& res);
    void submit_batch(const Request& req, Response& res);
    void get_job(const Request& req, Response& res);
    void cancel_job(const Request& req, Response& res);
    void job_events(const Request& req, Response& res);
    void job_tile_stream(const Request& req, Response& res);
    void job_tile(const Request& req, Response& res);
    void job_image(const Request& req, Response& res);
    void job_preview(const Request& req, Response& res);
    void upload_scene(const Request& req, Response& res);
    void list_scenes(const Request& req, Response& res);
    void get_scene(const Request& req, Response& res);
    void delete_scene(const Request& req, Response& res);
    void list_photon_maps(const Request& req, Response& res);
    void export_photon_maps(const Request& req, Response& res);
    void import_photon_maps(const Request& req, Response& res);
    void list_render_caches(const Request& req, Response& res);
    void export_render_cache(const Request& req, Response& res);
    void import_render_cache(const Request& req, Response& res);
    RenderCacheDirectory& render_caches() const {
        if (!services.render_caches) throw ServiceError(ErrorKind::NotFound, "this daemon keeps no render caches");
        return *services.render_caches;
    }
    void healthz(const Request& req, Response& res);
    void readyz(const Request& req, Response& res);
    void metrics(const Request& req, Response& res);
    void openapi(const Request& req, Response& res);

    /// The 413's detail, naming the limit.
    std::string body_limit_message() const {
        return "the request body exceeds the limit of " + std::to_string(options.max_body_bytes >> 20) +
               " MiB (--max-body-mb)";
    }
};

/// A handler for every route of the table (server/routes.h), found by its operation id; a route
/// without a handler or a handler without a route stops the daemon at its start.
void HttpServer::Impl::register_routes() {
    using Member = void (Impl::*)(const Request&, Response&);
    const std::map<std::string, Member> handlers = {
        {"submitJob", &Impl::submit_job},
        {"listJobs", &Impl::list_jobs},
        {"submitBatch", &Impl::submit_batch},
        {"getJob", &Impl::get_job},
        {"cancelJob", &Impl::cancel_job},
        {"jobEvents", &Impl::job_events},
        {"jobTileStream", &Impl::job_tile_stream},
        {"jobTile", &Impl::job_tile},
        {"jobImage", &Impl::job_image},
        {"jobPreview", &Impl::job_preview},
        {"uploadScene", &Impl::upload_scene},
        {"listScenes", &Impl::list_scenes},
        {"getScene", &Impl::get_scene},
        {"deleteScene", &Impl::delete_scene},
        {"listPhotonMaps", &Impl::list_photon_maps},
        {"exportPhotonMaps", &Impl::export_photon_maps},
        {"importPhotonMaps", &Impl::import_photon_maps},
        {"listRenderCaches", &Impl::list_render_caches},
        {"exportRenderCache", &Impl::export_render_cache},
        {"importRenderCache", &Impl::import_render_cache},
        {"healthz", &Impl::healthz},
        {"readyz", &Impl::readyz},
        {"metrics", &Impl::metrics},
        {"openapi", &Impl::openapi},
    };
    std::set<std::string> unused;
    for (const auto& [id, member] : handlers) unused.insert(id);
    for (const auto& [id, handler] : web_handlers()) unused.insert(id);
    for (const Route& r : api_routes()) {
        // The web page's handlers (server/web_handlers.h) are kept in their own file.
        if (const auto web = web_handlers().find(r.operation_id); web != web_handlers().end() && unused.erase(r.operation_id)) {
            route(r.method, r.path_regex(),
                  [this, handler = web->second](const Request& req, Response& res) { handler(services, req, res); },
                  !r.authenticated);
            continue;
        }
        const auto it = handlers.find(r.operation_id);
        if (it == handlers.end() || !unused.erase(r.operation_id))
            throw std::logic_error(r.method + " " + r.path + ": no handler for operation '" +
                                   r.operation_id + "', or a second route for it");
        const Member member = it->second;
        route(r.method, r.path_regex(),
              [this, member](const Request& req, Response& res) { (this->*member)(req, res); },
              !r.authenticated);
    }
    if (!unused.empty()) throw std::logic_error("a handler without a route: " + *unused.begin());
}

void HttpServer::Impl::install() {
    install_routes();
    install_error_handlers();
    configure_connections();
}

/// Bodies are read through a content reader, whatever their Content-Type: cpp-httplib parses an
/// application/x-www-form-urlencoded body (what curl's --data-binary sends by default) as a form
/// and refuses it beyond 8 KiB, which README's uploads of real files hit. The reader still
/// enforces --max-body-mb.
httplib::Server::HandlerWithContentReader HttpServer::Impl::with_body(Handler handler) {
    return [this, handler = std::move(handler)](const Request& req, Response& res,
                                                const httplib::ContentReader& content) {
        Request read = req;
        // Without Content-Length or chunked encoding a request has no body (RFC 9112, 6.3),
        // and a declared length beyond the limit is refused before any of it is read: the
        // content reader waited 30 s (its read timeout) for bodies that never came.
        const std::string declared_length = req.get_header_value("Content-Length");
        const bool chunked = req.get_header_value("Transfer-Encoding").find("chunked") != std::string::npos;
        if (declared_length.empty() && !chunked) {
            handler(read, res);
            return;
        }
        if (!chunked && std::strtoull(declared_length.c_str(), nullptr, 10) > options.max_body_bytes) {
            res.set_header("Connection", "close");  // its body is not read: no next request on it
            throw ServiceError(ErrorKind::PayloadTooLarge, body_limit_message());
        }
        const bool complete = content([&](const char* data, size_t length) {
            read.body.append(data, length);
            return true;
        });
        if (!complete) {
            // A declared length was checked above: a chunked body past the limit, or a cut one.
            if (chunked && read.body.size() >= options.max_body_bytes)
                throw ServiceError(ErrorKind::PayloadTooLarge, body_limit_message());
            throw ServiceError(ErrorKind::MalformedRequest, "the request body could not be read to its end");
        }
        handler(read, res);
    };
}

void HttpServer::Impl::add_route(const std::string& method, const std::string& pattern, Handler handler) {
    if (method == "GET")
        server.Get(pattern, std::move(handler));
    else if (method == "POST")
        server.Post(pattern, with_body(std::move(handler)));
    else if (method == "PUT")
        server.Put(pattern, with_body(std::move(handler)));
    else if (method == "PATCH")
        server.Patch(pattern, with_body(std::move(handler)));
    else if (method == "DELETE")
        server.Delete(pattern, std::move(handler));
}

/// Hands the routes to cpp-httplib, each wrapped with the token check, and answers 405 (with
/// Allow) for the other methods on a known path.
void HttpServer::Impl::install_routes() {
    std::map<std::string, std::set<std::string>> methods_of;  // pattern -> methods
    for (const BoundRoute& r : routes) methods_of[r.pattern].insert(r.method);
    for (const BoundRoute& r : routes) {
        add_route(r.method, r.pattern,
                  [this, handler = r.handler, open = r.open](const Request& req, Response& res) {
                      if (!open) check_token(req);
                      handler(req, res);
                  });
    }
    for (const auto& [pattern, methods] : methods_of) {
        for (const char* method : {"GET", "POST", "PUT", "PATCH", "DELETE"}) {
            if (methods.contains(method)) continue;
            add_route(method, pattern, [method, methods = methods](const Request&, Response&) {
                throw method_not_allowed(method, methods);
            });
        }
        known_paths.push_back({std::regex(pattern), methods});
    }
}

void HttpServer::Impl::install_error_handlers() {
    server.set_exception_handler([this](const Request& req, Response& res, std::exception_ptr error) {
        try {
            std::rethrow_exception(error);
        } catch (const ServiceError& e) {
            write_problem(res, e, req);
        } catch (const std::exception& e) {
            log("internal error on " + req.method + " " + req.path + ": " + e.what());
            write_problem(res, ErrorKind::Internal, e.what(), "", req.path);
        } catch (...) {
            log("internal error on " + req.method + " " + req.path);
            write_problem(res, ErrorKind::Internal, "unknown error", "", req.path);
        }
    });
    server.set_error_handler(httplib::Server::HandlerWithResponse(
        [this](const Request& req, Response& res) { return answer_own_error(req, res); }));
}

/// Errors cpp-httplib answers by itself: no route (404), body too large (413), a malformed
/// request (400; also a PUT without a body). A response a handler wrote already has a body and
/// is left alone. A known path with a method it does not serve is a 405 whatever httplib said.
httplib::Server::HandlerResponse HttpServer::Impl::answer_own_error(const Request& req, Response& res) const {
    if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
    for (const auto& [pattern, methods] : known_paths) {
        if (!std::regex_match(req.path, pattern) || methods.contains(req.method)) continue;
        write_problem(res, method_not_allowed(req.method, methods), req);
        return httplib::Server::HandlerResponse::Handled;
    }
    const int status = res.status;
    std::string detail;
    switch (status) {
        case 404:
            detail = "no route for " + req.method + " " + req.path + " (see /v1/openapi.json)";
            break;
        case 413:
            detail = body_limit_message();
            break;
        case 400:
            detail = req.has_header("Content-Length") || req.has_header("Transfer-Encoding")
                         ? "malformed HTTP request"
                         : "malformed HTTP request (a " + req.method +
                               " needs a body with Content-Length or chunked encoding)";
            break;
        default:
            detail = "HTTP status " + std::to_string(status);
            break;
    }
    write_problem(res, kind_of_status(status), detail, "", req.path);
    res.status = status;
    return httplib::Server::HandlerResponse::Handled;
}

void HttpServer::Impl::configure_connections() {
    server.set_logger([this](const Request& req, const Response& res) {
        services.metrics.record_response(res.status);
        if (options.access_log) log(req.method + " " + req.path + " " + std::to_string(res.status));
    });
    // SO_REUSEADDR alone: cpp-httplib's default also sets SO_REUSEPORT, with which a second daemon
    // on the same port started without an error and took half of the first one's connections.
    server.set_socket_options([](socket_t socket) {
        int yes = 1;
        ::setsockopt(socket, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    // Small answers go out at once: with Nagle's algorithm a body written after its headers
    // waited for the client's delayed ACK (40 ms on Linux), and so did each SSE event.
    server.set_tcp_nodelay(true);
    server.set_payload_max_length(options.max_body_bytes);
    server.set_keep_alive_timeout(2);
    server.set_read_timeout(30);
    server.set_write_timeout(30);
    // A thread per connection, started when one arrives, up to --http-threads at once: slow or
    // idle clients and open streams then never make /healthz or anyone else wait.
    const size_t threads = static_cast<size_t>(std::max(options.http_threads, 4));
    server.new_task_queue = [threads] {
        return new HttpThreadPool(threads, kKeptHttpThreads, kHttpThreadIdleTimeout);
    };
}

// ---------------------------------------------------------------------------------------------
// Jobs

void HttpServer::Impl::submit_job(const Request& req, Response& res) {
    const protocol::Job job = decode_job(req.body);
    const std::string key = req.get_header_value("Idempotency-Key");
    if (key.size() > 256)
        throw ServiceError(ErrorKind::MalformedRequest,
                           "Idempotency-Key: longer than 256 characters");
    // Stored with the job and compared byte for byte: visible ASCII only (a UUID, a hash).
    if (std::any_of(key.begin(), key.end(), [](char c) { return c < 0x21 || c > 0x7e; }))
        throw ServiceError(ErrorKind::MalformedRequest,
                           "Idempotency-Key: only visible ASCII characters (0x21 to 0x7E) are accepted");
    const JobManager::Submitted submitted = services.jobs.submit(job, key);
    res.set_header("Location", "/v1/jobs/" + submitted.status.id);
    send_json(res, protocol::to_json(submitted.status), submitted.created ? 202 : 200);
}

void HttpServer::Impl::submit_batch(const Request& req, Response& res) {
    const json document = decode_json_body(req.body, "{\"job\": {...}, \"cameras\": [{...}, ...]}");
    if (!document.is_object()) throw ServiceError(ErrorKind::InvalidField, "a batch must be a JSON object", "");
    for (const auto& [name, value] : document.items())
        if (name != "job" && name != "cameras")
            throw ServiceError(ErrorKind::InvalidField, "unknown field (expected \"job\" and \"cameras\")", name);
    if (!document.contains("job") || !document["job"].is_object())
        throw ServiceError(ErrorKind::InvalidField, "must be the job description every view shares", "job");
    const json& cameras = document.value("cameras", json());
    if (!cameras.is_array() || cameras.empty() || cameras.size() > kMaxBatchViews)
        throw ServiceError(ErrorKind::InvalidField,
                           "must be a list of 1 to " + std::to_string(kMaxBatchViews) + " cameras, one per view",
                           "cameras");
    if (document["job"].contains("camera"))
        throw ServiceError(ErrorKind::InvalidField, "the views' cameras are the batch's \"cameras\"", "job.camera");
    std::vector<protocol::Job> views;
    for (size_t k = 0; k < cameras.size(); ++k) {
        json view = document["job"];
        view["camera"] = cameras[k];
        auto parsed = protocol::parse_job_detailed(view);
        if (auto* error = std::get_if<protocol::FieldError>(&parsed)) {
            // Named as the batch names it: cameras[k]... or job....
            const bool camera = error->path == "camera" || error->path.rfind("camera.", 0) == 0;
            const std::string path = camera ? "cameras[" + std::to_string(k) + "]" + error->path.substr(6)
                                            : "job." + error->path;
            throw ServiceError(ErrorKind::InvalidField, path + ": " + error->message, path);
        }
        views.push_back(std::get<protocol::Job>(std::move(parsed)));
    }
    json jobs = json::array();
    for (const protocol::JobStatus& status : services.jobs.submit_batch(views)) jobs.push_back(protocol::to_json(status));
    send_json(res, {{"jobs", std::move(jobs)}}, 202);
}

void HttpServer::Impl::list_jobs(const Request& req, Response& res) {
    std::optional<protocol::JobState> state;
    if (req.has_param("state")) {
        state = protocol::parse_job_state(req.get_param_value("state"));
        if (!state)
            throw ServiceError(ErrorKind::MalformedRequest,
                               "state: expected queued, running, done, failed or cancelled");
    }
    size_t limit = 1000;
    if (req.has_param("limit")) {
        const auto value = parse_number<size_t>(req.get_param_value("limit"));
        if (!value || *value == 0)
            throw ServiceError(ErrorKind::MalformedRequest, "limit: expected a positive integer");
        limit = *value;
    }
    json jobs = json::array();
    for (const protocol::JobStatus& status : services.jobs.list(state, limit))
        jobs.push_back(protocol::to_json(status));
    send_json(res, {{"jobs", std::move(jobs)}});
}

void HttpServer::Impl::get_job(const Request& req, Response& res) {
    send_json(res, protocol::to_json(services.jobs.status(req.matches[1])));
}

void HttpServer::Impl::cancel_job(const Request& req, Response& res) {
    const protocol::JobStatus status =
        services.jobs.cancel(req.matches[1], std::chrono::seconds(5));
    // 202: the render was asked to stop but has not finished its current tile yet.
    send_json(res, protocol::to_json(status),
              status.state == protocol::JobState::Cancelled ? 200 : 202);
}

void HttpServer::Impl::job_events(const Request& req, Response& res) {
    const std::string id = req.matches[1];
    (void)services.jobs.status(id);  // 404 before the stream starts
    uint64_t last_id = 0;
    std::string resume = req.get_header_value("Last-Event-ID");
    if (resume.empty() && req.has_param("last_event_id"))
        resume = req.get_param_value("last_event_id");
    if (!resume.empty()) {
        const auto value = parse_number<uint64_t>(resume);
        if (!value)
            throw ServiceError(ErrorKind::MalformedRequest,
                               "Last-Event-ID: expected an event id (an integer)");
        last_id = *value;
    }
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Accel-Buffering", "no");  // proxies (nginx) must not hold events back
    auto cursor = std::make_shared<uint64_t>(last_id);
    auto started = std::make_shared<bool>(false);
    res.set_chunked_content_provider(
        "text/event-stream", [this, id, cursor, started](size_t, httplib::DataSink& sink) {
            std::string out;
            if (!*started) {
                *started = true;
                out = ": events of job " + id + "\nretry: 2000\n\n";
            }
            JobManager::EventBatch batch;
            try {
                batch = services.jobs.wait_events(id, *cursor, options.keep_alive_interval);
            } catch (const ServiceError&) {
                sink.done();
                return true;
            }
            for (const protocol::JobEvent& event : batch.events) {
                out += protocol::format_sse(event);
                *cursor = event.id;
            }
            if (out.empty()) out = ": keep-alive\n\n";  // also finds out when the client has gone
            if (!sink.write(out.data(), out.size())) return false;
            if (batch.ended) sink.done();
            return true;
        });
}

void HttpServer::Impl::job_tile(const Request& req, Response& res) {
    const std::string id = req.matches[1];
    const auto tx = parse_number<int>(req.matches[2].str());
    const auto ty = parse_number<int>(req.matches[3].str());
    const protocol::TileIndex tile{tx.value_or(-1), ty.value_or(-1)};
    const auto geometry = services.jobs.tile_geometry(id, tile);
    if (!geometry)
        throw ServiceError(ErrorKind::NotFound, "tile (" + req.matches[2].str() + ", " +
                                                    req.matches[3].str() +
                                                    ") is outside the tile grid of job " + id);
    const bool or_preview = req.has_param("preview") && is_true(req.get_param_value("preview"));
    bool preview = false;
    auto bytes = services.jobs.tile_exr(id, tile, or_preview, &preview);
    if (!bytes) {
        const protocol::JobStatus status = services.jobs.status(id);
        throw ServiceError(
            ErrorKind::NotFound,
            protocol::is_terminal(status.state)
                ? "job " + id + " is " + std::string(protocol::to_string(status.state)) +
                      ": its tiles are gone"
                : "tile (" + std::to_string(tile.tx) + ", " + std::to_string(tile.ty) +
                      ") of job " + id + " is not finished yet");
    }
    res.set_header("X-Tile-X", std::to_string(tile.tx));
    res.set_header("X-Tile-Y", std::to_string(tile.ty));
    res.set_header("X-Tile-Rect", rect_header(geometry->rect));
    res.set_header("X-Tile-Kind", preview ? "preview" : "final");
    if (or_preview) res.set_header("Cache-Control", "no-cache");  // the same URL gives the final tile later
    send_bytes(res, std::move(*bytes), kExrType);
}

void HttpServer::Impl::job_tile_stream(const Request& req, Response& res) {
    const std::string id = req.matches[1];
    (void)services.jobs.status(id);  // 404 before the stream starts
    const std::string boundary = random_boundary();
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Accel-Buffering", "no");
    auto next = std::make_shared<size_t>(0);
    res.set_chunked_content_provider(
        "multipart/mixed; boundary=" + boundary,
        [this, id, boundary, next](size_t, httplib::DataSink& sink) {
            JobManager::TileBatch batch;
            try {
                batch = services.jobs.wait_tiles(id, *next, options.keep_alive_interval);
            } catch (const ServiceError&) {
                sink.done();
                return true;
            }
            for (const protocol::TileIndex& tile : batch.tiles) {
                const auto geometry = services.jobs.tile_geometry(id, tile);
                auto bytes = services.jobs.tile_exr(id, tile);
                if (!geometry || !bytes) continue;  // freed meanwhile (cancelled)
                std::string head =
                    "--" + boundary + "\r\nContent-Type: image/x-exr\r\nContent-Length: " +
                    std::to_string(bytes->size()) + "\r\nX-Tile-X: " + std::to_string(tile.tx) +
                    "\r\nX-Tile-Y: " + std::to_string(tile.ty) +
                    "\r\nX-Tile-Rect: " + rect_header(geometry->rect) + "\r\n\r\n";
                head.append(reinterpret_cast<const char*>(bytes->data()), bytes->size());
                head += "\r\n";
                if (!sink.write(head.data(), head.size())) return false;
            }
            *next = batch.next;
            if (batch.ended) {
                const std::string closing = "--" + boundary + "--\r\n";
                if (!sink.write(closing.data(), closing.size())) return false;
                sink.done();
            }
            return true;
        });
}

void HttpServer::Impl::job_image(const Request& req, Response& res) {
    const std::string id = req.matches[1];
    if (req.has_param("wait") && is_true(req.get_param_value("wait"))) {
        for (;;) {
            const protocol::JobStatus status =
                services.jobs.wait_finished(id, std::chrono::seconds(1));
            if (protocol::is_terminal(status.state)) break;
            if (services.jobs.stopping())
                throw ServiceError(ErrorKind::Unavailable, "the daemon is shutting down; job " +
                                                               id + " runs again when it restarts")
                    .with_header("Retry-After", "10");
        }
    }
    const std::filesystem::path file = services.jobs.image_file(id);
    std::error_code error;
    const auto size = std::filesystem::file_size(file, error);
    if (error) throw ServiceError(ErrorKind::Internal, file.string() + ": cannot be read");
    auto in = std::make_shared<std::ifstream>(file, std::ios::binary);
    if (!*in) throw ServiceError(ErrorKind::Internal, file.string() + ": cannot be read");
    res.set_header("Content-Disposition", "attachment; filename=\"" + id + ".exr\"");
    res.set_content_provider(
        size, kExrType, [in](size_t offset, size_t length, httplib::DataSink& sink) {
            std::vector<char> buffer(std::min<size_t>(length, size_t{1} << 20));
            in->seekg(static_cast<std::streamoff>(offset));
            in->read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
            const auto got = static_cast<size_t>(in->gcount());
            return got > 0 && sink.write(buffer.data(), got);
        });
}

void HttpServer::Impl::job_preview(const Request& req, Response& res) {
    res.set_header("Cache-Control", "no-cache");
    send_bytes(res, services.jobs.preview_png(req.matches[1]), "image/png");
}

// ---------------------------------------------------------------------------------------------
// Scenes and photon maps

void HttpServer::Impl::upload_scene(const Request& req, Response& res) {
    const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(req.body.data()),
                                         req.body.size());
    auto result = services.scenes.add(bytes);
    if (const auto* refused = std::get_if<SceneStore::Refused>(&result))
        throw ServiceError(
            refused->over_limit ? ErrorKind::PayloadTooLarge : ErrorKind::InvalidField,
            refused->message);
    const SceneStore::Added& added = std::get<SceneStore::Added>(result);
    res.set_header("Location", "/v1/scenes/" + added.info.id);
    send_json(res, to_json(added.info), added.created ? 201 : 200);
}

void HttpServer::Impl::list_scenes(const Request&, Response& res) {
    json scenes = json::array();
    for (const SceneInfo& info : services.scenes.list()) scenes.push_back(to_json(info));
    send_json(res, {{"scenes", std::move(scenes)}});
}

void HttpServer::Impl::get_scene(const Request& req, Response& res) {
    const std::string id = req.matches[1];
    const auto info = services.scenes.info(id);
    if (!info) throw ServiceError(ErrorKind::NotFound, "no uploaded scene '" + id + "'");
    send_json(res, to_json(*info));
}

void HttpServer::Impl::delete_scene(const Request& req, Response& res) {
    const std::string id = req.matches[1];
    if (!services.scenes.remove(id))
        throw ServiceError(ErrorKind::NotFound, "no uploaded scene '" + id + "'");
    res.status = 204;
}

namespace {

// The routes of a cache of artifacts (photon maps, render caches): list, export, import.

template <class Traits>
void list_artifacts(const ArtifactCache<Traits>& cache, Response& res) {
    send_json(res, {{"keys", cache.keys()}});
}

template <class Traits>
void export_artifact(ArtifactCache<Traits>& cache, const std::string& key, Response& res) {
    auto bytes = cache.export_bytes(key);
    if (!bytes)
        throw ServiceError(ErrorKind::NotFound, Traits::is_valid_key(key)
                                                    ? "no " + std::string(Traits::kName) + " for key " + key + " here"
                                                    : "'" + key + "' is not a " + Traits::kName + " key (" +
                                                          Traits::kKeyForm + ")");
    res.set_header("Content-Disposition", "attachment; filename=\"" + key + Traits::kExtension + "\"");
    send_bytes(res, std::move(*bytes), "application/octet-stream");
}

template <class Traits>
void import_artifact(ArtifactCache<Traits>& cache, const std::string& key, const std::string& body, Response& res) {
    if (!Traits::is_valid_key(key))
        throw ServiceError(ErrorKind::NotFound,
                           "'" + key + "' is not a " + Traits::kName + " key (" + Traits::kKeyForm + ")");
    const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(body.data()), body.size());
    bool conflict = false;
    auto imported = cache.import_bytes(key, bytes, &conflict);
    if (!imported)
        throw ServiceError(conflict ? ErrorKind::Conflict : ErrorKind::InvalidField, imported.error().message);
    send_json(res, {{"key", key}, {"created", *imported}}, *imported ? 201 : 200);
}

}  // namespace

void HttpServer::Impl::list_photon_maps(const Request&, Response& res) { list_artifacts(services.photon_maps, res); }

void HttpServer::Impl::export_photon_maps(const Request& req, Response& res) {
    export_artifact(services.photon_maps, req.matches[1], res);
}

void HttpServer::Impl::import_photon_maps(const Request& req, Response& res) {
    import_artifact(services.photon_maps, req.matches[1], req.body, res);
}

void HttpServer::Impl::list_render_caches(const Request&, Response& res) {
    list_artifacts(render_caches(), res);
}

void HttpServer::Impl::export_render_cache(const Request& req, Response& res) {
    export_artifact(render_caches(), req.matches[1], res);
}

void HttpServer::Impl::import_render_cache(const Request& req, Response& res) {
    import_artifact(render_caches(), req.matches[1], req.body, res);
}

// ---------------------------------------------------------------------------------------------
// Operations

void HttpServer::Impl::healthz(const Request&, Response& res) {
    res.set_content("ok\n", "text/plain");
}

void HttpServer::Impl::readyz(const Request&, Response& res) {
    if (services.jobs.stopping())
        throw ServiceError(ErrorKind::Unavailable, "the daemon is shutting down");
    if (!services.jobs.worker_running())
        throw ServiceError(ErrorKind::Unavailable, "the render worker is not running");
    if (!services.jobs.cache_dir_writable())
        throw ServiceError(ErrorKind::Unavailable, "the cache directory is not writable");
    // A full disk fails every job (and refuses every submission): not ready, and why.
    const std::optional<uint64_t> free = services.jobs.cache_dir_free_bytes();
    if (free && *free < options.min_free_bytes)
        throw ServiceError(ErrorKind::Unavailable, "the cache directory's disk has " + std::to_string(*free >> 20) +
                                                       " MiB free, under the " +
                                                       std::to_string(options.min_free_bytes >> 20) +
                                                       " MiB that --min-free-mb asks for");
    send_json(res, {{"status", "ready"}, {"cache_free_bytes", free ? json(*free) : json(nullptr)}});
}

void HttpServer::Impl::metrics(const Request&, Response& res) {
    MetricsSnapshot snapshot;
    services.jobs.fill_metrics(snapshot);
    const PhotonMapCache::Counters cache = services.photon_maps.counters();
    snapshot.photon_cache_hits = cache.hits;
    snapshot.photon_cache_misses = cache.misses;
    snapshot.photon_cache_bytes = cache.memory_bytes;
    snapshot.photon_cache_entries = cache.memory_entries;
    if (services.render_caches) {
        const auto render = services.render_caches->counters();
        snapshot.render_cache_hits = render.hits;
        snapshot.render_cache_misses = render.misses;
        snapshot.render_cache_bytes = render.memory_bytes;
        snapshot.render_cache_entries = render.memory_entries;
    }
    res.set_content(services.metrics.render(snapshot), "text/plain; version=0.0.4; charset=utf-8");
}

void HttpServer::Impl::openapi(const Request&, Response& res) {
    send_json(res, openapi_document());
}

// ---------------------------------------------------------------------------------------------

HttpServer::HttpServer(HttpServerOptions options, HttpServices services)
    : impl_(std::make_unique<Impl>(std::move(options), services)) {
    impl_->register_routes();
    impl_->install();
}

HttpServer::~HttpServer() { stop(); }

Expected<int> HttpServer::bind() {
    const std::string& host = impl_->options.host;
    if (impl_->options.port == 0) {
        const int port = impl_->server.bind_to_any_port(host);
        if (port <= 0) return Error{"cannot listen on " + host + " (any port)"};
        impl_->server.widen_backlog();
        return port;
    }
    if (!impl_->server.bind_to_port(host, impl_->options.port))
        return Error{"cannot listen on " + host + ":" + std::to_string(impl_->options.port) +
                     " (in use, or not an address of this machine)"};
    impl_->server.widen_backlog();
    return impl_->options.port;
}

void HttpServer::serve() { impl_->server.listen_after_bind(); }

void HttpServer::stop() { impl_->server.stop(); }

bool HttpServer::running() const { return impl_->server.is_running(); }

// ---------------------------------------------------------------------------------------------
// Requests from memory (fuzz/http_request_fuzzer.cpp, tests/server/http_raw_request_test.cpp)

namespace {

/// A connection whose client sends `input` and then nothing, and whose output is kept (up to
/// `max_output` bytes: a write beyond it fails, which ends a stream).
class MemoryStream final : public httplib::Stream {
public:
    MemoryStream(std::string_view input, size_t max_output)
        : input_(input), max_output_(max_output) {}

    bool is_readable() const override { return position_ < input_.size(); }
    bool is_writable() const override { return output_.size() < max_output_; }
    ssize_t read(char* ptr, size_t size) override {
        const size_t n = std::min(size, input_.size() - position_);
        std::copy_n(input_.data() + position_, n, ptr);
        position_ += n;
        return static_cast<ssize_t>(n);
    }
    ssize_t write(const char* ptr, size_t size) override {
        if (size > max_output_ - std::min(max_output_, output_.size())) return -1;
        output_.append(ptr, size);
        return static_cast<ssize_t>(size);
    }
    void get_remote_ip_and_port(std::string& ip, int& port) const override {
        ip = "127.0.0.1";
        port = 0;
    }
    void get_local_ip_and_port(std::string& ip, int& port) const override {
        ip = "127.0.0.1";
        port = 0;
    }
    socket_t socket() const override { return INVALID_SOCKET; }

    std::string take_output() { return std::move(output_); }

private:
    std::string_view input_;
    size_t position_ = 0;
    size_t max_output_;
    std::string output_;
};

}  // namespace

std::string HttpServer::handle_raw_request(std::string_view bytes) {
    constexpr int kMaxRequests = 5;  // cpp-httplib's keep-alive default per connection
    constexpr size_t kMaxOutputBytes = size_t{8} << 20;
    MemoryStream stream(bytes, kMaxOutputBytes);
    for (int i = 0; i < kMaxRequests && stream.is_readable(); ++i) {
        bool connection_closed = false;
        const bool last = i + 1 == kMaxRequests;
        if (!impl_->server.process_request(stream, last, connection_closed, nullptr) ||
            connection_closed)
            break;
    }
    return stream.take_output();
}

}  // namespace photond::service
