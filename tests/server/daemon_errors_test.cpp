// Bad requests against the real daemon: each gets its 4xx as RFC 9457 problem+json with a
// message (and the offending field's path for job fields), and the daemon keeps serving.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

const json kSmallJob = {{"scene", {{"builtin", "cornell-box"}}},
                        {"integrator", "direct"},
                        {"image", {{"width", 16}, {"height", 16}, {"spp", 1}}}};

// A render of a few seconds on 2 cores, to hold the worker busy.
const json kLongJob = {
    {"scene", {{"builtin", "cornell-box"}}},
    {"integrator", "path"},
    {"image", {{"width", 256}, {"height", 192}, {"spp", 64}, {"tile_size", 16}}}};

/// Checks a problem answer, then that the daemon still answers /healthz.
void expect_problem(const HttpClient& client, const HttpResponse& response, int status,
                    const std::string& field = {}, const std::string& detail_part = {}) {
    EXPECT_EQ(response.status, status) << response.body;
    EXPECT_EQ(response.header("content-type"), "application/problem+json") << response.body;
    const json problem = response.json_body();
    ASSERT_TRUE(problem.is_object()) << response.body;
    EXPECT_EQ(problem.value("status", 0), status);
    EXPECT_FALSE(problem.value("title", "").empty());
    EXPECT_FALSE(problem.value("type", "").empty());
    const std::string detail = problem.value("detail", "");
    EXPECT_FALSE(detail.empty());
    if (!field.empty()) {
        EXPECT_EQ(problem.value("field", ""), field) << detail;
    }
    if (!detail_part.empty()) {
        EXPECT_NE(detail.find(detail_part), std::string::npos) << detail;
    }
    const HttpResponse health = client.get("/healthz");
    EXPECT_EQ(health.status, 200) << "the daemon stopped serving after a " << status;
}

json with(json job, const std::string& pointer, json value) {
    job[json::json_pointer(pointer)] = std::move(value);
    return job;
}

class DaemonErrors : public ::testing::Test {
protected:
    TempDir dir_{"daemon_errors"};
};

