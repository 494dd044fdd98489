// HttpServer::handle_raw_request, the socket-free entry the fuzzer drives
// (fuzz/http_request_fuzzer.cpp): raw request bytes in, raw response bytes out, through the same
// routes, token check and error handling as a served connection.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "server/http_server.h"
#include "server/job_manager.h"
#include "server/metrics.h"
#include "server/photon_map_cache.h"
#include "server/scene_store.h"
#include "tests/server/daemon_harness.h"
#include "tests/support/render_fixtures.h"

namespace photond::service {
namespace {

/// The services of `photond serve` on a temporary cache directory, the worker not started.
class RawRequestDaemon {
public:
    RawRequestDaemon()
        : dir_("http_raw_request"),
          photon_maps_(dir_.path() / "photon-maps", 16 << 20),
          scenes_(dir_.path() / "scenes"),
          jobs_(job_options(dir_.path()), test_support::shared_device(), &photon_maps_, &scenes_,
                &metrics_),
          server_(http_options(), {jobs_, scenes_, photon_maps_, metrics_}) {}

    std::string handle(const std::string& bytes) { return server_.handle_raw_request(bytes); }

private:
    static JobManagerOptions job_options(const std::filesystem::path& dir) {
        JobManagerOptions options;
        options.cache_dir = dir;
        options.scene_root = dir;
        options.max_queued = 1;
        return options;
    }
    static HttpServerOptions http_options() {
        HttpServerOptions options;
        options.token = "secret";
        return options;
    }

    test::TempDir dir_;
    Metrics metrics_;
    PhotonMapCache photon_maps_;
    SceneStore scenes_;
    JobManager jobs_;
    HttpServer server_;
};

size_t count(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

TEST(HttpRawRequest, HealthzAnswers200) {
    RawRequestDaemon daemon;
    const std::string response = daemon.handle("GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n");
    EXPECT_TRUE(response.starts_with("HTTP/1.1 200 OK\r\n")) << response;
    EXPECT_TRUE(response.ends_with("\r\n\r\nok\n")) << response;
}

TEST(HttpRawRequest, AMalformedRequestAnswers400WithAProblem) {
    RawRequestDaemon daemon;
    const std::string response = daemon.handle("NOT AN HTTP REQUEST\r\n\r\n");
    EXPECT_TRUE(response.starts_with("HTTP/1.1 400 Bad Request\r\n")) << response;
    EXPECT_NE(response.find("application/problem+json"), std::string::npos) << response;
    EXPECT_NE(response.find("malformed HTTP request"), std::string::npos) << response;
}

TEST(HttpRawRequest, KeepAliveRequestsAreAnsweredInOrder) {
    RawRequestDaemon daemon;
    const std::string response = daemon.handle(
        "GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n"
        "GET /v1/jobs HTTP/1.1\r\nHost: x\r\n\r\n");
    const size_t ok = response.find("HTTP/1.1 200 OK\r\n");
    const size_t unauthorized = response.find("HTTP/1.1 401 Unauthorized\r\n");
    ASSERT_NE(ok, std::string::npos) << response;
    ASSERT_NE(unauthorized, std::string::npos) << response;
    EXPECT_LT(ok, unauthorized);
    EXPECT_NE(response.find("this daemon needs a bearer token"), std::string::npos) << response;
}

TEST(HttpRawRequest, JobsAreValidatedAndQueuedWithoutRendering) {
    RawRequestDaemon daemon;
    const std::string job =
        R"({"scene": {"builtin": "cornell-box"}, "image": {"width": 8, "height": 8}})";
    const std::string submit =
        "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer secret\r\n"
        "Content-Type: application/json\r\nContent-Length: " +
        std::to_string(job.size()) + "\r\n\r\n" + job;
    EXPECT_TRUE(daemon.handle(submit).starts_with("HTTP/1.1 202 Accepted\r\n"));
    // The worker never started: the job waits, and the queue (one job) is full.
    const std::string second = daemon.handle(submit);
    EXPECT_TRUE(second.starts_with("HTTP/1.1 429 Too Many Requests\r\n")) << second;
    EXPECT_NE(second.find("Retry-After: "), std::string::npos) << second;

    const std::string bad = "{\"scene\": ";
    const std::string malformed = daemon.handle(
        "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer secret\r\n"
        "Content-Length: " +
        std::to_string(bad.size()) + "\r\n\r\n" + bad);
    EXPECT_TRUE(malformed.starts_with("HTTP/1.1 400 Bad Request\r\n")) << malformed;
    EXPECT_NE(malformed.find("malformed JSON at line 1 column 11"), std::string::npos) << malformed;
    EXPECT_EQ(count(malformed, "HTTP/1.1 "), 1u);
}

}  // namespace
}  // namespace photond::service
