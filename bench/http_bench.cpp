// What the daemon costs on top of rendering. Prints:
//   0. time from submit to the first full-frame image of a progressive job (job.progressive, the
//      default) on a photon-map cache hit: the last preview tile's event on the SSE stream, and
//      preview.png of the whole frame received after it (goal: 150 ms at 512x512 on 2 cores);
//   1. time from submit to the first final tile on a photon-map cache hit (a second camera view
//      of a scene whose maps are cached), through POST /v1/jobs and the multipart tile stream;
//   2. HTTP and streaming overhead as a share of render time: the same job rendered by run_job
//      directly (plus the EXR write `photond render` does) against the daemon's wall time from
//      POST to the last byte of the tile stream and of image.exr, with the stream consumed.
//      Goal: under 2 %.
// The daemon runs in this process (JobManager + HttpServer on a free loopback port); the client is
// cpp-httplib over a real socket.
#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "core/image/exr_io.h"
#include "protocol/job.h"
#include "protocol/statistics.h"
#include "server/http_server.h"
#include "server/job_manager.h"
#include "server/metrics.h"
#include "server/photon_map_cache.h"
#include "server/render_pipeline.h"
#include "server/scene_store.h"

namespace {

namespace fs = std::filesystem;
using namespace photond;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values[values.size() / 2];
}

json make_job(const json& camera, bool progressive = true) {
    json job = {{"scene", {{"builtin", "cornell-box"}}},
                {"integrator", "photon-map"},
                {"image", {{"width", 512}, {"height", 512}, {"spp", 4}, {"tile_size", 32}}},
                {"photons", {{"global", 100000}, {"caustic", 50000}, {"seed", 1}}},
                {"gather", {{"rays", 128}}},
                {"progressive", progressive}};
    if (!camera.is_null()) job["camera"] = camera;
    return job;
}

json view(double x) {
    return {{"look_from", {x, 3.0, 9.0}}, {"look_at", {0.0, 2.5, 0.0}}, {"vfov_deg", 42}};
}

/// Counts the parts of a multipart stream as it arrives (parts carry Content-Length).
class PartCounter {
public:
    explicit PartCounter(std::string boundary) : delimiter_("--" + std::move(boundary)) {}
    void feed(const char* data, size_t size) {
        buffer_.append(data, size);
        for (;;) {
            if (remaining_ > 0) {
                const size_t take = std::min(remaining_, buffer_.size());
                buffer_.erase(0, take);
                remaining_ -= take;
                if (remaining_ > 0) return;
                ++parts_;
                continue;
            }
            const size_t start = buffer_.find(delimiter_);
            if (start == std::string::npos) return;
            if (buffer_.compare(start + delimiter_.size(), 2, "--") == 0) {
                closed_ = true;
                return;
            }
            const size_t head_end = buffer_.find("\r\n\r\n", start);
            if (head_end == std::string::npos) return;
            const size_t length_at = buffer_.find("Content-Length: ", start);
            remaining_ = std::stoul(buffer_.substr(length_at + 16)) + 2;  // body + CRLF
            buffer_.erase(0, head_end + 4);
            if (remaining_ == 0) ++parts_;
        }
    }
    size_t parts() const { return parts_; }
    bool closed() const { return closed_; }

private:
    std::string delimiter_;
    std::string buffer_;
    size_t remaining_ = 0;
    size_t parts_ = 0;
    bool closed_ = false;
};

struct StreamTimes {
    double first_tile = 0.0;  // from POST
    double last_byte = 0.0;   // of the tile stream (closing boundary), from POST
    double with_image = 0.0;  // image.exr fetched too, from POST
    size_t tiles = 0;
    json status;
};

/// Submits a job; returns its id (exits on failure).
std::string submit(httplib::Client& client, const json& job) {
    auto posted = client.Post("/v1/jobs", job.dump(), "application/json");
    if (!posted || posted->status != 202) {
        std::fprintf(stderr, "http_bench: submit failed\n");
        std::exit(1);
    }
    return json::parse(posted->body).at("id");
}

/// Submits a job and consumes its tile stream and final image, timing from the POST.
StreamTimes submit_and_stream(httplib::Client& client, const json& job) {
    StreamTimes t;
    const Clock::time_point start = Clock::now();
    const std::string id = submit(client, job);
    std::unique_ptr<PartCounter> counter;
    client.Get(
        "/v1/jobs/" + id + "/tiles",
        [&](const httplib::Response& response) {
            const std::string type = response.get_header_value("Content-Type");
            counter = std::make_unique<PartCounter>(type.substr(type.find('=') + 1));
            return true;
        },
        [&](const char* data, size_t size) {
            const size_t before = counter->parts();
            counter->feed(data, size);
            if (before == 0 && counter->parts() > 0) t.first_tile = seconds_since(start);
            return true;
        });
    t.last_byte = seconds_since(start);
    t.tiles = counter ? counter->parts() : 0;
    auto image = client.Get("/v1/jobs/" + id + "/image.exr?wait=true");
    if (!image || image->status != 200) {
        std::fprintf(stderr, "http_bench: image.exr failed\n");
        std::exit(1);
    }
    t.with_image = seconds_since(start);
    t.status = json::parse(client.Get("/v1/jobs/" + id)->body);
    return t;
}