TEST_F(DaemonErrors, BadJobsAndUploadsGetProblemsAndTheDaemonKeepsServing) {
    const fs::path root = dir_.path() / "scenes";
    fs::create_directories(root / "sub");
    fs::copy_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "lights.gltf",
                  root / "sub" / "lights.gltf");
    write_file(dir_.path() / "outside.gltf",
               read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "lights.gltf"));
    fs::create_symlink(dir_.path() / "outside.gltf", root / "escape.gltf");
    Daemon daemon(dir_.path() / "cache", {"--scene-root", root.string(), "--max-body-mb", "1"});
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();

    // Malformed JSON: 400 with line and column.
    expect_problem(client, client.post("/v1/jobs", R"({"scene": {"builtin": "cornell-box"},)"), 400,
                   "", "line 1");
    expect_problem(client, client.post("/v1/jobs", ""), 400);
    // Unknown fields, by their path.
    expect_problem(client, client.post("/v1/jobs", with(kSmallJob, "/image/sppp", 4).dump()), 422,
                   "image.sppp", "unknown field");
    expect_problem(client, client.post("/v1/jobs", with(kSmallJob, "/colour", "red").dump()), 422,
                   "colour");
    // Wrong types.
    expect_problem(client, client.post("/v1/jobs", with(kSmallJob, "/image/width", "big").dump()),
                   422, "image.width");
    expect_problem(client,
                   client.post("/v1/jobs", with(kSmallJob, "/priority", json::array()).dump()), 422,
                   "priority");
    expect_problem(client, client.post("/v1/jobs", json::array({1, 2}).dump()), 422);
    // The whole document and the empty key are named too ("" and "\"\"").
    {
        const json not_object = client.post("/v1/jobs", json::array({1, 2}).dump()).json_body();
        EXPECT_TRUE(not_object.contains("field") && not_object.at("field") == "") << not_object.dump();
        const json empty_key = client.post("/v1/jobs", with(kSmallJob, "/", 1).dump()).json_body();
        EXPECT_EQ(empty_key.value("field", "(none)"), "\"\"") << empty_key.dump();
        const json nested = client.post("/v1/jobs", with(kSmallJob, "/image/", 1).dump()).json_body();
        EXPECT_EQ(nested.value("field", "(none)"), "image.\"\"") << nested.dump();
    }
    // Out of range and absurd sizes.
    expect_problem(client, client.post("/v1/jobs", with(kSmallJob, "/image/width", 1000000).dump()),
                   422, "image.width");
    expect_problem(client, client.post("/v1/jobs", with(kSmallJob, "/photons/global", 1e12).dump()),
                   422, "photons.global");
    expect_problem(client,
                   client.post("/v1/jobs", with(kSmallJob, "/irradiance_cache/a", 2).dump()), 422,
                   "irradiance_cache.a");
    expect_problem(client, client.post("/v1/jobs", with(kSmallJob, "/image/spp", -1).dump()), 422,
                   "image.spp");
    // Missing scenes.
    expect_problem(
        client,
        client.post("/v1/jobs", with(kSmallJob, "/scene", {{"builtin", "cornel-box"}}).dump()), 422,
        "scene.builtin", "cornell-box");
    expect_problem(
        client,
        client.post("/v1/jobs", with(kSmallJob, "/scene", {{"path", "nothing.glb"}}).dump()), 422,
        "scene.path", "nothing.glb");
    expect_problem(
        client,
        client.post("/v1/jobs",
                    with(kSmallJob, "/scene", {{"id", "sha256:" + std::string(64, '0')}}).dump()),
        422, "scene.id", "POST /v1/scenes");
    // Paths outside --scene-root: by "..", absolutely, and through a symbolic link.
    expect_problem(
        client,
        client.post("/v1/jobs", with(kSmallJob, "/scene", {{"path", "../outside.gltf"}}).dump()),
        422, "scene.path");
    expect_problem(
        client,
        client.post("/v1/jobs", with(kSmallJob, "/scene", {{"path", "/etc/passwd"}}).dump()), 422,
        "scene.path");
    expect_problem(
        client,
        client.post("/v1/jobs", with(kSmallJob, "/scene", {{"path", "escape.gltf"}}).dump()), 422,
        "scene.path", "outside the scene root");
    // A path inside the root is accepted and renders.
    const HttpResponse inside =
        client.post("/v1/jobs", with(kSmallJob, "/scene", {{"path", "sub/lights.gltf"}}).dump());
    ASSERT_EQ(inside.status, 202) << inside.body;
    const json done = wait_for_status(client, inside.json_body().at("id"), is_terminal_state);
    EXPECT_EQ(done.at("state"), "done") << done.dump();

    // A scene that passes the checks at submission but cannot be loaded: the job fails with the
    // loader's message, on its status and as its last event.
    fs::copy_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "broken" / "index_out_of_range.gltf",
                  root / "broken.gltf");
    const HttpResponse broken =
        client.post("/v1/jobs", with(kSmallJob, "/scene", {{"path", "broken.gltf"}}).dump());
    ASSERT_EQ(broken.status, 202) << broken.body;
    const std::string broken_id = broken.json_body().at("id");
    const json failed = wait_for_status(client, broken_id, is_terminal_state);
    EXPECT_EQ(failed.at("state"), "failed");
    EXPECT_NE(failed.value("error", "").find("broken.gltf"), std::string::npos) << failed.dump();
    const auto events = parse_sse(client.get("/v1/jobs/" + broken_id + "/events").body);
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back().type, "failed");
    EXPECT_EQ(events.back().data.value("error", ""), failed.value("error", ""));
    expect_problem(client, client.get("/v1/jobs/" + broken_id + "/image.exr?wait=true"), 409, "",
                   "failed");

    // Broken glTF uploads: the loader's message.
    expect_problem(client, client.post("/v1/scenes", "this is not a scene"), 422, "", "glTF");
    expect_problem(client,
                   client.post("/v1/scenes", read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" /
                                                       "broken" / "truncated.glb")),
                   422);
    expect_problem(client,
                   client.post("/v1/scenes", read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" /
                                                       "broken" / "external_buffer.gltf")),
                   422);
    expect_problem(client, client.post("/v1/scenes", ""), 422, "", "empty");

    // Too large a body: 413 (--max-body-mb 1).
    expect_problem(client, client.post("/v1/scenes", std::string(size_t{2} << 20, 'x')), 413, "",
                   "max-body-mb");
    expect_problem(client, client.post("/v1/jobs", std::string(size_t{3} << 20, ' ')), 413);

    // Unknown things: 404; wrong methods: 405 with Allow.
    expect_problem(client, client.get("/v1/jobs/no-such-job"), 404, "", "no-such-job");
    expect_problem(client, client.request("DELETE", "/v1/jobs/no-such-job"), 404);
    expect_problem(client, client.get("/v1/jobs/no-such-job/image.exr"), 404);
    expect_problem(client, client.get("/v1/jobs/no-such-job/tiles/0/0.exr"), 404);
    expect_problem(client, client.get("/v1/no-such-route"), 404, "", "no route");
    expect_problem(client, client.get("/v1/scenes/sha256:" + std::string(64, 'a')), 404);
    expect_problem(client, client.get("/v1/photon-maps/pm1-" + std::string(64, 'a')), 404);
    expect_problem(client, client.get("/v1/photon-maps/..%2F..%2Fetc"), 404);
    const HttpResponse not_allowed = client.request("PATCH", "/v1/jobs", "{}");
    expect_problem(client, not_allowed, 405);
    EXPECT_EQ(not_allowed.header("allow"), "GET, POST");
    const HttpResponse put_health = client.request("PUT", "/healthz");
    expect_problem(client, put_health, 405);
    EXPECT_EQ(put_health.header("allow"), "GET");

    // Tiles out of the grid, and results of a job that has none.
    const std::string id = inside.json_body().at("id");
    expect_problem(client, client.get("/v1/jobs/" + id + "/tiles/99/0.exr"), 404, "",
                   "outside the tile grid");
    expect_problem(client, client.request("DELETE", "/v1/jobs/" + id), 409, "", "already done");
    // A corrupt photon-map import.
    expect_problem(
        client,
        client.request("PUT", "/v1/photon-maps/pm1-" + std::string(64, 'b'), "PHOTONMP garbage"),
        422);

    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

