// What the daemon keeps: the photon-map cache (a second view of a scene skips photon tracing;
// maps move between daemons by export and import; a corrupt file on disk is set aside and
// rebuilt), the render caches (a view's irradiance cache built once for its jobs and regions, and
// moved between daemons), finished jobs across a restart, jobs interrupted by a clean shutdown or killed
// (resumed from their tiles, failed as poison after three deaths), and uploaded scenes rendered by
// content id.
#include <gtest/gtest.h>

#include <set>

#include "core/image/exr_assemble.h"
#include "core/image/exr_io.h"
#include "core/util/sha256.h"
#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

json photon_job(json camera = nullptr) {
    json job = {{"scene", {{"builtin", "cornell-box"}}},
                {"integrator", "photon-map"},
                {"image", {{"width", 48}, {"height", 32}, {"spp", 1}, {"tile_size", 16}}},
                {"photons", {{"global", 3000}, {"caustic", 2000}, {"seed", 3}}}};
    if (!camera.is_null()) job["camera"] = std::move(camera);
    return job;
}

const json kOtherView = {
    {"look_from", {1.5, 3.0, 9.0}}, {"look_at", {0.0, 2.0, 0.0}}, {"vfov_deg", 45}};

json render(const HttpClient& client, const json& job) {
    const HttpResponse submitted = client.post("/v1/jobs", job.dump());
    EXPECT_EQ(submitted.status, 202) << submitted.body;
    return wait_for_status(client, submitted.json_body().at("id"), is_terminal_state);
}

class DaemonCache : public ::testing::Test {
protected:
    TempDir dir_{"daemon_cache"};
};