struct PreviewTimes {
    double last_preview_event = 0.0;  // the preview tile event that completes the frame, from POST
    double preview_png = 0.0;         // preview.png (the whole frame) received after it, from POST
    json status;
};

/// Submits a progressive job and follows its SSE stream until the preview covers the frame,
/// then fetches preview.png; waits for the job to end.
PreviewTimes submit_and_watch_preview(httplib::Client& client, const json& job) {
    PreviewTimes t;
    const Clock::time_point start = Clock::now();
    const std::string id = submit(client, job);
    std::string buffer;
    bool complete = false;
    // Events are "event: TYPE\ndata: JSON\n\n"; the stream is left once the preview is whole
    // (or the job ended without one).
    client.Get("/v1/jobs/" + id + "/events", [&](const char* data, size_t size) {
        buffer.append(data, size);
        for (size_t end; (end = buffer.find("\n\n")) != std::string::npos; buffer.erase(0, end + 2)) {
            const std::string event = buffer.substr(0, end);
            const size_t type_at = event.find("event: "), data_at = event.find("data: ");
            if (type_at == std::string::npos || data_at == std::string::npos) continue;
            const std::string type = event.substr(type_at + 7, event.find('\n', type_at) - type_at - 7);
            if (type == "done" || type == "failed" || type == "cancelled") return false;
            if (type != "tile") continue;
            const json d = json::parse(event.substr(data_at + 6), nullptr, false);
            if (!d.value("preview", false)) continue;
            if (d.value("preview_tiles_done", 0) == d.value("tiles_total", -1)) {
                t.last_preview_event = seconds_since(start);
                complete = true;
                return false;
            }
        }
        return true;
    });
    if (!complete) {
        std::fprintf(stderr, "http_bench: job %s streamed no whole preview\n", id.c_str());
        std::exit(1);
    }
    auto png = client.Get("/v1/jobs/" + id + "/preview.png");
    if (!png || png->status != 200) {
        std::fprintf(stderr, "http_bench: preview.png failed\n");
        std::exit(1);
    }
    t.preview_png = seconds_since(start);
    auto image = client.Get("/v1/jobs/" + id + "/image.exr?wait=true");
    if (!image || image->status != 200) {
        std::fprintf(stderr, "http_bench: image.exr failed\n");
        std::exit(1);
    }
    t.status = json::parse(client.Get("/v1/jobs/" + id)->body);
    return t;
}

}  // namespace

