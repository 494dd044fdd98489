// `photond serve` end to end, against the real daemon on a free loopback port: submit, events,
// single tiles, the tile stream and the final image (byte for byte what `photond render` writes
// for the same job), SSE resume, Idempotency-Key, and the operational endpoints.
#include <gtest/gtest.h>

#include <set>

#include "core/image/exr_io.h"
#include "core/image/png_preview.h"
#include "protocol/job.h"
#include "server/routes.h"
#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

// Tiny but real: a photon-map render of the Cornell box with both maps, 12 tiles of 16 pixels.
const json kJob = {{"scene", {{"builtin", "cornell-box"}}},
                   {"integrator", "photon-map"},
                   {"image", {{"width", 64}, {"height", 48}, {"spp", 1}, {"tile_size", 16}}},
                   {"photons", {{"global", 2000}, {"caustic", 1000}}},
                   {"seed", 7}};

std::span<const uint8_t> bytes_of(const std::string& s) {
    return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

/// Reads the whole SSE stream of a job (it ends after the job's last event).
std::vector<SseEvent> read_events(const HttpClient& client, const std::string& id,
                                  const Headers& headers = {}, const std::string& query = "") {
    const HttpResponse response =
        client.request("GET", "/v1/jobs/" + id + "/events" + query, {}, headers);
    EXPECT_EQ(response.status, 200);
    EXPECT_EQ(response.header("content-type"), "text/event-stream");
    return parse_sse(response.body);
}

class DaemonApi : public ::testing::Test {
protected:
    TempDir dir_{"daemon_api"};
};

TEST_F(DaemonApi, SubmitEventsTilesAndImageEqualToPhotondRender) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpClient client = daemon.client();

    const HttpResponse submitted =
        client.post("/v1/jobs", kJob.dump(), {{"Content-Type", "application/json"}});
    ASSERT_EQ(submitted.status, 202) << submitted.body;
    const json accepted = submitted.json_body();
    const std::string id = accepted.at("id");
    EXPECT_EQ(submitted.header("location"), "/v1/jobs/" + id);
    EXPECT_TRUE(accepted.at("state") == "queued" || accepted.at("state") == "running");
    EXPECT_EQ(accepted.at("progress").at("tiles_total"), 12);

    // Events: the history, then live, ending after "done"; ids count up from 1.
    const std::vector<SseEvent> events = read_events(client, id);
    ASSERT_FALSE(events.empty());
    for (size_t i = 0; i < events.size(); ++i) EXPECT_EQ(events[i].id, i + 1);
    EXPECT_EQ(events.front().type, "state");
    EXPECT_EQ(events.front().data.at("state"), "queued");
    EXPECT_EQ(events.back().type, "done");
    EXPECT_EQ(events.back().data.at("state"), "done");
    std::vector<SseEvent> tiles;
    double last_fraction = 0.0;
    bool saw_running = false;
    for (const SseEvent& e : events) {
        if (e.type == "tile" && !e.data.value("preview", false)) tiles.push_back(e);  // final tiles
        if (e.type == "state" && e.data.at("state") == "running") saw_running = true;
        if (e.type == "progress") {
            EXPECT_GE(e.data.at("fraction").get<double>(), last_fraction);
            last_fraction = e.data.at("fraction");
        }
    }
    EXPECT_TRUE(saw_running);
    EXPECT_DOUBLE_EQ(last_fraction, 1.0);
    ASSERT_EQ(tiles.size(), 12u);

    // Each tile on its own: a small EXR whose data window is the tile, display window the frame.
    std::map<std::pair<int, int>, std::string> tile_bytes;
    Image assembled(64, 48);
    for (const SseEvent& t : tiles) {
        const HttpResponse tile = client.get(t.data.at("url"));
        ASSERT_EQ(tile.status, 200) << tile.body;
        EXPECT_EQ(tile.header("content-type"), "image/x-exr");
        const auto rect = t.data.at("rect");
        EXPECT_EQ(tile.header("x-tile-rect"), std::to_string(rect[0].get<int>()) + "," +
                                                  std::to_string(rect[1].get<int>()) + "," +
                                                  std::to_string(rect[2].get<int>()) + "," +
                                                  std::to_string(rect[3].get<int>()));
        const auto decoded = decode_tile_exr(bytes_of(tile.body));
        ASSERT_TRUE(decoded.has_value()) << decoded.error().message;
        EXPECT_EQ(decoded->frame_width, 64);
        EXPECT_EQ(decoded->frame_height, 48);
        EXPECT_EQ(decoded->rect, (PixelRect{rect[0], rect[1], rect[2], rect[3]}));
        assembled.paste(decoded->tile.beauty, decoded->rect.x0, decoded->rect.y0);
        tile_bytes[{t.data.at("tx"), t.data.at("ty")}] = tile.body;
    }

    // The multipart stream of a finished job: every tile, the same bytes, then the closing
    // boundary.
    const HttpResponse stream = client.get("/v1/jobs/" + id + "/tiles");
    ASSERT_EQ(stream.status, 200);
    const std::string type = stream.header("content-type");
    ASSERT_EQ(type.rfind("multipart/mixed; boundary=", 0), 0u) << type;
    bool closed = false;
    const auto parts = parse_multipart(stream.body, type.substr(type.find('=') + 1), &closed);
    EXPECT_TRUE(closed);
    ASSERT_EQ(parts.size(), 12u);
    for (const MultipartPart& part : parts) {
        EXPECT_EQ(part.headers.at("content-type"), "image/x-exr");
        const std::pair<int, int> key{std::stoi(part.headers.at("x-tile-x")),
                                      std::stoi(part.headers.at("x-tile-y"))};
        ASSERT_TRUE(tile_bytes.contains(key));
        EXPECT_EQ(part.body, tile_bytes[key]);
        EXPECT_FALSE(part.headers.at("x-tile-rect").empty());
    }

    // The final image: the same bytes as `photond render` of the same job.
    const HttpResponse image = client.get("/v1/jobs/" + id + "/image.exr?wait=true");
    ASSERT_EQ(image.status, 200) << image.body;
    EXPECT_EQ(image.header("content-type"), "image/x-exr");
    write_file(dir_.path() / "job.json", kJob.dump());
    const auto [code, output] =
        run_command(kPhotondBinary + " render --job " + (dir_.path() / "job.json").string() +
                    " --threads 1 --quiet -o " + (dir_.path() / "cli.exr").string());
    ASSERT_EQ(code, 0) << output;
    const std::string cli = read_file(dir_.path() / "cli.exr");
    ASSERT_FALSE(cli.empty());
    EXPECT_EQ(image.body.size(), cli.size());
    EXPECT_TRUE(image.body == cli) << "the daemon's EXR differs from photond render's";

    // The tiles assemble into exactly the final image.
    const auto final_image = decode_exr(bytes_of(image.body));
    ASSERT_TRUE(final_image.has_value());
    EXPECT_TRUE(final_image->beauty == assembled);

    // Status: done, all tiles, the plan, timings and a photon-map cache miss (first render).
    const json status = client.get("/v1/jobs/" + id).json_body();
    EXPECT_EQ(status.at("state"), "done");
    EXPECT_EQ(status.at("progress").at("tiles_done"), 12);
    EXPECT_DOUBLE_EQ(status.at("progress").at("fraction").get<double>(), 1.0);
    EXPECT_EQ(status.at("photons").at("cache"), "miss");
    EXPECT_GT(status.at("timings").at("photon_tracing").get<double>(), 0.0);
    EXPECT_GT(status.at("timings").at("render").get<double>(), 0.0);
    EXPECT_FALSE(status.at("plan").empty());
    EXPECT_EQ(status.at("job").at("seed"), 7);
    EXPECT_FALSE(status.at("finished_at").get<std::string>().empty());

    const HttpResponse preview = client.get("/v1/jobs/" + id + "/preview.png");
    ASSERT_EQ(preview.status, 200);
    EXPECT_EQ(preview.body.substr(1, 3), "PNG");

    const json list = client.get("/v1/jobs").json_body();
    ASSERT_EQ(list.at("jobs").size(), 1u);
    EXPECT_EQ(list.at("jobs")[0].at("id"), id);

    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

TEST_F(DaemonApi, AovLayersReachTilesTheStreamAndTheImage) {
    // The job's AOVs as named EXR layers in every tile, every part of the multipart stream and the
    // final image, which is the same bytes as `photond render` of the job; the radiance parts sum
    // to the beauty pass.
    json job = kJob;
    job["output"] = {{"pixel_type", "float"}, {"aovs", {"emission", "direct", "indirect", "caustic", "normal"}}};
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpClient client = daemon.client();
    const HttpResponse submitted = client.post("/v1/jobs", job.dump(), {{"Content-Type", "application/json"}});
    ASSERT_EQ(submitted.status, 202) << submitted.body;
    const std::string id = submitted.json_body().at("id");
    const HttpResponse image = client.get("/v1/jobs/" + id + "/image.exr?wait=true");
    ASSERT_EQ(image.status, 200) << image.body;
    const auto final_image = decode_exr(bytes_of(image.body));
    ASSERT_TRUE(final_image.has_value()) << final_image.error().message;
    std::set<std::string> names;
    for (const auto& [name, layer] : final_image->aovs) names.insert(name);
    EXPECT_EQ(names, (std::set<std::string>{"emission", "direct", "indirect", "caustic", "normal"}));
    double worst = 0.0;
    for (size_t p = 0; p < final_image->beauty.pixel_count(); ++p) {
        Color sum(0.0f);
        for (const char* part : {"emission", "direct", "indirect", "caustic"})
            sum += final_image->find_aov(part)->pixels()[p];
        const Color beauty = final_image->beauty.pixels()[p];
        for (int ch = 0; ch < 3; ++ch)
            worst = std::max(worst, double(std::abs(sum[ch] - beauty[ch])) / std::max(1.0, double(beauty[ch])));
    }
    EXPECT_LT(worst, 1e-5);

    // A tile: every layer, equal to the final image's rectangle.
    const HttpResponse tile = client.get("/v1/jobs/" + id + "/tiles/1/2.exr");
    ASSERT_EQ(tile.status, 200) << tile.body;
    const auto decoded = decode_tile_exr(bytes_of(tile.body));
    ASSERT_TRUE(decoded.has_value()) << decoded.error().message;
    EXPECT_EQ(decoded->rect, (PixelRect{16, 32, 32, 48}));
    ASSERT_EQ(decoded->tile.aovs.size(), 5u);
    EXPECT_TRUE(decoded->tile.beauty == final_image->beauty.copy_rect(decoded->rect));
    for (const auto& [name, layer] : decoded->tile.aovs)
        EXPECT_TRUE(layer == final_image->find_aov(name)->copy_rect(decoded->rect)) << name;

    // The multipart stream: the same tile bytes.
    const HttpResponse stream = client.get("/v1/jobs/" + id + "/tiles");
    ASSERT_EQ(stream.status, 200);
    const std::string type = stream.header("content-type");
    const auto parts = parse_multipart(stream.body, type.substr(type.find('=') + 1));
    ASSERT_EQ(parts.size(), 12u);
    bool found = false;
    for (const MultipartPart& part : parts) {
        if (part.headers.at("x-tile-x") == "1" && part.headers.at("x-tile-y") == "2") {
            found = true;
            EXPECT_TRUE(part.body == tile.body);
        }
    }
    EXPECT_TRUE(found);

    write_file(dir_.path() / "job.json", job.dump());
    const auto [code, output] =
        run_command(kPhotondBinary + " render --job " + (dir_.path() / "job.json").string() +
                    " --threads 1 --quiet -o " + (dir_.path() / "cli.exr").string());
    ASSERT_EQ(code, 0) << output;
    EXPECT_TRUE(image.body == read_file(dir_.path() / "cli.exr")) << "the daemon's EXR differs from photond render's";
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

TEST_F(DaemonApi, PreviewPngHonoursTheJobsExposure) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    // Float pixels, so that the EXR fetched holds exactly the values the preview is made from.
    json job = {{"scene", {{"builtin", "cornell-box"}}},
                {"integrator", "direct"},
                {"image", {{"width", 32}, {"height", 24}, {"spp", 1}, {"tile_size", 16}}},
                {"output", {{"pixel_type", "float"}}}};
    std::string id;
    auto preview_of = [&](const json& submitted_job, std::string* exr) {
        const HttpResponse submitted = client.post("/v1/jobs", submitted_job.dump());
        EXPECT_EQ(submitted.status, 202) << submitted.body;
        id = submitted.json_body().value("id", "");
        *exr = client.get("/v1/jobs/" + id + "/image.exr?wait=true").body;
        const HttpResponse preview = client.get("/v1/jobs/" + id + "/preview.png");
        EXPECT_EQ(preview.status, 200);
        EXPECT_EQ(preview.header("content-type"), "image/png");
        return preview.body;
    };
    std::string automatic_exr, exposed_exr;
    const std::string automatic = preview_of(job, &automatic_exr);
    job["output"]["exposure_ev"] = 2.5;
    const std::string exposed = preview_of(job, &exposed_exr);
    EXPECT_EQ(automatic_exr, exposed_exr);  // the EXR stays linear radiance
    EXPECT_NE(automatic, exposed);

    const auto image = decode_exr(bytes_of(exposed_exr));
    ASSERT_TRUE(image.has_value()) << image.error().message;
    for (const auto& [png, exposure] :
         {std::pair{exposed, std::optional<float>(2.5f)}, std::pair{automatic, std::optional<float>()}}) {
        auto expected = encode_render_preview(image->beauty, exposure);
        ASSERT_TRUE(expected);
        EXPECT_TRUE(png == std::string(expected->begin(), expected->end()))
            << "exposure " << (exposure ? std::to_string(*exposure) : "automatic");
    }
    // Asked again (now from the file the daemon keeps): the same bytes.
    EXPECT_EQ(client.get("/v1/jobs/" + id + "/preview.png").body, exposed);

    // The field is validated by name.
    for (const json& bad : {json(31), json("bright"), json(nullptr), json::array({1})}) {
        job["output"]["exposure_ev"] = bad;
        const HttpResponse refused = client.post("/v1/jobs", job.dump());
        EXPECT_EQ(refused.status, 422) << bad;
        EXPECT_EQ(refused.json_body().value("field", ""), "output.exposure_ev") << refused.body;
    }
}

TEST_F(DaemonApi, LastEventIdResumesAfterThatEvent) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string id = client.post("/v1/jobs", kJob.dump()).json_body().at("id");
    const std::vector<SseEvent> all = read_events(client, id);
    ASSERT_GT(all.size(), 6u);

    const std::vector<SseEvent> resumed = read_events(client, id, {{"Last-Event-ID", "5"}});
    ASSERT_EQ(resumed.size(), all.size() - 5);
    EXPECT_EQ(resumed.front().id, 6u);
    EXPECT_EQ(resumed.front().type, all[5].type);
    EXPECT_EQ(resumed.back().type, "done");

    const std::vector<SseEvent> by_query =
        read_events(client, id, {}, "?last_event_id=" + std::to_string(all.size() - 1));
    ASSERT_EQ(by_query.size(), 1u);
    EXPECT_EQ(by_query.front().type, "done");

    const HttpResponse bad = client.get("/v1/jobs/" + id + "/events", {{"Last-Event-ID", "seven"}});
    EXPECT_EQ(bad.status, 400);
    EXPECT_EQ(bad.header("content-type"), "application/problem+json");
    EXPECT_EQ(client.get("/v1/jobs/no-such-job/events").status, 404);
}