TEST_F(DaemonErrors, InvalidUtf8AndDeepNestingAreProblemsNotCrashes) {
    // Bytes that are not UTF-8 reach error messages (paths, field values, headers); the JSON
    // writer once threw on them inside the error handler and ended the daemon. Documents nested
    // 100,000 deep overflowed the stack of the parser or of the code that walks them.
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    for (const std::string path : {"/%F9", "/\xF9", "/v1/jobs/%F9", "/v1/jobs/\xF9", "/v1/scenes/%F9",
                                   "/v1/photon-maps/%F9"}) {
        const HttpResponse r = client.get(path);
        EXPECT_GE(r.status, 400) << path;
        EXPECT_LT(r.status, 500) << path << ": " << r.body;
        EXPECT_TRUE(r.json_body().is_object()) << path << ": " << r.body;
        ASSERT_EQ(client.get("/healthz").status, 200) << "the daemon died on " << path << "\n" << daemon.log();
    }
    // A job whose values hold invalid UTF-8: 400 for the malformed text, named by position.
    expect_problem(client, client.post("/v1/jobs", "{\"scene\": {\"builtin\": \"corn\xf9\"}}"), 400);
    expect_problem(client, client.post("/v1/jobs", "{\"scene\": \xc3\xa9}"), 400);
    expect_problem(client, client.post("/v1/jobs", "{\"preset\": \"" + std::string(60, 'x') + "\xe9\"}"), 400);
    // A valid UTF-8 value cut inside an error message's quote: still valid JSON out.
    std::string accents;
    for (int i = 0; i < 40; ++i) accents += "\xc3\xa9";
    expect_problem(client, client.post("/v1/jobs", with(kSmallJob, "/preset", accents).dump()), 422, "preset");
    // An Idempotency-Key with a byte beyond ASCII: refused, and no job directory is left.
    expect_problem(client, client.post("/v1/jobs", kSmallJob.dump(), {{"Idempotency-Key", "key\xf9"}}), 400, "",
                   "Idempotency-Key");
    EXPECT_FALSE(fs::exists(dir_.path() / "cache" / "jobs") && !fs::is_empty(dir_.path() / "cache" / "jobs"));
    // Nested 100,000 deep inside the scene, and just past the limit: refused before parsing.
    const std::string deep = "{\"scene\": " + std::string(100000, '[') + std::string(100000, ']') + "}";
    expect_problem(client, client.post("/v1/jobs", deep), 400, "", "nest more than 128");
    const std::string just_past = "{\"scene\": " + std::string(128, '[') + std::string(128, ']') + "}";
    expect_problem(client, client.post("/v1/jobs", just_past), 400, "", "nest more than 128");
    // A glTF upload whose extras nest 100,000 deep.
    const std::string deep_gltf = "{\"asset\": {\"version\": \"2.0\"}, \"extras\": " + std::string(100000, '[') +
                                  std::string(100000, ']') + "}";
    const HttpResponse upload = client.post("/v1/scenes", deep_gltf, {{"Content-Type", "model/gltf+json"}});
    EXPECT_GE(upload.status, 400) << upload.body;
    EXPECT_LT(upload.status, 500) << upload.body;
    EXPECT_NE(upload.body.find("nest more than 128"), std::string::npos) << upload.body;
    EXPECT_EQ(client.get("/healthz").status, 200) << daemon.log();
}

