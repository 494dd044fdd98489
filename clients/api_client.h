// The daemon's HTTP API v1 (README.md, "Using the daemon with curl"; docs/ARCHITECTURE.md) as C++ calls, for photonctl. Every
// failure comes back as an Error whose message is ready for a user: problem+json answers as
// "<title>: <detail> (field: <field>)", connection failures naming the server's URL.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "clients/stream_parsers.h"
#include "core/util/expected.h"

namespace httplib {
class Client;
}

namespace photond::client {

inline constexpr std::string_view kDefaultServerUrl = "http://127.0.0.1:8080";

/// A server address: "http://host:port" (or https) plus an optional path prefix ("/render").
struct ServerUrl {
    std::string origin;       ///< scheme://host:port, what the HTTP library connects to
    std::string path_prefix;  ///< "" or "/prefix" without a trailing '/'
    std::string text;         ///< as the user wrote it, for messages
};

/// Reads "http://host:port[/prefix]"; a URL without a scheme gets "http://".
Expected<ServerUrl> parse_server_url(std::string_view url);

/// An RFC 9457 problem (or any other non-success answer, described in the same terms).
struct Problem {
    int status = 0;
    std::string type;
    std::string title;
    std::string detail;
    std::string field;  ///< the offending field's path, when the server names one
};

/// Reads a problem+json body; a body that is not one still gives a problem with `status`, the
/// reason phrase as title and the (shortened) body as detail.
Problem parse_problem(int status, std::string_view content_type, std::string_view body);

/// "<title>: <detail> (field: <field>)", leaving out the parts that are empty.
std::string describe(const Problem& problem);

/// How a stream (events or tiles) ended.
struct StreamEnd {
    enum class Kind {
        Ended,        ///< the server closed the stream after a complete response
        Stopped,      ///< the callback asked to stop
        Interrupted,  ///< the connection broke mid-stream: reconnecting may resume it
        Failed,       ///< no stream: connection refused, an HTTP error, a malformed stream
    };
    Kind kind = Kind::Ended;
    std::string message;  ///< for Interrupted and Failed, ready for a user
    int http_status = 0;  ///< the response's status, 0 when none arrived
};

class ApiClient {
public:
    /// `token` is sent as "Authorization: Bearer <token>" when non-empty.
    ApiClient(ServerUrl server, std::string token);
    ~ApiClient();

    const ServerUrl& server() const { return server_; }

    /// POST /v1/jobs; the answer (with "id"). `idempotency_key` is sent when non-empty.
    Expected<nlohmann::json> submit(const nlohmann::json& job, const std::string& idempotency_key);
    /// GET /v1/jobs/{id}.
    Expected<nlohmann::json> job(const std::string& id);
    /// GET /v1/jobs: the list of jobs (the "jobs" member when the server wraps it).
    Expected<nlohmann::json> jobs();
    /// DELETE /v1/jobs/{id}.
    Expected<nlohmann::json> cancel(const std::string& id);
    /// GET /v1/jobs/{id}/image.exr (with ?wait=true: blocks until the job ends).
    Expected<std::string> image(const std::string& id, bool wait);
    /// POST /v1/scenes with a .glb, a self-contained .gltf or a zip / tar / tar.gz bundle body.
    Expected<nlohmann::json> upload_scene(const std::string& bytes, std::string_view content_type);

    /// GET /v1/jobs/{id}/events, calling `on_event` for each event until it returns false or the
    /// stream ends. `last_event_id` (when non-empty) resumes after that event.
    StreamEnd events(const std::string& id, const std::string& last_event_id,
                     const std::function<bool(const SseEvent&)>& on_event);
    /// GET /v1/jobs/{id}/tiles, calling `on_part` for each tile part as it arrives.
    StreamEnd tiles(const std::string& id,
                    const std::function<bool(const MultipartPart&)>& on_part);

private:
    struct Response {
        int status = 0;
        std::string content_type;
        std::string body;
    };

    std::unique_ptr<httplib::Client> connect(bool long_wait) const;
    std::string path(std::string_view api_path) const;
    std::string job_path(const std::string& id, std::string_view suffix = {}) const;
    std::string connection_failure(int error_code) const;
    Expected<Response> request(std::string_view method, const std::string& path,
                               const std::string* body, std::string_view content_type,
                               const std::string& idempotency_key, bool long_wait);
    Expected<nlohmann::json> request_json(std::string_view method, const std::string& path,
                                          const std::string* body = nullptr,
                                          std::string_view content_type = {},
                                          const std::string& idempotency_key = {});
    /// A streaming GET: `on_bytes` sees the body of a successful answer as it arrives and
    /// returns false to stop; `on_response` sees the answer's headers first.
    StreamEnd stream(
        const std::string& path, const std::string& accept, const std::string& last_event_id,
        const std::function<bool(int status, const std::string& content_type)>& on_response,
        const std::function<bool(std::string_view bytes)>& on_bytes);

    ServerUrl server_;
    std::string token_;
};

/// Percent-encodes a path segment (a job id may hold any character).
std::string encode_path_segment(std::string_view segment);

}  // namespace photond::client