TEST_F(DaemonCache, SecondViewOfASceneSkipsPhotonTracing) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();

    const json first = render(client, photon_job());
    ASSERT_EQ(first.at("state"), "done") << first.dump();
    EXPECT_EQ(first.at("photons").at("cache"), "miss");
    EXPECT_GT(first.at("timings").at("photon_tracing").get<double>(), 0.0);
    const std::string key = first.at("photons").at("key");
    EXPECT_EQ(key.rfind("pm1-", 0), 0u);
    EXPECT_TRUE(fs::exists(dir_.path() / "cache" / "photon-maps" / (key + ".pm")));

    const json second = render(client, photon_job(kOtherView));
    ASSERT_EQ(second.at("state"), "done") << second.dump();
    EXPECT_EQ(second.at("photons").at("cache"), "hit");
    EXPECT_EQ(second.at("photons").at("key"), key);
    EXPECT_EQ(second.at("timings").at("photon_tracing").get<double>(), 0.0);
    EXPECT_EQ(second.at("timings").at("photon_kdtree").get<double>(), 0.0);
    EXPECT_EQ(second.at("photons").at("stored_global"), first.at("photons").at("stored_global"));

    // Other photon settings: another key, traced again.
    json more = photon_job(kOtherView);
    more["photons"]["seed"] = 4;
    const json third = render(client, more);
    EXPECT_EQ(third.at("photons").at("cache"), "miss");
    EXPECT_NE(third.at("photons").at("key"), key);

    const std::string metrics = client.get("/metrics").body;
    EXPECT_NE(metrics.find("photond_photon_cache_hits_total 1\n"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("photond_photon_cache_misses_total 2\n"), std::string::npos) << metrics;
    EXPECT_EQ(metrics.find("photond_photon_cache_bytes 0\n"), std::string::npos) << metrics;
    const json keys = client.get("/v1/photon-maps").json_body().at("keys");
    EXPECT_EQ(keys.size(), 2u);
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

TEST_F(DaemonCache, ADamagedResultImageIsNeverServed) {
    // The final EXR is written with its SHA-256 beside it; a file damaged afterwards (here cut to
    // half) fails the job with the reason and is moved aside, also after a restart.
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const json job = {{"scene", {{"builtin", "cornell-box"}}}, {"integrator", "direct"},
                      {"image", {{"width", 32}, {"height", 32}, {"spp", 1}}}};
    const json done = render(client, job);
    ASSERT_EQ(done.at("state"), "done") << done.dump();
    const std::string id = done.at("id");
    const fs::path image = dir_.path() / "cache" / "jobs" / id / "image.exr";
    ASSERT_TRUE(fs::exists(image));
    EXPECT_TRUE(fs::exists(image.string() + ".sha256"));
    EXPECT_EQ(client.get("/v1/jobs/" + id + "/image.exr").status, 200);  // intact: served

    // Cut to half while the daemon is down: the restarted one finds it out on the first request.
    const std::string bytes = read_file(image);
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
    write_file(image, bytes.substr(0, bytes.size() / 2));
    Daemon restarted(dir_.path() / "cache");
    ASSERT_TRUE(restarted.started()) << restarted.log();
    const HttpClient again = restarted.client();
    const HttpResponse refused = again.get("/v1/jobs/" + id + "/image.exr");
    EXPECT_EQ(refused.status, 409) << refused.body;
    EXPECT_NE(refused.body.find("does not match the checksum"), std::string::npos) << refused.body;
    EXPECT_EQ(again.get("/v1/jobs/" + id + "/preview.png").status, 409);
    const json status = again.get("/v1/jobs/" + id).json_body();
    EXPECT_EQ(status.at("state"), "failed") << status.dump();
    EXPECT_TRUE(fs::exists(image.string() + ".corrupt"));
    EXPECT_FALSE(fs::exists(image));
    EXPECT_EQ(again.get("/healthz").status, 200);
}

TEST_F(DaemonCache, PhotonMapsMoveBetweenDaemonsByExportAndImport) {
    Daemon source(dir_.path() / "source");
    Daemon target(dir_.path() / "target");
    ASSERT_TRUE(source.started() && target.started()) << source.log() << target.log();
    const json traced = render(source.client(), photon_job());
    const std::string key = traced.at("photons").at("key");
    const HttpResponse exported = source.client().get("/v1/photon-maps/" + key);
    ASSERT_EQ(exported.status, 200);
    EXPECT_EQ(exported.header("content-type"), "application/octet-stream");
    EXPECT_EQ(exported.body.substr(0, 8), "PHOTONMP");

    const HttpClient client = target.client();
    // Refused: flipped bytes, a truncated file, and maps filed under another key.
    std::string corrupt = exported.body;
    corrupt[corrupt.size() / 2] ^= 0x5a;
    EXPECT_EQ(client.request("PUT", "/v1/photon-maps/" + key, corrupt).status, 422);
    EXPECT_EQ(client
                  .request("PUT", "/v1/photon-maps/" + key,
                           exported.body.substr(0, exported.body.size() / 3))
                  .status,
              422);
    const std::string other_key = "pm1-" + std::string(64, 'c');
    const HttpResponse foreign =
        client.request("PUT", "/v1/photon-maps/" + other_key, exported.body);
    EXPECT_EQ(foreign.status, 422);
    EXPECT_EQ(client.get("/v1/photon-maps/" + other_key).status, 404);
    EXPECT_EQ(client.get("/v1/photon-maps/" + key).status, 404);

    // Sent as `curl --data-binary` sends it (application/x-www-form-urlencoded), which cpp-httplib
    // refused beyond 8 KiB as a form; the map is several MB.
    ASSERT_GT(exported.body.size(), 8192u);
    const HttpResponse imported = client.request("PUT", "/v1/photon-maps/" + key, exported.body,
                                                 {{"Content-Type", "application/x-www-form-urlencoded"}});
    EXPECT_EQ(imported.status, 201) << imported.body;
    EXPECT_EQ(client.request("PUT", "/v1/photon-maps/" + key, exported.body).status, 200);
    EXPECT_EQ(client.get("/v1/photon-maps/" + key).body, exported.body);
    // Another scene's maps relabelled with this key (checksum recomputed) do not replace them.
    json other_job = photon_job();
    other_job["photons"]["seed"] = 4;
    const std::string forged_from = render(source.client(), other_job).at("photons").at("key");
    std::string forged = source.client().get("/v1/photon-maps/" + forged_from).body;
    ASSERT_EQ(forged_from.size(), key.size());
    const size_t at = forged.find(forged_from);
    ASSERT_NE(at, std::string::npos);
    forged.replace(at, key.size(), key);
    const std::string body = forged.substr(0, forged.size() - 32);
    const Sha256Digest digest = sha256({reinterpret_cast<const uint8_t*>(body.data()), body.size()});
    forged = body + std::string(reinterpret_cast<const char*>(digest.data()), digest.size());
    const HttpResponse refused = client.request("PUT", "/v1/photon-maps/" + key, forged);
    EXPECT_EQ(refused.status, 409) << refused.body;
    EXPECT_NE(refused.body.find("not traced for this key"), std::string::npos) << refused.body;
    EXPECT_EQ(client.get("/v1/photon-maps/" + key).body, exported.body) << "the kept map was replaced";

    const json rendered = render(client, photon_job(kOtherView));
    ASSERT_EQ(rendered.at("state"), "done");
    EXPECT_EQ(rendered.at("photons").at("cache"), "hit");
    EXPECT_EQ(rendered.at("timings").at("photon_tracing").get<double>(), 0.0);
}

TEST_F(DaemonCache, CorruptMapOnDiskIsSetAsideAndRebuilt) {
    std::string key;
    {
        Daemon daemon(dir_.path() / "cache");
        ASSERT_TRUE(daemon.started()) << daemon.log();
        key = render(daemon.client(), photon_job()).at("photons").at("key");
        ASSERT_EQ(daemon.stop(), 0);
    }
    const fs::path file = dir_.path() / "cache" / "photon-maps" / (key + ".pm");
    std::string bytes = read_file(file);
    ASSERT_GT(bytes.size(), 100u);
    bytes.resize(bytes.size() - 40);  // a truncated write
    write_file(file, bytes);

    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const json rebuilt = render(daemon.client(), photon_job(kOtherView));
    ASSERT_EQ(rebuilt.at("state"), "done") << rebuilt.dump();
    EXPECT_EQ(rebuilt.at("photons").at("cache"), "miss");
    EXPECT_TRUE(fs::exists(file.string() + ".corrupt"));
    EXPECT_GT(fs::file_size(file), bytes.size());
    const json again = render(daemon.client(), photon_job());
    EXPECT_EQ(again.at("photons").at("cache"), "hit");
    EXPECT_NE(daemon.log().find("moved aside"), std::string::npos) << daemon.log();
}

TEST_F(DaemonCache, FinishedJobsSurviveARestartAndInterruptedJobsRunAgain) {
    std::string done_id, interrupted_id, image;
    {
        Daemon daemon(dir_.path() / "cache");
        ASSERT_TRUE(daemon.started()) << daemon.log();
        const HttpClient client = daemon.client();
        const json done = render(client, photon_job());
        ASSERT_EQ(done.at("state"), "done");
        done_id = done.at("id");
        image = client.get("/v1/jobs/" + done_id + "/image.exr").body;
        ASSERT_FALSE(image.empty());
        // A job of a few seconds, interrupted by the shutdown.
        const json long_job = {
            {"scene", {{"builtin", "cornell-box"}}},
            {"integrator", "path"},
            {"image", {{"width", 192}, {"height", 128}, {"spp", 32}, {"tile_size", 16}}}};
        interrupted_id = client.post("/v1/jobs", long_job.dump()).json_body().at("id");
        wait_for_status(client, interrupted_id,
                        [](const json& s) { return s.at("progress").at("tiles_done") > 0; });
        EXPECT_EQ(daemon.stop(), 0) << daemon.log();
    }
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const json status = client.get("/v1/jobs/" + done_id).json_body();
    EXPECT_EQ(status.at("state"), "done");
    EXPECT_EQ(status.at("photons").at("cache"), "miss");
    EXPECT_EQ(client.get("/v1/jobs/" + done_id + "/image.exr").body, image);
    // Tiles and events of the restored job, from its image on disk.
    const HttpResponse tile = client.get("/v1/jobs/" + done_id + "/tiles/2/1.exr");
    ASSERT_EQ(tile.status, 200);
    const auto decoded =
        decode_tile_exr({reinterpret_cast<const uint8_t*>(tile.body.data()), tile.body.size()});
    ASSERT_TRUE(decoded.has_value());
    EXPECT_EQ(decoded->rect, (PixelRect{32, 16, 48, 32}));
    const auto events = parse_sse(client.get("/v1/jobs/" + done_id + "/events").body);
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back().type, "done");
    EXPECT_EQ(client.get("/v1/jobs/" + done_id + "/preview.png").status, 200);

    // The interrupted job runs again and finishes.
    const HttpResponse finished = client.get("/v1/jobs/" + interrupted_id + "/image.exr?wait=true");
    EXPECT_EQ(finished.status, 200) << finished.body;
    EXPECT_EQ(client.get("/v1/jobs/" + interrupted_id).json_body().at("state"), "done");
    // (Both daemons log to the same file.)
    EXPECT_NE(daemon.log().find("interrupted by shutdown"), std::string::npos) << daemon.log();
    EXPECT_NE(daemon.log().find("restored 2 job(s)"), std::string::npos) << daemon.log();
    EXPECT_NE(daemon.log().find("(1 queued)"), std::string::npos) << daemon.log();
}

