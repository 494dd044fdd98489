// The HTTP API: raw request bytes through the real server's routes, handlers and error handling
// (HttpServer::handle_raw_request, server/http_server.h), without a socket. The services are
// built as `photond serve` builds them (server/serve_command.cpp), on a cache directory of this
// process under /dev/shm, with a bearer token (fuzz/corpus/http_request sends it) and a 1 MiB
// body limit.
//
// Nothing renders: the job manager's worker is not started (JobManager::start is never called)
// and at most one job may wait in the queue, so the first valid job submitted is queued and the
// others are answered 429. Uploaded scenes are deleted again after each input, so that the
// store does not grow with every valid upload the fuzzer makes.
//
// cpp-httplib's own request parser is Debian's compiled library (not instrumented): what is
// measured and guided is photond's side of each request.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "core/accel/ray_tracer.h"
#include "server/http_server.h"
#include "server/job_manager.h"
#include "server/metrics.h"
#include "server/photon_map_cache.h"
#include "server/scene_store.h"

namespace {

namespace fs = std::filesystem;
using namespace photond::service;

struct Daemon {
    fs::path root = fs::path("/dev/shm") / ("photond-http-fuzzer-" + std::to_string(getpid()));
    std::shared_ptr<photond::EmbreeDevice> device;
    std::unique_ptr<Metrics> metrics;
    std::unique_ptr<PhotonMapCache> photon_maps;
    std::unique_ptr<SceneStore> scenes;
    std::unique_ptr<JobManager> jobs;
    std::unique_ptr<HttpServer> server;

    Daemon() {
        fs::remove_all(root);
        fs::create_directories(root / "cache");
        fs::create_directories(root / "scenes");
        auto created = photond::EmbreeDevice::create();
        if (!created) {
            std::fprintf(stderr, "http_request_fuzzer: %s\n", created.error().message.c_str());
            std::abort();
        }
        device = *created;
        metrics = std::make_unique<Metrics>();
        photon_maps = std::make_unique<PhotonMapCache>(root / "cache" / "photon-maps", 16 << 20);
        BundleLimits bundle_limits;
        bundle_limits.max_unpacked_bytes = uint64_t{8} << 20;
        bundle_limits.max_entries = 64;
        scenes = std::make_unique<SceneStore>(root / "cache" / "scenes", bundle_limits);
        JobManagerOptions job_options;
        job_options.cache_dir = root / "cache";
        job_options.scene_root = root / "scenes";
        job_options.threads = 1;
        job_options.max_queued = 1;
        jobs = std::make_unique<JobManager>(job_options, device, photon_maps.get(), scenes.get(),
                                            metrics.get());
        HttpServerOptions http_options;
        http_options.token = "fuzz-token";
        http_options.max_body_bytes = size_t{1} << 20;
        http_options.keep_alive_interval = std::chrono::milliseconds(1);
        server = std::make_unique<HttpServer>(http_options,
                                              HttpServices{*jobs, *scenes, *photon_maps, *metrics});
    }
    ~Daemon() {
        server.reset();
        jobs.reset();
        std::error_code ignored;
        fs::remove_all(root, ignored);
    }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static Daemon daemon;
    (void)daemon.server->handle_raw_request(
        std::string_view(reinterpret_cast<const char*>(data), size));
    for (const SceneInfo& info : daemon.scenes->list()) daemon.scenes->remove(info.id);
    return 0;
}