int main(int argc, char** argv) {
    const int repetitions = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
    const fs::path dir =
        fs::temp_directory_path() / ("photond_http_bench_" + std::to_string(::getpid()));
    fs::create_directories(dir);

    auto device = EmbreeDevice::create();
    if (!device) {
        std::fprintf(stderr, "http_bench: %s\n", device.error().message.c_str());
        return 1;
    }
    service::Metrics metrics;
    service::PhotonMapCache photon_maps(dir / "photon-maps", size_t{1} << 30);
    service::SceneStore scenes(dir / "scenes");
    service::JobManagerOptions options;
    options.cache_dir = dir;
    options.scene_root = dir;
    service::JobManager jobs(options, *device, &photon_maps, &scenes, &metrics);
    service::HttpServerOptions http_options;
    http_options.port = 0;
    service::HttpServer server(http_options, {jobs, scenes, photon_maps, metrics});
    const auto port = server.bind();
    if (!port) {
        std::fprintf(stderr, "http_bench: %s\n", port.error().message.c_str());
        return 1;
    }
    jobs.start();
    std::thread serving([&] { server.serve(); });
    httplib::Client client("127.0.0.1", *port);
    client.set_read_timeout(std::chrono::minutes(10));

    std::printf(
        "http_bench: cornell-box, photon-map, 512x512, 4 spp, 256 tiles, %d threads, %d "
        "repetitions\n",
        static_cast<int>(std::thread::hardware_concurrency()), repetitions);

    // Warm-up: traces the photon maps once (every later job hits the cache).
    const StreamTimes warm = submit_and_stream(client, make_job(nullptr));
    std::printf("  warm-up (photon maps traced): %.3f s, photons cache %s\n", warm.with_image,
                warm.status.at("photons").value("cache", "?").c_str());

    // 0. Submit to the first full-frame image of a progressive job on a cache hit: a new view
    // each time (so that the irradiance cache is built: its prepass is what the preview does
    // not wait for).
    std::vector<double> preview_event, preview_png, preview_pass;
    const int preview_runs = std::max(repetitions, 5);
    for (int r = 0; r < preview_runs; ++r) {
        const PreviewTimes t = submit_and_watch_preview(client, make_job(view(-0.5 - 0.25 * r)));
        if (t.status.at("photons").value("cache", "") != "hit")
            std::fprintf(stderr, "  warning: no cache hit\n");
        preview_event.push_back(t.last_preview_event);
        preview_png.push_back(t.preview_png);
        preview_pass.push_back(t.status.at("timings").value("preview", 0.0));
    }
    std::printf("\n0. submit -> first full-frame image of a progressive job on a photon-map cache hit\n");
    std::printf("   (new camera view, %d runs, medians; goal 150 ms)\n", preview_runs);
    std::printf("   last preview tile event (the frame covered)   %.3f s\n", median(preview_event));
    std::printf("   preview.png of the whole frame received       %.3f s   <- time to the first image\n",
                median(preview_png));
    std::printf("   of which the preview pass (server-side)       %.3f s\n", median(preview_pass));

    // 1. Submit to first tile on a cache hit: a new camera view each time.
    std::vector<double> first_tile, pre_render;
    for (int r = 0; r < repetitions; ++r) {
        const StreamTimes t = submit_and_stream(client, make_job(view(0.5 + 0.25 * r)));
        if (t.status.at("photons").value("cache", "") != "hit")
            std::fprintf(stderr, "  warning: no cache hit\n");
        first_tile.push_back(t.first_tile);
        const json& timings = t.status.at("timings");
        double before_tiles = 0.0;
        for (const char* pass :
             {"scene", "acceleration", "photon_tracing", "photon_kdtree", "preview", "irradiance_cache"})
            before_tiles += timings.value(pass, 0.0);
        pre_render.push_back(before_tiles);
    }
    std::printf("\n1. submit -> first final tile on a photon-map cache hit (new camera view)\n");
    std::printf(
        "   median %.3f s; of which passes before the tile pass (scene, acceleration, photon\n"
        "   lookup, preview, irradiance cache) %.3f s, queue + first tile + HTTP %.3f s\n",
        median(first_tile), median(pre_render), median(first_tile) - median(pre_render));

    // 2. Overhead: direct run_job (+ EXR write, as photond render) vs the daemon with the stream,
    // without the progressive preview, which `photond render` does not render.
    const auto job = protocol::parse_job(make_job(view(1.0), false));
    std::vector<double> direct, daemon_stream, daemon_image, daemon_pipeline, daemon_writing;
    for (int r = 0; r < repetitions; ++r) {
        service::PipelineOptions direct_options;
        direct_options.photon_maps = &photon_maps;  // the same warm cache as the daemon's
        const Clock::time_point start = Clock::now();
        auto result = service::run_job(*job, *device, direct_options);
        ExrWriteOptions exr;
        exr.tile_size = job->image.tile_size;
        if (!result || !write_exr(dir / "direct.exr", result->layers, exr)) {
            std::fprintf(stderr, "http_bench: direct render failed\n");
            return 1;
        }
        direct.push_back(seconds_since(start));

        const StreamTimes t = submit_and_stream(client, make_job(view(1.0), false));
        daemon_stream.push_back(t.last_byte);
        daemon_image.push_back(t.with_image);
        daemon_pipeline.push_back(t.status.at("statistics").at("total_seconds").get<double>());
        daemon_writing.push_back(t.status.at("timings").value("writing", 0.0));
        if (t.tiles != 256) std::fprintf(stderr, "  warning: %zu tiles streamed\n", t.tiles);
    }
    const double d = median(direct), s = median(daemon_stream), i = median(daemon_image);
    std::printf("\n2. HTTP and streaming overhead (same job, warm photon cache, medians)\n");
    std::printf("   direct run_job + EXR write        %.3f s\n", d);
    std::printf("   daemon pipeline (server-side)      %.3f s\n", median(daemon_pipeline));
    std::printf("   daemon POST -> last tile byte      %.3f s   overhead %+.2f %%\n", s,
                100.0 * (s - d) / d);
    std::printf("   daemon POST -> image.exr received  %.3f s   overhead %+.2f %%  (goal < 2 %%)\n",
                i, 100.0 * (i - d) / d);
    // The same comparison inside one run: the daemon's wall time against its own pipeline's, so
    // that the run-to-run noise of the render (about 1 %) drops out. What is left is queue
    // pickup, the EXR write, and HTTP.
    const double p = median(daemon_pipeline);
    const double w = median(daemon_writing);
    std::printf(
        "   daemon wall - its pipeline         %.3f s   = %.2f %% of the render, of which\n", i - p,
        100.0 * (i - p) / p);
    std::printf("     EXR and status written            %.3f s\n", w);
    std::printf("     queue, HTTP and streaming         %.3f s   = %.2f %% of the render\n",
                i - p - w, 100.0 * (i - p - w) / p);

    jobs.shutdown();
    server.stop();
    serving.join();
    std::error_code ignored;
    fs::remove_all(dir, ignored);
    return 0;
}