TEST_F(DaemonCache, AViewsIrradianceCacheIsBuiltOnceForItsJobsAndRegionsAndTravelsBetweenDaemons) {
    json job = photon_job();
    job["image"]["width"] = 64;
    job["output"] = {{"pixel_type", "float"}};
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const auto image_of = [](const HttpClient& c, const json& status) {
        return c.get("/v1/jobs/" + status.at("id").get<std::string>() + "/image.exr").body;
    };

    const json first = render(client, job);
    ASSERT_EQ(first.at("state"), "done") << first.dump();
    const json& built = first.at("statistics").at("irradiance_cache");
    EXPECT_EQ(built.at("cache"), "miss");
    EXPECT_GT(built.at("waves").get<int>(), 0);
    const std::string key = built.at("key");
    EXPECT_EQ(key.rfind("rc1-", 0), 0u);
    EXPECT_TRUE(fs::exists(dir_.path() / "cache" / "render-caches" / (key + ".rc")));
    const std::string whole = image_of(client, first);

    // The same view again (more samples per pixel: the prepass does not depend on them): no prepass.
    json more_samples = job;
    more_samples["image"]["spp"] = 2;
    const json again = render(client, more_samples);
    ASSERT_EQ(again.at("state"), "done") << again.dump();
    EXPECT_EQ(again.at("statistics").at("irradiance_cache").at("cache"), "hit");
    EXPECT_EQ(again.at("statistics").at("irradiance_cache").at("key"), key);
    EXPECT_EQ(again.at("statistics").at("irradiance_cache").at("waves"), 0);
    EXPECT_EQ(again.at("statistics").at("irradiance_cache").at("records"), built.at("records"));

    // Another view: another key, built.
    json other = job;
    other["camera"] = kOtherView;
    const json other_view = render(client, other);
    EXPECT_EQ(other_view.at("statistics").at("irradiance_cache").at("cache"), "miss");
    EXPECT_NE(other_view.at("statistics").at("irradiance_cache").at("key"), key);

    // The frame's regions take the frame's cache and assemble into its bytes.
    std::vector<fs::path> parts;
    const std::vector<std::array<int, 4>> regions = {{0, 0, 40, 20}, {40, 0, 64, 20}, {0, 20, 20, 32}, {20, 20, 64, 32}};
    for (const auto& region : regions) {
        json part = job;
        part["image"]["region"] = region;
        const json done = render(client, part);
        ASSERT_EQ(done.at("state"), "done") << done.dump();
        EXPECT_EQ(done.at("statistics").at("irradiance_cache").at("cache"), "hit");
        parts.push_back(dir_.path() / ("part" + std::to_string(parts.size()) + ".exr"));
        write_file(parts.back(), image_of(client, done));
    }
    const auto assembled = assemble_exr_parts(parts);
    ASSERT_TRUE(assembled.has_value()) << assembled.error().message;
    EXPECT_TRUE(std::string(assembled->bytes.begin(), assembled->bytes.end()) == whole);
    EXPECT_NE(client.get("/metrics").body.find("photond_render_cache_hits_total 5\n"), std::string::npos);

    // Another daemon takes the photon maps and the render cache by import: no photon pass, no
    // prepass, the same bytes.
    const std::string photon_key = first.at("photons").at("key");
    const HttpResponse maps = client.get("/v1/photon-maps/" + photon_key);
    const HttpResponse cache = client.get("/v1/render-caches/" + key);
    ASSERT_EQ(cache.status, 200);
    EXPECT_EQ(client.get("/v1/render-caches").json_body().at("keys").size(), 2u);
    Daemon node(dir_.path() / "node");
    ASSERT_TRUE(node.started()) << node.log();
    const HttpClient remote = node.client();
    EXPECT_EQ(remote.request("PUT", "/v1/photon-maps/" + photon_key, maps.body).status, 201);
    EXPECT_EQ(remote.request("PUT", "/v1/render-caches/" + key, cache.body).status, 201);
    EXPECT_EQ(remote.request("PUT", "/v1/render-caches/" + key, cache.body).status, 200);  // the same again
    const std::string other_key = other_view.at("statistics").at("irradiance_cache").at("key");
    const HttpResponse mislabelled = remote.request("PUT", "/v1/render-caches/" + other_key, cache.body);
    EXPECT_EQ(mislabelled.status, 422) << mislabelled.body;
    EXPECT_EQ(remote.request("PUT", "/v1/render-caches/rc1-../x", cache.body).status, 404);
    const json imported = render(remote, job);
    ASSERT_EQ(imported.at("state"), "done") << imported.dump();
    EXPECT_EQ(imported.at("photons").at("cache"), "hit");
    EXPECT_EQ(imported.at("statistics").at("irradiance_cache").at("cache"), "hit");
    EXPECT_TRUE(image_of(remote, imported) == whole);
}

