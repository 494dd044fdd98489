// The job manager through the real daemon: cancellation mid-render, clients that hang up in the
// middle of a stream, 50 concurrent status and event clients, priorities, and what a running
// job serves.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <mutex>
#include <thread>

#include "core/image/exr_io.h"
#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::chrono::seconds kStreamTimeout(60);  // no job here streams for longer

json path_job(int width, int height, int spp, int priority = 50) {
    return {{"scene", {{"builtin", "cornell-box"}}},
            {"integrator", "path"},
            {"priority", priority},
            {"image", {{"width", width}, {"height", height}, {"spp", spp}, {"tile_size", 16}}}};
}

class DaemonJobs : public ::testing::Test {
protected:
    TempDir dir_{"daemon_jobs"};
};

TEST_F(DaemonJobs, CancelMidRenderStopsWithinAboutATile) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    // About 6 s of rendering on 2 cores, 192 tiles.
    const HttpResponse submitted = client.post("/v1/jobs", path_job(256, 192, 64).dump());
    ASSERT_EQ(submitted.status, 202);
    const std::string id = submitted.json_body().at("id");

    json first_tile;
    double cancel_seconds = -1.0;
    const std::vector<SseEvent> events = follow_events(client, id, [&](const SseEvent& e) {
        // The first final tile: a progressive job's preview tiles come first, in the preview pass.
        if (e.type != "tile" || e.data.value("preview", false) || !first_tile.is_null()) return true;
        first_tile = e.data;
        // While rendering: a finished tile is served, the image is not ready, the preview is.
        const HttpResponse tile = client.get(e.data.at("url"));
        EXPECT_EQ(tile.status, 200);
        EXPECT_EQ(tile.header("content-type"), "image/x-exr");
        const HttpResponse image = client.get("/v1/jobs/" + id + "/image.exr");
        EXPECT_EQ(image.status, 409);
        EXPECT_NE(image.body.find("wait=true"), std::string::npos) << image.body;
        const HttpResponse preview = client.get("/v1/jobs/" + id + "/preview.png");
        EXPECT_EQ(preview.status, 200);
        EXPECT_EQ(preview.body.substr(1, 3), "PNG");
        const json running = client.get("/v1/jobs/" + id).json_body();
        EXPECT_EQ(running.at("state"), "running");
        EXPECT_EQ(running.at("pass"), "render");

        const auto start = Clock::now();
        const HttpResponse cancelled = client.request("DELETE", "/v1/jobs/" + id);
        const json status = wait_for_status(client, id, is_terminal_state, std::chrono::seconds(5));
        cancel_seconds = std::chrono::duration<double>(Clock::now() - start).count();
        EXPECT_TRUE(cancelled.status == 200 || cancelled.status == 202) << cancelled.body;
        EXPECT_EQ(status.at("state"), "cancelled");
        return true;  // read on: the stream must end by itself
    }, kStreamTimeout);
    ASSERT_FALSE(first_tile.is_null());
    EXPECT_GE(cancel_seconds, 0.0);
    EXPECT_LT(cancel_seconds, 2.0);
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back().type, "cancelled");

    const json status = client.get("/v1/jobs/" + id).json_body();
    EXPECT_EQ(status.at("state"), "cancelled");
    EXPECT_LT(status.at("progress").at("tiles_done").get<int>(), 192);
    EXPECT_TRUE(status.at("statistics").at("cancelled").get<bool>());
    // Its pixels are freed: no tiles, no image.
    EXPECT_EQ(client.get(first_tile.at("url")).status, 404);
    EXPECT_EQ(client.get("/v1/jobs/" + id + "/image.exr?wait=true").status, 409);
    EXPECT_EQ(client.request("DELETE", "/v1/jobs/" + id).status, 200);  // again: harmless

    // A queued job is cancelled at once; the daemon goes on with the next job.
    const std::string blocker =
        client.post("/v1/jobs", path_job(256, 192, 64).dump()).json_body().at("id");
    const std::string queued =
        client.post("/v1/jobs", path_job(32, 32, 1).dump()).json_body().at("id");
    const HttpResponse dequeued = client.request("DELETE", "/v1/jobs/" + queued);
    EXPECT_EQ(dequeued.status, 200);
    EXPECT_EQ(dequeued.json_body().at("state"), "cancelled");
    client.request("DELETE", "/v1/jobs/" + blocker);
    const std::string after =
        client.post("/v1/jobs", path_job(32, 32, 1).dump()).json_body().at("id");
    EXPECT_EQ(wait_for_status(client, after, is_terminal_state).at("state"), "done");
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