TEST_F(DaemonApi, IdempotencyKeyReturnsTheSameJob) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const HttpResponse first =
        client.post("/v1/jobs", kJob.dump(), {{"Idempotency-Key", "render-42"}});
    ASSERT_EQ(first.status, 202) << first.body;
    const std::string id = first.json_body().at("id");

    // A retry (even spelled differently: same job after defaults) gets the same job, with 200.
    json same = kJob;
    same["preset"] = "final";
    const HttpResponse retry =
        client.post("/v1/jobs", same.dump(2), {{"Idempotency-Key", "render-42"}});
    EXPECT_EQ(retry.status, 200) << retry.body;
    EXPECT_EQ(retry.json_body().at("id"), id);
    EXPECT_EQ(retry.header("location"), "/v1/jobs/" + id);

    json other = kJob;
    other["seed"] = 8;
    const HttpResponse conflict =
        client.post("/v1/jobs", other.dump(), {{"Idempotency-Key", "render-42"}});
    EXPECT_EQ(conflict.status, 409);
    EXPECT_EQ(conflict.header("content-type"), "application/problem+json");
    EXPECT_NE(conflict.json_body().at("detail").get<std::string>().find(id), std::string::npos);

    const HttpResponse fresh = client.post("/v1/jobs", kJob.dump());
    EXPECT_EQ(fresh.status, 202);
    EXPECT_NE(fresh.json_body().at("id"), id);
    EXPECT_EQ(client.get("/v1/jobs").json_body().at("jobs").size(), 2u);

    // The key survives a restart.
    ASSERT_EQ(daemon.stop(), 0);
    Daemon again(dir_.path() / "cache");
    ASSERT_TRUE(again.started()) << again.log();
    const HttpResponse after =
        again.client().post("/v1/jobs", kJob.dump(), {{"Idempotency-Key", "render-42"}});
    EXPECT_EQ(after.status, 200);
    EXPECT_EQ(after.json_body().at("id"), id);
}

