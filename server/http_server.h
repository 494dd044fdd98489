// The HTTP API v1 of `photond serve` on cpp-httplib. The routes are those of the route table
// (server/routes.h), registered in one function (register_routes in http_server.cpp); handlers
// are thin: decode the request, call the job manager or a store, encode the answer. Failures are
// thrown as ServiceError and turned into RFC 9457 problem+json in one place, the server's
// exception handler; errors that cpp-httplib raises itself (no route, body too large, malformed
// request) get the same treatment in its error handler.
//
// httplib.h is kept out of this header: it must be compiled with the definitions that
// PkgConfig::HTTPLIB carries (Debian builds the library with OpenSSL, zlib and Brotli support),
// so only the .cpp files of the photond_daemon library include it.
//
// Thread safety: bind(), serve() and stop() may be called from different threads; stop() may be
// called at any time, also before serve() starts.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "core/util/expected.h"

namespace photond::service {

class JobManager;
class SceneStore;
class PhotonMapCache;
class RenderCacheDirectory;
class Metrics;

struct HttpServerOptions {
    std::string host = "127.0.0.1";
    int port = 8080;    // 0: any free port (bind() says which)
    std::string token;  // bearer token; empty: no authentication
    size_t max_body_bytes = size_t{256} << 20;
    uint64_t min_free_bytes = uint64_t{64} << 20;  // /readyz: not ready below this on the cache disk
    int http_threads = 1024;  // connections served at once, a thread each (HttpThreadPool)
    std::chrono::milliseconds keep_alive_interval{15000};  // SSE comment while nothing happens
    bool access_log = false;                               // one line per request to `log`
    std::function<void(const std::string&)> log;
};

struct HttpServices {
    JobManager& jobs;
    SceneStore& scenes;
    PhotonMapCache& photon_maps;
    Metrics& metrics;
    RenderCacheDirectory* render_caches = nullptr;  // null: /v1/render-caches answers 404
};

class HttpServer {
public:
    HttpServer(HttpServerOptions options, HttpServices services);
    ~HttpServer();
    HttpServer(const HttpServer&) = delete;
    HttpServer& operator=(const HttpServer&) = delete;

    /// Binds the listening socket; returns the port (the chosen one when options.port is 0).
    Expected<int> bind();
    /// Serves requests until stop(); call after a successful bind().
    void serve();
    void stop();
    bool running() const;

    /// Serves the raw bytes of one or more HTTP/1.1 requests (keep-alive, at most 5, as on one
    /// connection) through the same routes, handlers and error handling as serve(), without a
    /// socket, and returns the raw bytes of the responses. Streamed responses (events, tiles) end
    /// where the stream does or after 8 MiB. For the fuzzer (fuzz/http_request_fuzzer.cpp) and
    /// tests; bind() is not needed.
    std::string handle_raw_request(std::string_view bytes);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace photond::service