TEST_F(DaemonCache, ABatchOfViewsTracesOnceAndCarriesTheIrradianceCacheFromViewToView) {
    // POST /v1/batches: a job per view, run in order; the photon maps are traced once and each
    // view's irradiance cache starts from the one before, as photond render does with
    // irradiance_cache.start_from: the same bytes on a daemon and offline.
    const json shared = {{"scene", {{"builtin", "cornell-box-diffuse"}}},
                         {"preset", "preview"},
                         {"image", {{"width", 64}, {"height", 48}}}};
    const json cameras = json::array({json{{"look_from", {2.78, 2.73, -8.0}}, {"look_at", {2.78, 2.73, 0.0}}},
                                      json{{"look_from", {1.8, 2.2, -7.0}}, {"look_at", {3.2, 2.5, 2.8}},
                                           {"vfov_deg", 38}}});
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const HttpResponse submitted = client.post("/v1/batches", json{{"job", shared}, {"cameras", cameras}}.dump());
    ASSERT_EQ(submitted.status, 202) << submitted.body;
    const json jobs = submitted.json_body().at("jobs");
    ASSERT_EQ(jobs.size(), 2u);
    std::vector<json> views;
    for (const json& job : jobs) views.push_back(wait_for_status(client, job.at("id"), is_terminal_state));
    ASSERT_EQ(views[0].at("state"), "done") << views[0].dump();
    ASSERT_EQ(views[1].at("state"), "done") << views[1].dump();
    EXPECT_EQ(views[0].at("photons").at("cache"), "miss");
    EXPECT_EQ(views[1].at("photons").at("cache"), "hit");
    const json& first = views[0].at("statistics").at("irradiance_cache");
    const json& second = views[1].at("statistics").at("irradiance_cache");
    EXPECT_EQ(second.at("start_from"), first.at("key"));
    EXPECT_EQ(second.at("records_reused"), first.at("records"));
    EXPECT_GT(second.at("records").get<uint64_t>(), first.at("records").get<uint64_t>());

    // Offline, view by view with a cache directory: the same keys and bytes.
    const fs::path offline = dir_.path() / "offline";
    for (size_t k = 0; k < 2; ++k) {
        json view = shared;
        view["camera"] = cameras[k];
        if (k == 1) view["irradiance_cache"] = {{"start_from", first.at("key")}};
        write_file(dir_.path() / ("view" + std::to_string(k) + ".json"), view.dump());
        const auto [code, output] = run_command(kPhotondBinary + " render --quiet --cache-dir " + offline.string() +
                                                " --job " + (dir_.path() / ("view" + std::to_string(k) + ".json")).string() +
                                                " -o " + (dir_.path() / ("view" + std::to_string(k) + ".exr")).string());
        ASSERT_EQ(code, 0) << output;
        const std::string id = views[k].at("id");
        EXPECT_TRUE(read_file(dir_.path() / ("view" + std::to_string(k) + ".exr")) ==
                    client.get("/v1/jobs/" + id + "/image.exr").body)
            << "view " << k;
    }

    // A batch's problems are named as the batch names them.
    const HttpResponse bad_camera =
        client.post("/v1/batches", json{{"job", shared}, {"cameras", {cameras[0], {{"vfov_deg", 500}}}}}.dump());
    EXPECT_EQ(bad_camera.status, 422);
    EXPECT_EQ(bad_camera.json_body().value("field", ""), "cameras[1].look_from") << bad_camera.body;
    json bad_job = shared;
    bad_job["image"]["spp"] = 0;
    EXPECT_EQ(client.post("/v1/batches", json{{"job", bad_job}, {"cameras", cameras}}.dump()).json_body().value("field", ""),
              "job.image.spp");
    EXPECT_EQ(client.post("/v1/batches", json{{"job", shared}, {"cameras", json::array()}}.dump()).status, 422);
    EXPECT_EQ(client.post("/v1/batches", json{{"job", shared}, {"cameras", cameras}, {"extra", 1}}.dump())
                  .json_body()
                  .value("field", ""),
              "extra");
}