TEST_F(DaemonApi, OpenApiHealthReadinessAndMetrics) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();

    const HttpResponse health = client.get("/healthz");
    EXPECT_EQ(health.status, 200);
    EXPECT_EQ(health.body, "ok\n");
    const HttpResponse ready = client.get("/readyz");
    EXPECT_EQ(ready.status, 200);
    EXPECT_EQ(ready.json_body().at("status"), "ready");

    const json openapi = client.get("/v1/openapi.json").json_body();
    EXPECT_EQ(openapi.at("openapi"), "3.1.0");
    EXPECT_EQ(openapi.at("components").at("schemas").at("Job"), protocol::job_json_schema());
    for (const char* schema : {"JobStatus", "JobEvent", "Problem", "SceneInfo"})
        EXPECT_TRUE(openapi.at("components").at("schemas").contains(schema)) << schema;
    // The document's operations are the route table's, no more and no fewer.
    size_t documented = 0;
    for (const auto& [path, operations] : openapi.at("paths").items())
        documented += operations.size();
    EXPECT_EQ(documented, service::api_routes().size());
    for (const service::Route& route : service::api_routes()) {
        const std::string method = lower(route.method);
        ASSERT_TRUE(openapi["paths"].contains(route.path) &&
                    openapi["paths"][route.path].contains(method))
            << route.method << " " << route.path;
        EXPECT_EQ(openapi["paths"][route.path][method].at("operationId"), route.operation_id);
    }
    EXPECT_EQ(openapi["paths"]["/v1/jobs"]["post"]["requestBody"]["content"]["application/json"]
                     ["schema"]["$ref"],
              "#/components/schemas/Job");

    const std::string id = client.post("/v1/jobs", kJob.dump()).json_body().at("id");
    ASSERT_EQ(client.get("/v1/jobs/" + id + "/image.exr?wait=true").status, 200);
    const HttpResponse metrics = client.get("/metrics");
    ASSERT_EQ(metrics.status, 200);
    EXPECT_EQ(metrics.header("content-type").rfind("text/plain", 0), 0u);
    const std::string& text = metrics.body;
    for (const char* line :
         {"# TYPE photond_jobs gauge", "photond_jobs{state=\"done\"} 1",
          "photond_jobs{state=\"queued\"} 0", "# TYPE photond_jobs_submitted_total counter",
          "photond_jobs_submitted_total 1", "photond_tiles_rendered_total 12",
          "photond_photon_cache_misses_total 1", "photond_photon_cache_hits_total 0",
          "photond_queue_jobs 0", "# TYPE photond_pass_duration_seconds histogram",
          "photond_pass_duration_seconds_count{pass=\"render\"} 1", "# HELP photond_rays_total",
          "# TYPE photond_photon_cache_bytes gauge"})
        EXPECT_NE(text.find(line), std::string::npos) << line << "\n" << text;
    EXPECT_EQ(text.find("photond_rays_total 0\n"), std::string::npos);
}

}  // namespace
}  // namespace photond::test