TEST_F(DaemonErrors, BodiesOver8KiBAreReadWhateverTheirContentType) {
    // curl's --data-binary and -d send application/x-www-form-urlencoded unless told otherwise;
    // cpp-httplib parsed such bodies as forms and answered 413 beyond 8 KiB.
    Daemon daemon(dir_.path() / "cache", {"--max-body-mb", "1"});
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const Headers form{{"Content-Type", "application/x-www-form-urlencoded"}};
    const std::string job = kSmallJob.dump() + std::string(20000, ' ');
    const HttpResponse submitted = client.post("/v1/jobs", job, form);
    EXPECT_EQ(submitted.status, 202) << submitted.body;
    std::string gltf = read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "lights.gltf");
    gltf += std::string(20000, '\n');
    const HttpResponse uploaded = client.post("/v1/scenes", gltf, form);
    EXPECT_EQ(uploaded.status, 201) << uploaded.body;
    // Beyond --max-body-mb the 413 names the real limit.
    expect_problem(client, client.post("/v1/jobs", std::string(2 << 20, ' '), form), 413, "", "1 MiB");
    // A POST without a body, and one that declares 256 MiB and sends nothing, are answered at
    // once (both waited out the 30 s read timeout).
    const auto started = std::chrono::steady_clock::now();
    expect_problem(client, client.post("/v1/jobs", "", {{"Content-Length", ""}}), 400, "", "no body");
    expect_problem(client, client.request("POST", "/v1/jobs", "", {{"Content-Length", std::to_string(256 << 20)}}),
                   413, "", "1 MiB");
    EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(10));
}

TEST_F(DaemonErrors, ReadinessSaysWhenTheCacheDiskIsFull) {
    // A disk with less free space than --min-free-mb (here more than any disk has: 2^40 MiB) is
    // a full one for readiness: 503 with what is free; health stays 200 (the process is fine).
    Daemon full(dir_.path() / "full", {"--min-free-mb", std::to_string(uint64_t{1} << 40)});
    ASSERT_TRUE(full.started()) << full.log();
    const HttpClient client = full.client();
    expect_problem(client, client.get("/readyz"), 503, "", "MiB free, under the");
    Daemon roomy(dir_.path() / "roomy", {"--min-free-mb", "0"});
    ASSERT_TRUE(roomy.started()) << roomy.log();
    const HttpResponse ready = roomy.client().get("/readyz");
    EXPECT_EQ(ready.status, 200) << ready.body;
    EXPECT_GT(ready.json_body().value("cache_free_bytes", uint64_t{0}), 0u) << ready.body;
}