TEST_F(DaemonJobs, ClientsHangingUpMidStreamDoNotDisturbTheJob) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const json job = path_job(128, 96, 24);  // 48 tiles, about a second
    const std::string id = client.post("/v1/jobs", job.dump()).json_body().at("id");

    // An SSE client that leaves after the first tile event.
    const std::vector<SseEvent> partial =
        follow_events(client, id, [](const SseEvent& e) { return e.type != "tile"; }, kStreamTimeout);
    EXPECT_EQ(partial.back().type, "tile");
    // A multipart client that leaves in the middle of its first part.
    HttpResponse response;
    size_t received = 0;
    client.stream("GET", "/v1/jobs/" + id + "/tiles", {}, {}, std::chrono::seconds(30), response,
                  [&](std::string_view data) {
                      received += data.size();
                      return received < 100;
                  });
    EXPECT_EQ(response.status, 200);
    EXPECT_GE(received, 100u);
    // Several more that hang up at once.
    for (int i = 0; i < 5; ++i) {
        HttpResponse r;
        client.stream("GET", "/v1/jobs/" + id + (i % 2 ? "/tiles" : "/events"), {}, {},
                      std::chrono::seconds(30), r, [](std::string_view) { return false; });
    }

    const json status = wait_for_status(client, id, is_terminal_state);
    EXPECT_EQ(status.at("state"), "done") << status.dump();
    EXPECT_EQ(status.at("progress").at("tiles_done"), 48);
    // A full stream afterwards has every tile and its closing boundary.
    const HttpResponse stream = client.get("/v1/jobs/" + id + "/tiles");
    const std::string type = stream.header("content-type");
    bool closed = false;
    const auto parts = parse_multipart(stream.body, type.substr(type.find('=') + 1), &closed);
    EXPECT_EQ(parts.size(), 48u);
    EXPECT_TRUE(closed);
    // And the daemon serves new work as before.
    const std::string next =
        client.post("/v1/jobs", path_job(32, 32, 1).dump()).json_body().at("id");
    EXPECT_EQ(wait_for_status(client, next, is_terminal_state).at("state"), "done");
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

TEST_F(DaemonJobs, FiftyConcurrentStatusAndEventClientsWhileAJobRenders) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string id =
        client.post("/v1/jobs", path_job(160, 120, 32).dump()).json_body().at("id");
    const int tiles = 10 * 8;

    std::atomic<int> failures{0};
    std::mutex mutex;
    std::vector<std::string> messages;
    auto fail = [&](const std::string& message) {
        ++failures;
        std::lock_guard lock(mutex);
        messages.push_back(message);
    };
    std::vector<std::thread> threads;
    for (int i = 0; i < 25; ++i) {
        threads.emplace_back([&, i] {  // event clients: each sees the whole history and the end
            const std::vector<SseEvent> events =
                follow_events(client, id, {}, kStreamTimeout);
            int tile_events = 0;
            for (size_t k = 0; k < events.size(); ++k) {
                if (events[k].id != k + 1)
                    return fail("event client " + std::to_string(i) + ": ids not consecutive");
                tile_events += events[k].type == "tile" && !events[k].data.value("preview", false);
            }
            if (events.empty() || events.back().type != "done")
                return fail("event client " + std::to_string(i) + ": no done");
            if (tile_events != tiles)
                return fail("event client " + std::to_string(i) + ": " +
                            std::to_string(tile_events) + " tiles");
        });
        threads.emplace_back([&, i] {  // status clients: progress never goes back
            uint64_t last = 0;
            for (;;) {
                const HttpResponse r = client.get("/v1/jobs/" + id);
                if (r.status != 200)
                    return fail("status client " + std::to_string(i) + ": " +
                                std::to_string(r.status));
                const json s = r.json_body();
                const uint64_t done = s.at("progress").at("tiles_done");
                if (done < last)
                    return fail("status client " + std::to_string(i) + ": progress went back");
                last = done;
                if (is_terminal_state(s)) {
                    if (s.at("state") != "done")
                        fail("status client: state " + s.at("state").get<std::string>());
                    return;
                }
                std::this_thread::sleep_for(std::chrono::milliseconds(50));
            }
        });
    }
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(failures.load(), 0) << (messages.empty() ? "" : messages.front());
    EXPECT_EQ(client.get("/healthz").status, 200);
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

json tiny_job(int seed) {
    return {{"scene", {{"builtin", "cornell-box"}}},
            {"integrator", "direct"},
            {"seed", seed},
            {"image", {{"width", 1}, {"height", 1}, {"spp", 1}}}};
}