TEST_F(DaemonCache, TwoDaemonsShareOneCacheDirectoryAndBuildEachKeyOnce) {
    // Render farms share photon maps and render caches through a common --cache-dir: both daemons
    // get the same job at once, one builds each key (a lock file per key) while the other waits
    // and then reads the complete file; nobody reads half a file.
    json job = photon_job();
    job["photons"]["global"] = 150000;  // tracing takes long enough for the two to meet
    Daemon first(dir_.path() / "shared");
    Daemon second(dir_.path() / "shared");
    ASSERT_TRUE(first.started() && second.started()) << first.log();
    const std::string a = first.client().post("/v1/jobs", job.dump()).json_body().at("id");
    const std::string b = second.client().post("/v1/jobs", job.dump()).json_body().at("id");
    const json done_a = wait_for_status(first.client(), a, is_terminal_state);
    const json done_b = wait_for_status(second.client(), b, is_terminal_state);
    ASSERT_EQ(done_a.at("state"), "done") << done_a.dump();
    ASSERT_EQ(done_b.at("state"), "done") << done_b.dump();
    EXPECT_EQ(done_a.at("photons").at("key"), done_b.at("photons").at("key"));
    const std::set<std::string> photon_caches = {done_a.at("photons").at("cache"), done_b.at("photons").at("cache")};
    EXPECT_EQ(photon_caches, (std::set<std::string>{"hit", "miss"})) << "traced by both daemons";
    const std::set<std::string> render_caches = {done_a.at("statistics").at("irradiance_cache").at("cache"),
                                                 done_b.at("statistics").at("irradiance_cache").at("cache")};
    EXPECT_EQ(render_caches, (std::set<std::string>{"hit", "miss"})) << "built by both daemons";
    EXPECT_TRUE(first.client().get("/v1/jobs/" + a + "/image.exr").body ==
                second.client().get("/v1/jobs/" + b + "/image.exr").body);
    for (const char* kind : {"photon-maps", "render-caches"})
        for (const auto& entry : fs::directory_iterator(dir_.path() / "shared" / kind))
            EXPECT_TRUE(entry.path().extension() == ".pm" || entry.path().extension() == ".rc" ||
                        entry.path().extension() == ".lock")
                << entry.path();  // no temporary or corrupt files
    // Another view on a fresh daemon of the farm: a hit from the shared directory.
    Daemon third(dir_.path() / "shared", {"--photon-cache-mb", "0"});
    ASSERT_TRUE(third.started());
    json other = job;
    other["camera"] = kOtherView;
    const json hit = render(third.client(), other);
    EXPECT_EQ(hit.at("photons").at("cache"), "hit");
    EXPECT_NE(third.client().get("/metrics").body.find("photond_photon_cache_bytes 0\n"),
              std::string::npos);
}