/// A tmpfs of `kilobytes` mounted at `path` for the test's lifetime (needs CAP_SYS_ADMIN).
class SmallDisk {
public:
    SmallDisk(const fs::path& path, int kilobytes) : path_(path) {
        fs::create_directories(path);
        mounted_ = std::system(("mount -t tmpfs -o size=" + std::to_string(kilobytes) + "k tmpfs '" + path.string() +
                                "' 2>/dev/null")
                                   .c_str()) == 0;
    }
    ~SmallDisk() {
        if (mounted_) (void)std::system(("umount '" + path_.string() + "'").c_str());
    }
    bool mounted() const { return mounted_; }

private:
    fs::path path_;
    bool mounted_ = false;
};

TEST_F(DaemonErrors, AFullCacheDiskRefusesJobsAndLeavesNoHalfWrittenOnes) {
    const SmallDisk disk(dir_.path() / "disk", 512);
    if (!disk.mounted()) GTEST_SKIP() << "mounting a tmpfs needs CAP_SYS_ADMIN";
    const fs::path cache = dir_.path() / "disk" / "cache";
    {
        Daemon daemon(cache, {"--min-free-mb", "0"});
        ASSERT_TRUE(daemon.started()) << daemon.log();
        const HttpClient client = daemon.client();
        // A job accepted while there is room, still rendering when the disk fills.
        const HttpResponse running = client.post("/v1/jobs", kLongJob.dump());
        ASSERT_EQ(running.status, 202) << running.body;
        // Fill the disk to the last byte.
        {
            std::ofstream filler(dir_.path() / "disk" / "filler", std::ios::binary);
            const std::string block(4096, 'x');
            while (filler.write(block.data(), static_cast<std::streamsize>(block.size()))) {
            }
        }
        for (int i = 0; i < 5; ++i) {
            const HttpResponse r = client.post("/v1/jobs", with(kSmallJob, "/seed", i).dump());
            EXPECT_EQ(r.status, 503) << r.body;
            EXPECT_NE(r.body.find("cannot keep the job"), std::string::npos) << r.body;
        }
        EXPECT_EQ(client.get("/healthz").status, 200);
        // The running job cannot write its image: it fails with the reason, and the states the
        // disk refused are counted and carried by the job as a warning.
        const json ended = wait_for_status(client, running.json_body().at("id"), is_terminal_state);
        EXPECT_EQ(ended.at("state"), "failed") << ended.dump();
        bool warned = false;
        for (const json& w : ended.value("warnings", json::array()))
            warned = warned || w.get<std::string>().find("could not be written to the cache directory") != std::string::npos;
        EXPECT_TRUE(warned) << ended.dump();
        const std::string metrics = client.get("/metrics").body;
        EXPECT_EQ(metrics.find("photond_store_write_failures_total 0\n"), std::string::npos) << metrics;
        EXPECT_NE(metrics.find("photond_store_write_failures_total "), std::string::npos) << metrics;
        size_t directories = 0;
        for (const auto& entry : fs::directory_iterator(cache / "jobs")) directories += entry.is_directory();
        EXPECT_EQ(directories, 1u) << "refused submissions left job directories behind (only the accepted one may stay)";
        EXPECT_EQ(daemon.stop(), 0) << daemon.log();
    }
    // With room again, a restart finds no broken job directory and serves a new one.
    fs::remove(dir_.path() / "disk" / "filler");
    Daemon restarted(cache, {"--min-free-mb", "0"});
    ASSERT_TRUE(restarted.started()) << restarted.log();
    EXPECT_EQ(restarted.log().find("cannot be read"), std::string::npos) << restarted.log();
    const HttpResponse accepted = restarted.client().post("/v1/jobs", kSmallJob.dump());
    EXPECT_EQ(accepted.status, 202) << accepted.body;
}