TEST_F(DaemonJobs, FinishedJobsDoNotGrowTheDaemon) {
    // Each finished job's scene and buffers are freed, but glibc kept the freed memory mapped:
    // 1.45 MB of RSS per 1x1 job (300 jobs: +447 MB). Then the job records stayed in memory:
    // about 57 kB per job (status with statistics, event history). Only the last few finished
    // jobs keep their records in memory now; the rest are read back from disk when asked for.
    Daemon daemon(dir_.path() / "cache", {"--max-queued", "1000", "--finished-jobs-in-memory", "8"});
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const auto run_jobs = [&](int first, int count) {
        std::string last;
        for (int i = first; i < first + count; ++i) {
            const HttpResponse r = client.post("/v1/jobs", tiny_job(i).dump());
            EXPECT_EQ(r.status, 202) << r.body;
            last = r.json_body().at("id");
        }
        // A hang guard, not a time goal: 300 jobs take about 20 s alone and over 30 s (the
        // default wait) beside the heaviest tests of a parallel ctest.
        EXPECT_EQ(wait_for_status(client, last, is_terminal_state, std::chrono::seconds(180)).at("state"), "done");
    };
    // The worker frees a job's scene and trims the heap after the job is announced done: the RSS
    // is read once it stops changing.
    const auto settled_kb = [&] {
        long last = daemon.resident_kb();
        for (int i = 0; i < 40; ++i) {
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
            const long now = daemon.resident_kb();
            if (now == last) break;
            last = now;
        }
        return last;
    };
    run_jobs(0, 150);  // warm up: threads, the allocator's arenas (about 2 MB), the device, the records kept
    const long before = settled_kb();
    run_jobs(150, 300);
    const long after = settled_kb();
    ASSERT_GT(before, 0);
    const double per_job_kb = static_cast<double>(after - before) / 300.0;
    std::printf("daemon RSS %ld kB -> %ld kB over 300 finished jobs: %.1f kB per job\n", before, after, per_job_kb);
    // The records were 57 kB each (17 MB here); the allocator's arenas move by about 1-2 MB.
    EXPECT_LT(per_job_kb, 12.0);
}

TEST_F(DaemonJobs, FinishedJobsOutOfMemoryAreReadBackWhole) {
    // One finished record in memory: every other job is answered from its files, as it was.
    Daemon daemon(dir_.path() / "cache", {"--finished-jobs-in-memory", "1"});
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const json first_job = {{"scene", {{"builtin", "cornell-box"}}},
                            {"integrator", "direct"},
                            {"image", {{"width", 40}, {"height", 20}, {"spp", 1}, {"tile_size", 16}}}};
    const HttpResponse submitted = client.post("/v1/jobs", first_job.dump(), {{"Idempotency-Key", "first"}});
    ASSERT_EQ(submitted.status, 202) << submitted.body;
    const std::string first = submitted.json_body().at("id");
    const json first_done = wait_for_status(client, first, is_terminal_state);
    ASSERT_EQ(first_done.at("state"), "done");
    const std::string first_image = client.get("/v1/jobs/" + first + "/image.exr").body;
    const std::vector<SseEvent> live_events = parse_sse(client.get("/v1/jobs/" + first + "/events").body);
    std::vector<std::string> ids = {first};
    for (int i = 1; i <= 3; ++i) {
        ids.push_back(client.post("/v1/jobs", tiny_job(i).dump()).json_body().at("id"));
        ASSERT_EQ(wait_for_status(client, ids.back(), is_terminal_state).at("state"), "done");
    }
    // Removing the second job's status from disk shows that its record left memory: it cannot be
    // read back, and the daemon says so (503: the files may come back) instead of making one up.
    const fs::path status_file = dir_.path() / "cache" / "jobs" / ids[1] / "status.json";
    fs::rename(status_file, status_file.string() + ".away");
    const HttpResponse lost = client.get("/v1/jobs/" + ids[1]);
    EXPECT_EQ(lost.status, 503) << lost.body;
    EXPECT_NE(lost.body.find("cannot be read back"), std::string::npos) << lost.body;
    EXPECT_EQ(client.get("/v1/jobs").json_body().at("jobs").size(), 3u);  // left out, and logged
    fs::rename(status_file.string() + ".away", status_file);

    // The first job as it was: status with statistics, events ending in "done", tiles, image,
    // preview, the Idempotency-Key.
    const json status = client.get("/v1/jobs/" + first).json_body();
    EXPECT_EQ(status.at("state"), "done");
    EXPECT_EQ(status.at("statistics"), first_done.at("statistics"));
    EXPECT_EQ(status.at("timings"), first_done.at("timings"));
    EXPECT_EQ(status.at("job"), first_done.at("job"));
    const std::vector<SseEvent> events = parse_sse(client.get("/v1/jobs/" + first + "/events").body);
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back().type, "done");
    EXPECT_EQ(events.back().data.at("statistics"), live_events.back().data.at("statistics"));
    size_t tile_events = 0;
    for (const SseEvent& e : events) tile_events += e.type == "tile" && !e.data.value("preview", false);
    EXPECT_EQ(tile_events, 6u);  // 3 x 2 tiles of 16 px
    // The live stream's last id and tile order (its pass and progress events are not rebuilt):
    // a stream resumed where it was goes on.
    EXPECT_EQ(events.back().id, live_events.back().id);
    const auto tile_order = [](const std::vector<SseEvent>& stream) {
        std::vector<std::pair<int, int>> order;
        for (const SseEvent& e : stream)
            if (e.type == "tile" && !e.data.value("preview", false))  // previews are not kept
                order.emplace_back(e.data.at("tx"), e.data.at("ty"));
        return order;
    };
    EXPECT_EQ(tile_order(events), tile_order(live_events));
    const std::string last_but_one = std::to_string(live_events.back().id - 1);
    const std::vector<SseEvent> resumed =
        parse_sse(client.get("/v1/jobs/" + first + "/events", {{"Last-Event-ID", last_but_one}}).body);
    ASSERT_EQ(resumed.size(), 1u);
    EXPECT_EQ(resumed[0].type, "done");
    EXPECT_EQ(resumed[0].id, live_events.back().id);
    EXPECT_EQ(client.get("/v1/jobs/" + first + "/image.exr").body, first_image);
    const HttpResponse tile = client.get("/v1/jobs/" + first + "/tiles/2/1.exr");
    ASSERT_EQ(tile.status, 200);
    const auto decoded = decode_tile_exr({reinterpret_cast<const uint8_t*>(tile.body.data()), tile.body.size()});
    ASSERT_TRUE(decoded.has_value());
    EXPECT_EQ(decoded->rect, (PixelRect{32, 16, 40, 20}));
    EXPECT_EQ(client.get("/v1/jobs/" + first + "/preview.png").status, 200);
    const HttpResponse again = client.post("/v1/jobs", first_job.dump(), {{"Idempotency-Key", "first"}});
    EXPECT_EQ(again.json_body().at("id"), first) << again.body;
    EXPECT_EQ(client.post("/v1/jobs", tiny_job(9).dump(), {{"Idempotency-Key", "first"}}).status, 409);

    // The list, newest first, with the states of jobs in memory and on disk alike.
    const HttpResponse cancelled = client.request("DELETE", "/v1/jobs/" + ids[2]);
    EXPECT_EQ(cancelled.status, 409) << cancelled.body;  // done: nothing to cancel, read back or not
    const json list = client.get("/v1/jobs").json_body().at("jobs");
    ASSERT_EQ(list.size(), 4u) << list.dump();
    for (size_t i = 0; i < 4; ++i) EXPECT_EQ(list[i].at("id"), ids[3 - i]);
    for (size_t i = 0; i < 4; ++i) EXPECT_EQ(list[i].at("state"), "done");
    EXPECT_FALSE(list[3].contains("statistics"));
    EXPECT_EQ(list[3].at("job"), first_done.at("job"));
    EXPECT_EQ(client.get("/v1/jobs?state=done").json_body().at("jobs").size(), 4u);
    EXPECT_EQ(client.get("/v1/jobs?state=failed").json_body().at("jobs").size(), 0u);
    const std::string metrics = client.get("/metrics").body;
    EXPECT_NE(metrics.find("photond_jobs{state=\"done\"} 4\n"), std::string::npos) << metrics;
}