TEST_F(DaemonCache, AJobKilledMidRenderResumesFromItsTilesWithTheSameBytes) {
    // kill -9 in the middle of the render pass: the restarted daemon takes the tiles finished
    // before the kill, takes the photon maps from the cache, rebuilds the irradiance cache and
    // renders the rest; the image, AOV layers included, is byte-identical to an uninterrupted
    // run's.
    const json job = {{"scene", {{"builtin", "cornell-box"}}},
                      {"integrator", "photon-map"},
                      {"image", {{"width", 256}, {"height", 192}, {"spp", 32}, {"tile_size", 16}}},
                      {"output", {{"pixel_type", "float"}, {"aovs", {"caustic", "albedo", "depth"}}}}};
    const fs::path cache = dir_.path() / "cache";
    std::string id;
    uint64_t done_before_kill = 0;
    {
        Daemon daemon(cache);
        ASSERT_TRUE(daemon.started()) << daemon.log();
        id = daemon.client().post("/v1/jobs", job.dump()).json_body().at("id");
        const json running = wait_for_status(daemon.client(), id, [](const json& s) {
            return is_terminal_state(s) || s.at("progress").at("tiles_done").get<uint64_t>() >= 40;
        });
        ASSERT_EQ(running.at("state"), "running") << running.dump();
        daemon.kill_hard();
        done_before_kill = running.at("progress").at("tiles_done").get<uint64_t>();
    }
    const fs::path tiles = cache / "jobs" / id / "tiles";
    size_t kept = 0;
    for (const auto& entry : fs::directory_iterator(tiles)) kept += entry.path().extension() == ".tile";
    EXPECT_GE(kept, done_before_kill);
    ASSERT_LT(kept, 192u);

    Daemon restarted(cache);
    ASSERT_TRUE(restarted.started()) << restarted.log();
    const json resumed = wait_for_status(restarted.client(), id, is_terminal_state, std::chrono::seconds(60));
    ASSERT_EQ(resumed.at("state"), "done") << resumed.dump();
    EXPECT_EQ(resumed.at("crashes"), 1);
    EXPECT_EQ(resumed.at("photons").at("cache"), "hit");  // traced before the kill, kept on disk
    EXPECT_EQ(resumed.at("statistics").at("tiles_restored").get<size_t>(), kept);
    EXPECT_FALSE(fs::exists(tiles));  // the job ended: its kept tiles are gone
    EXPECT_NE(restarted.log().find("tile(s) taken from the interrupted run"), std::string::npos) << restarted.log();
    const auto events = parse_sse(restarted.client().get("/v1/jobs/" + id + "/events").body);
    ASSERT_FALSE(events.empty());
    EXPECT_NE(events.front().data.dump().find("resumes from the tiles"), std::string::npos) << events.front().data.dump();
    const std::string resumed_image = restarted.client().get("/v1/jobs/" + id + "/image.exr").body;

    Daemon uninterrupted(dir_.path() / "fresh");
    ASSERT_TRUE(uninterrupted.started());
    const json reference = render(uninterrupted.client(), job);
    ASSERT_EQ(reference.at("state"), "done") << reference.dump();
    EXPECT_EQ(reference.at("statistics").at("tiles_restored"), 0);
    const std::string reference_image =
        uninterrupted.client().get("/v1/jobs/" + reference.at("id").get<std::string>() + "/image.exr").body;
    ASSERT_GT(reference_image.size(), 100000u);  // a whole float image (compressed)
    EXPECT_TRUE(resumed_image == reference_image) << "the resumed image differs from the uninterrupted one";
    const auto layers = decode_exr({reinterpret_cast<const uint8_t*>(resumed_image.data()), resumed_image.size()});
    ASSERT_TRUE(layers.has_value()) << layers.error().message;
    EXPECT_EQ(layers->aovs.size(), 3u);
}