TEST_F(DaemonErrors, LightingThatCannotWorkIsRefusedAtSubmission) {
    const fs::path root = dir_.path() / "scenes";
    fs::create_directories(root);
    fs::copy_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "texture.gltf", root / "dark.gltf");
    write_file(dir_.path() / "outside.exr", "not read");
    fs::create_symlink(dir_.path() / "outside.exr", root / "escape.exr");
    Daemon daemon(dir_.path() / "cache", {"--scene-root", root.string()});
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const json dark = with(kSmallJob, "/scene", {{"path", "dark.gltf"}});
    // No light in the scene, none from the job, and the default environment turned off.
    expect_problem(client, client.post("/v1/jobs", with(dark, "/environment", nullptr).dump()), 422,
                   "environment", "\"lights\"");
    expect_problem(client,
                   client.post("/v1/jobs", with(dark, "/environment", {{"image", "missing.exr"}}).dump()),
                   422, "environment.image", "missing.exr");
    expect_problem(client,
                   client.post("/v1/jobs", with(dark, "/environment", {{"image", "escape.exr"}}).dump()),
                   422, "environment.image", "outside the scene root");
    // With a light from the job the same scene renders, and by default under the white sky.
    json lit = with(dark, "/environment", nullptr);
    lit["lights"] = json::array({{{"type", "point"}, {"position", {0, 0, 2}}, {"intensity", 5}}});
    for (const json& job : {lit, dark}) {
        const HttpResponse accepted = client.post("/v1/jobs", job.dump());
        ASSERT_EQ(accepted.status, 202) << accepted.body;
        const json done = wait_for_status(client, accepted.json_body().at("id"), is_terminal_state);
        EXPECT_EQ(done.at("state"), "done") << done.dump();
    }
}

TEST_F(DaemonErrors, MediaRenderAndAreRefusedByNameWhereTheyCannot) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const json fog = {{"sigma_a", 0.02}, {"sigma_s", {0.2, 0.3, 0.4}}, {"g", 0.4}};
    expect_problem(client, client.post("/v1/jobs", with(kSmallJob, "/atmosphere", {{"sigma_s", -1}}).dump()), 422,
                   "atmosphere.sigma_s", "[0, 1e+06]");
    // Every integrator renders it, and the plan says where it is and how dense (and photon-map
    // that it traces a volume map).
    for (const std::string integrator : {"path", "direct", "photon-map"}) {
        const HttpResponse accepted =
            client.post("/v1/jobs", with(with(kSmallJob, "/integrator", integrator), "/atmosphere", fog).dump());
        ASSERT_EQ(accepted.status, 202) << accepted.body;
        const json done = wait_for_status(client, accepted.json_body().at("id"), is_terminal_state);
        ASSERT_EQ(done.at("state"), "done") << done.dump();
        EXPECT_NE(done.dump().find("\"atmosphere\""), std::string::npos) << done.dump();
        EXPECT_NE(done.dump().find("optical depth"), std::string::npos) << done.dump();
        if (integrator == "photon-map") {
            EXPECT_NE(done.dump().find("\"volume_map\""), std::string::npos) << done.dump();
        }
    }
    // direct does not render a medium inside solids: a 422 that names the field.
    expect_problem(client,
                   client.post("/v1/jobs", with(with(kSmallJob, "/integrator", "direct"), "/material_media",
                                                {{"glass", {{"sigma_s", 3.0}}}}).dump()),
                   422, "material_media", "\"path\"");
    // A medium inside the box's glass sphere (material "glass"): path and photon-map render it
    // (photon-map with a volume map of the solid's photons); a material the scene lacks is
    // refused at submission, naming the entry and the materials there are.
    for (const std::string integrator : {"path", "photon-map"}) {
        const HttpResponse accepted = client.post(
            "/v1/jobs", with(with(kSmallJob, "/integrator", integrator), "/material_media",
                             {{"glass", {{"sigma_s", 3.0}, {"g", 0.3}}}}).dump());
        ASSERT_EQ(accepted.status, 202) << accepted.body;
        const json done = wait_for_status(client, accepted.json_body().at("id"), is_terminal_state);
        ASSERT_EQ(done.at("state"), "done") << done.dump();
        EXPECT_NE(done.dump().find("the solids of 'glass'"), std::string::npos) << done.dump();
        if (integrator == "photon-map") {
            EXPECT_NE(done.dump().find("solids scatter light inside"), std::string::npos) << done.dump();
        }
    }
    const json path_job = with(kSmallJob, "/integrator", "path");
    expect_problem(client, client.post("/v1/jobs", with(path_job, "/material_media", {{"nope", {{"sigma_s", 1}}}}).dump()),
                   422, "material_media.nope", "'glass'");
    expect_problem(client, client.post("/v1/jobs", with(path_job, "/material_media", {{"white", {{"sigma_s", 1}}}}).dump()),
                   422, "material_media.white", "not transmissive");
}