TEST_F(DaemonJobs, HigherPriorityRunsFirstThenArrivalOrder) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string blocker =
        client.post("/v1/jobs", path_job(128, 96, 24).dump()).json_body().at("id");
    wait_for_status(client, blocker,
                    [](const json& s) { return s.value("state", "") == "running"; });
    const std::string low =
        client.post("/v1/jobs", path_job(16, 16, 1, 10).dump()).json_body().at("id");
    const std::string high =
        client.post("/v1/jobs", path_job(16, 16, 1, 90).dump()).json_body().at("id");
    const std::string high_later =
        client.post("/v1/jobs", path_job(16, 16, 1, 90).dump()).json_body().at("id");
    // Newest first in the list.
    const json list = client.get("/v1/jobs?state=queued").json_body().at("jobs");
    ASSERT_EQ(list.size(), 3u);
    EXPECT_EQ(list[0].at("id"), high_later);
    EXPECT_EQ(list[2].at("id"), low);

    const json s_low = wait_for_status(client, low, is_terminal_state);
    const json s_high = client.get("/v1/jobs/" + high).json_body();
    const json s_later = client.get("/v1/jobs/" + high_later).json_body();
    ASSERT_EQ(s_low.at("state"), "done");
    ASSERT_EQ(s_high.at("state"), "done");
    ASSERT_EQ(s_later.at("state"), "done");
    // RFC 3339 timestamps of one format compare as strings.
    EXPECT_LE(s_high.at("finished_at").get<std::string>(),
              s_later.at("started_at").get<std::string>());
    EXPECT_LE(s_later.at("finished_at").get<std::string>(),
              s_low.at("started_at").get<std::string>());
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

}  // namespace
}  // namespace photond::test