TEST_F(DaemonCache, AJobRunningAtThreeDeathsOfTheDaemonIsFailedAsPoison) {
    const json job = {{"scene", {{"builtin", "cornell-box"}}},
                      {"integrator", "path"},
                      {"image", {{"width", 256}, {"height", 192}, {"spp", 256}}}};
    const fs::path cache = dir_.path() / "cache";
    std::string id;
    for (int death = 1; death <= 3; ++death) {
        Daemon daemon(cache);
        ASSERT_TRUE(daemon.started()) << daemon.log();
        if (id.empty()) id = daemon.client().post("/v1/jobs", job.dump()).json_body().at("id");
        const json running = wait_for_status(daemon.client(), id, [](const json& s) {
            return s.value("state", "") == "running" || is_terminal_state(s);
        });
        ASSERT_EQ(running.at("state"), "running") << "death " << death << ": " << running.dump();
        EXPECT_EQ(running.value("crashes", 0), death - 1);
        daemon.kill_hard();
    }
    Daemon daemon(cache);
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const json status = daemon.client().get("/v1/jobs/" + id).json_body();
    EXPECT_EQ(status.at("state"), "failed") << status.dump();
    EXPECT_EQ(status.at("crashes"), 3);
    EXPECT_NE(status.at("error").get<std::string>().find("poison job"), std::string::npos) << status.dump();
    EXPECT_FALSE(fs::exists(cache / "jobs" / id / "tiles"));
    EXPECT_EQ(daemon.client().get("/v1/jobs/" + id + "/image.exr").status, 409);
    // The daemon goes on serving other jobs.
    const json next = render(daemon.client(), {{"scene", {{"builtin", "cornell-box"}}},
                                               {"integrator", "direct"},
                                               {"image", {{"width", 16}, {"height", 16}, {"spp", 1}}}});
    EXPECT_EQ(next.at("state"), "done") << next.dump();
}