TEST_F(DaemonErrors, FullQueueAnswers429WithRetryAfter) {
    Daemon daemon(dir_.path() / "cache", {"--max-queued", "1"});
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string running = client.post("/v1/jobs", kLongJob.dump()).json_body().at("id");
    wait_for_status(client, running,
                    [](const json& s) { return s.value("state", "") == "running"; });
    const HttpResponse queued = client.post("/v1/jobs", kSmallJob.dump());
    ASSERT_EQ(queued.status, 202) << queued.body;
    const HttpResponse refused = client.post("/v1/jobs", kSmallJob.dump());
    expect_problem(client, refused, 429, "", "max-queued");
    EXPECT_GE(std::stoi(refused.header("retry-after")), 1);
    const std::string metrics = client.get("/metrics").body;
    EXPECT_NE(metrics.find("photond_queue_jobs 1"), std::string::npos) << metrics;
    // Cancelling makes room again.
    EXPECT_EQ(client.request("DELETE", "/v1/jobs/" + queued.json_body().at("id").get<std::string>())
                  .status,
              200);
    EXPECT_EQ(client.post("/v1/jobs", kSmallJob.dump()).status, 202);
    client.request("DELETE", "/v1/jobs/" + running);
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

TEST_F(DaemonErrors, BearerTokenIsRequiredWhenConfigured) {
    write_file(dir_.path() / "token", "s3cret-token\n");
    Daemon daemon(dir_.path() / "cache", {"--token-file", (dir_.path() / "token").string()});
    ASSERT_TRUE(daemon.started()) << daemon.log();

    const HttpClient anonymous = daemon.client();
    const HttpResponse missing = anonymous.get("/v1/jobs");
    expect_problem(anonymous, missing, 401);
    EXPECT_EQ(missing.header("www-authenticate").rfind("Bearer", 0), 0u);
    expect_problem(anonymous, anonymous.post("/v1/jobs", kSmallJob.dump()), 401);

    const HttpClient wrong = daemon.client("s3cret-tokem");
    const HttpResponse invalid = wrong.get("/v1/jobs");
    expect_problem(wrong, invalid, 401);
    EXPECT_NE(invalid.header("www-authenticate").find("invalid_token"), std::string::npos);

    const HttpClient right = daemon.client("s3cret-token");
    EXPECT_EQ(right.get("/v1/jobs").status, 200);
    EXPECT_EQ(right.post("/v1/jobs", kSmallJob.dump()).status, 202);
    EXPECT_EQ(anonymous.get("/readyz").status, 200);  // health checks stay open
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

/// A connected socket to the daemon (closed by the caller); -1 on failure.
int connect_to(int port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd >= 0 && ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0) return fd;
    if (fd >= 0) ::close(fd);
    return -1;
}

TEST_F(DaemonErrors, SlowAndIdleClientsDoNotStarveHealthChecks) {
    // 300 connections that hold a thread each (half a request head, or nothing at all) and 40
    // event streams whose readers never read, beyond the 128 threads the daemon once had for
    // every connection: /healthz and the API still answer at once.
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string id = client.post("/v1/jobs", kLongJob.dump()).json_body().at("id");
    std::vector<int> held;
    for (int i = 0; i < 300; ++i) {
        const int fd = connect_to(daemon.port());
        ASSERT_GE(fd, 0) << "connection " << i;
        if (i % 2 == 0) {
            const std::string partial = "GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ";
            ASSERT_EQ(::send(fd, partial.data(), partial.size(), 0), static_cast<ssize_t>(partial.size()));
        }
        held.push_back(fd);
    }
    for (int i = 0; i < 40; ++i) {
        const int fd = connect_to(daemon.port());
        ASSERT_GE(fd, 0);
        const std::string request = "GET /v1/jobs/" + id + "/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
        ASSERT_EQ(::send(fd, request.data(), request.size(), 0), static_cast<ssize_t>(request.size()));
        held.push_back(fd);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // every connection accepted
    double slowest_ms = 0.0;
    for (int i = 0; i < 20; ++i) {
        const auto start = std::chrono::steady_clock::now();
        const HttpResponse health = client.request("GET", "/healthz", {}, {}, std::chrono::seconds(5));
        slowest_ms = std::max(slowest_ms, std::chrono::duration<double, std::milli>(
                                              std::chrono::steady_clock::now() - start).count());
        ASSERT_EQ(health.status, 200) << "health check " << i << " with " << held.size() << " connections held";
    }
    EXPECT_EQ(client.get("/v1/jobs/" + id).status, 200);
    std::printf("slowest of 20 /healthz with %zu connections held: %.1f ms\n", held.size(), slowest_ms);
    for (int fd : held) ::close(fd);
    EXPECT_EQ(client.request("DELETE", "/v1/jobs/" + id).status, 200);
    EXPECT_EQ(daemon.stop(), 0) << daemon.log();
}

TEST_F(DaemonErrors, RefusesToListenBeyondLoopbackWithoutAToken) {
    const auto [code, output] =
        run_command(kPhotondBinary + " serve --listen 0.0.0.0:0 --cache-dir " +
                    (dir_.path() / "cache").string());
    EXPECT_EQ(code, 2);
    EXPECT_NE(output.find("--token-file"), std::string::npos) << output;
    const auto [usage_code, usage] = run_command(kPhotondBinary + " serve --listen nowhere");
    EXPECT_EQ(usage_code, 2);
    EXPECT_NE(usage.find("--listen"), std::string::npos) << usage;
    const auto [empty_code, empty] =
        run_command("touch " + (dir_.path() / "empty").string() + " && " + kPhotondBinary +
                    " serve --token-file " + (dir_.path() / "empty").string());
    EXPECT_EQ(empty_code, 2);
    EXPECT_NE(empty.find("empty"), std::string::npos) << empty;
}

TEST_F(DaemonErrors, ASecondDaemonOnATakenPortRefusesToStart) {
    // cpp-httplib's default socket options include SO_REUSEPORT: a second daemon bound the same
    // port without an error and took part of the first one's connections.
    Daemon first(dir_.path() / "first");
    ASSERT_TRUE(first.started()) << first.log();
    const auto [code, output] =
        run_command("timeout 10 " + kPhotondBinary + " serve --listen 127.0.0.1:" + std::to_string(first.port()) +
                    " --cache-dir " + (dir_.path() / "second").string());
    EXPECT_EQ(code, 1) << output;
    EXPECT_NE(output.find("cannot listen on 127.0.0.1:" + std::to_string(first.port()) + " (in use"),
              std::string::npos)
        << output;
    EXPECT_EQ(first.client().get("/healthz").status, 200);
}

}  // namespace
}  // namespace photond::test