TEST_F(DaemonCache, WarningsOfAnUploadAreInItsInfoAndInTheJobStatus) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string gltf = read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "warnings.gltf");
    const HttpResponse created = client.post("/v1/scenes", gltf);
    ASSERT_EQ(created.status, 201) << created.body;
    const std::string id = created.json_body().at("id");
    const auto names = [](const json& warnings) {
        std::string all;
        for (const json& w : warnings) all += w.get<std::string>() + "\n";
        return all;
    };
    const json info = client.get("/v1/scenes/" + id).json_body();
    EXPECT_NE(names(info.at("warnings")).find("KHR_materials_iridescence is not supported"),
              std::string::npos)
        << info.dump();
    const json job = {{"scene", {{"id", id}}},
                      {"integrator", "direct"},
                      {"image", {{"width", 8}, {"height", 8}, {"spp", 1}}}};
    const json status = render(client, job);
    ASSERT_EQ(status.at("state"), "done") << status.dump();
    EXPECT_NE(names(status.at("warnings")).find("KHR_materials_anisotropy is not supported"),
              std::string::npos)
        << status.dump();
    EXPECT_EQ(status.at("warnings"), status.at("statistics").at("warnings"));
}

TEST_F(DaemonCache, UploadedScenesAreStoredByContentAndRenderedById) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string gltf = read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "lights.gltf");
    const HttpResponse created =
        client.post("/v1/scenes", gltf, {{"Content-Type", "model/gltf+json"}});
    ASSERT_EQ(created.status, 201) << created.body;
    const json info = created.json_body();
    const std::string id = info.at("id");
    EXPECT_EQ(id.rfind("sha256:", 0), 0u);
    EXPECT_EQ(id.size(), 7u + 64u);
    EXPECT_EQ(created.header("location"), "/v1/scenes/" + id);
    EXPECT_EQ(info.at("format"), "gltf");
    EXPECT_EQ(info.at("bytes"), gltf.size());
    EXPECT_GT(info.at("triangles").get<int>(), 0);
    EXPECT_GT(info.at("lights").get<int>(), 0);
    EXPECT_EQ(client.post("/v1/scenes", gltf).status, 200);  // the same bytes again
    EXPECT_EQ(client.get("/v1/scenes/" + id).json_body().at("triangles"), info.at("triangles"));

    const std::string glb =
        read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "textured_quad.glb");
    const HttpResponse binary =
        client.post("/v1/scenes", glb, {{"Content-Type", "model/gltf-binary"}});
    ASSERT_EQ(binary.status, 201) << binary.body;
    EXPECT_EQ(binary.json_body().at("format"), "glb");
    EXPECT_EQ(client.get("/v1/scenes").json_body().at("scenes").size(), 2u);

    const json job = {{"scene", {{"id", id}}},
                      {"integrator", "direct"},
                      {"image", {{"width", 16}, {"height", 16}, {"spp", 1}}}};
    const json rendered = render(client, job);
    EXPECT_EQ(rendered.at("state"), "done") << rendered.dump();

    EXPECT_EQ(client.request("DELETE", "/v1/scenes/" + id).status, 204);
    EXPECT_EQ(client.get("/v1/scenes/" + id).status, 404);
    EXPECT_EQ(client.request("DELETE", "/v1/scenes/" + id).status, 404);
    EXPECT_EQ(client.post("/v1/jobs", job.dump()).status, 422);
}

}  // namespace
}  // namespace photond::test
