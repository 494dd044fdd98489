// The daemon's web page (server/web/, server/web_handlers.h) and its PNG tiles
// (server/tile_png.h), on a real daemon with a token:
//  - the page's files are served without the token, the API behind them only with it;
//  - the PNG tiles of a job, put side by side, are the bytes-decoded pixels of its preview.png,
//    with the job's exposure and with the automatic one;
//  - in a real browser (Debian's chromium, headless, driven by puppeteer-core, installed from the
//    npm registry into the build tree at the first run): the token asked for and kept, a job
//    submitted from the form whose image assembles from its tiles into exactly preview.png's
//    pixels, cancel, a readable error for a scene that does not exist, and the goals measured:
//    first paint, tile latency, browser memory (tests/server/web_page_browser.mjs). The two time
//    goals are asserted only under `make bench-web` (PHOTOND_WEB_TIME_GOALS set).
// WebPage.DISABLED_LargeJobInChromium is the 4096x4096 job (16,384 tiles); `make test-web-large`
// runs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <set>

#include "core/image/exr_io.h"
#include "tests/server/daemon_harness.h"
#include "tests/support/decoded_png.h"

namespace photond::test {
namespace {

using test_support::decode_png;
using test_support::DecodedPng;

// The last 22.x release; its declared engines include Debian 12's node 18.
constexpr std::string_view kPuppeteerVersion = "22.15.0";
const std::string kToken = "web-page-test-token";

std::string quoted(const std::string& text) {
    std::string out = "'";
    for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

/// A daemon with a token and a scene root.
struct TokenDaemon {
    TempDir dir{"web_page"};
    std::unique_ptr<Daemon> daemon;

    TokenDaemon() {
        write_file(dir.path() / "token", kToken + "\n");
        fs::create_directories(dir.path() / "scenes");
        daemon = std::make_unique<Daemon>(
            dir.path() / "cache",
            std::vector<std::string>{"--token-file", (dir.path() / "token").string(), "--scene-root",
                                     (dir.path() / "scenes").string()});
    }
};

TEST(WebPage, ThePageIsPublicItsDataNeedsTheToken) {
    TokenDaemon fixture;
    Daemon& daemon = *fixture.daemon;
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpClient anonymous = daemon.client();

    const HttpResponse page = anonymous.get("/");
    ASSERT_EQ(page.status, 200) << page.body;
    EXPECT_EQ(page.header("content-type"), "text/html; charset=utf-8");
    EXPECT_NE(page.body.find("<script type=\"module\" src=\"/web/app.js\">"), std::string::npos);
    const std::string policy = page.header("content-security-policy");
    EXPECT_NE(policy.find("script-src 'self'"), std::string::npos) << policy;
    EXPECT_NE(policy.find("frame-ancestors 'none'"), std::string::npos) << policy;
    EXPECT_EQ(page.header("referrer-policy"), "no-referrer");
    EXPECT_EQ(page.header("x-content-type-options"), "nosniff");

    for (const char* file : {"app.js", "api.js", "event_stream.js", "tile_canvas.js", "job_view.js",
                             "job_list.js", "submit_form.js"}) {
        const HttpResponse script = anonymous.get(std::string("/web/") + file);
        EXPECT_EQ(script.status, 200) << file;
        EXPECT_EQ(script.header("content-type"), "text/javascript; charset=utf-8") << file;
        // Every module the page imports is served.
        for (size_t at = script.body.find("from \"./"); at != std::string::npos;
             at = script.body.find("from \"./", at + 1)) {
            const size_t end = script.body.find('"', at + 8);
            const std::string imported = script.body.substr(at + 8, end - at - 8);
            EXPECT_EQ(anonymous.get("/web/" + imported).status, 200) << file << " imports " << imported;
        }
    }
    EXPECT_EQ(anonymous.get("/web/app.css").header("content-type"), "text/css; charset=utf-8");
    // One address for the page; no other files.
    for (const char* missing : {"/web/index.html", "/web/nothing.js", "/web/..%2Fapp.js"}) {
        const HttpResponse answer = anonymous.get(missing);
        EXPECT_EQ(answer.status, 404) << missing;
        EXPECT_EQ(answer.header("content-type"), "application/problem+json") << missing;
    }
    // The data is not public.
    for (const char* path : {"/v1/jobs", "/v1/scenes", "/v1/openapi.json", "/v1/jobs/x/tiles/0/0.png"})
        EXPECT_EQ(anonymous.get(path).status, 401) << path;
}

/// Pastes the tile PNGs of a done job at their X-Tile-Rect; each tile's X-Exposure-EV is added
/// to `exposures`.
DecodedPng assemble_tiles(const HttpClient& client, const std::string& id, int width, int height,
                          int tile, const std::string& query, std::set<std::string>& exposures) {
    DecodedPng frame{width, height, std::vector<uint8_t>(size_t(width) * height * 3, 0)};
    for (int ty = 0; ty * tile < height; ++ty) {
        for (int tx = 0; tx * tile < width; ++tx) {
            const std::string path = "/v1/jobs/" + id + "/tiles/" + std::to_string(tx) + "/" +
                                     std::to_string(ty) + ".png" + query;
            const HttpResponse answer = client.get(path);
            EXPECT_EQ(answer.status, 200) << path << answer.body;
            EXPECT_EQ(answer.header("content-type"), "image/png");
            exposures.insert(answer.header("x-exposure-ev"));
            int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
            EXPECT_EQ(std::sscanf(answer.header("x-tile-rect").c_str(), "%d,%d,%d,%d", &x0, &y0, &x1, &y1), 4);
            EXPECT_EQ(x0, tx * tile);
            EXPECT_EQ(y0, ty * tile);
            const DecodedPng png =
                decode_png(reinterpret_cast<const uint8_t*>(answer.body.data()), answer.body.size());
            EXPECT_EQ(png.width, x1 - x0) << path;
            EXPECT_EQ(png.height, y1 - y0) << path;
            for (int y = 0; y < png.height; ++y)
                for (int x = 0; x < png.width; ++x)
                    for (int c = 0; c < 3; ++c)
                        frame.rgb[size_t(((y0 + y) * width + x0 + x) * 3 + c)] = png.at(x, y, c);
        }
    }
    return frame;
}

size_t differing_pixels(const DecodedPng& a, const DecodedPng& b) {
    if (a.width != b.width || a.height != b.height) return size_t(-1);
    size_t differing = 0;
    for (size_t i = 0; i < a.rgb.size(); i += 3)
        differing += a.rgb[i] != b.rgb[i] || a.rgb[i + 1] != b.rgb[i + 1] || a.rgb[i + 2] != b.rgb[i + 2];
    return differing;
}

TEST(WebPage, PngTilesSideBySideArePreviewPng) {
    TokenDaemon fixture;
    Daemon& daemon = *fixture.daemon;
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpClient client = daemon.client(kToken);
    constexpr int kWidth = 80, kHeight = 56, kTile = 16;  // a partial tile column and row
    for (const bool own_exposure : {true, false}) {
        SCOPED_TRACE(own_exposure ? "the job's exposure" : "automatic exposure");
        json job = {{"scene", {{"builtin", "cornell-box"}}},
                    {"preset", "preview"},
                    {"image", {{"width", kWidth}, {"height", kHeight}, {"tile_size", kTile}, {"spp", 1}}},
                    {"photons", {{"global", 2000}, {"caustic", 1000}}},
                    {"gather", {{"rays", 16}}}};
        if (own_exposure) job["output"] = {{"exposure_ev", 1.5}};
        const HttpResponse submitted = client.post("/v1/jobs", job.dump());
        ASSERT_EQ(submitted.status, 202) << submitted.body;
        const std::string id = submitted.json_body().at("id");
        ASSERT_EQ(client.get("/v1/jobs/" + id + "/image.exr?wait=true").status, 200);
        const HttpResponse preview_answer = client.get("/v1/jobs/" + id + "/preview.png");
        ASSERT_EQ(preview_answer.status, 200);
        const DecodedPng preview = decode_png(
            reinterpret_cast<const uint8_t*>(preview_answer.body.data()), preview_answer.body.size());
        ASSERT_EQ(preview.width, kWidth);

        std::set<std::string> exposures;
        const DecodedPng tiles = assemble_tiles(client, id, kWidth, kHeight, kTile, "", exposures);
        EXPECT_EQ(differing_pixels(tiles, preview), 0u);
        ASSERT_EQ(exposures.size(), 1u);  // one exposure for the whole frame
        const std::string exposure = *exposures.begin();
        if (own_exposure) {
            EXPECT_EQ(exposure, "1.5");
        }
        // The exposure given back gives the same tiles; another one gives others.
        std::set<std::string> again;
        EXPECT_EQ(differing_pixels(assemble_tiles(client, id, kWidth, kHeight, kTile,
                                                  "?exposure_ev=" + exposure, again),
                                   preview),
                  0u);
        EXPECT_EQ(again, exposures);
        std::set<std::string> brighter;
        const DecodedPng other = assemble_tiles(client, id, kWidth, kHeight, kTile,
                                                "?exposure_ev=" + std::to_string(std::stof(exposure) + 2),
                                                brighter);
        EXPECT_GT(differing_pixels(other, preview), size_t(kWidth * kHeight / 2));
    }

    // Bad requests, each with a problem that says what is wrong.
    const std::string id = client.get("/v1/jobs").json_body().at("jobs").at(0).at("id");
    struct Refusal {
        std::string path;
        int status;
        std::string says;
    };
    for (const Refusal& r : std::vector<Refusal>{
             {"/v1/jobs/" + id + "/tiles/0/0.png?exposure_ev=bright", 400, "exposure_ev"},
             {"/v1/jobs/" + id + "/tiles/0/0.png?exposure_ev=65", 400, "[-64, 64]"},
             {"/v1/jobs/" + id + "/tiles/0/0.png?exposure_ev=nan", 400, "exposure_ev"},
             {"/v1/jobs/" + id + "/tiles/5/0.png", 404, "outside its tile grid"},
             {"/v1/jobs/no-such-job/tiles/0/0.png", 404, "no-such-job"}}) {
        const HttpResponse answer = client.get(r.path);
        EXPECT_EQ(answer.status, r.status) << r.path << answer.body;
        EXPECT_NE(answer.json_body().value("detail", "").find(r.says), std::string::npos)
            << r.path << ": " << answer.body;
    }
}

TEST(WebPage, LayerExrIsTheJobsAovAlone) {
    TokenDaemon fixture;
    Daemon& daemon = *fixture.daemon;
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpClient client = daemon.client(kToken);
    const json job = {{"scene", {{"builtin", "cornell-box"}}},
                      {"integrator", "direct"},
                      {"image", {{"width", 40}, {"height", 24}, {"tile_size", 16}, {"spp", 1}}},
                      {"output", {{"aovs", {"albedo", "depth"}}, {"pixel_type", "float"}}}};
    const HttpResponse submitted = client.post("/v1/jobs", job.dump());
    ASSERT_EQ(submitted.status, 202) << submitted.body;
    const std::string id = submitted.json_body().at("id");
    const std::string base = "/v1/jobs/" + id;
    ASSERT_EQ(client.get(base + "/image.exr?wait=true").status, 200);
    const HttpResponse image = client.get(base + "/image.exr");
    const auto whole = decode_exr({reinterpret_cast<const uint8_t*>(image.body.data()), image.body.size()});
    ASSERT_TRUE(whole.has_value()) << whole.error().message;
    for (const std::string layer : {"albedo", "depth"}) {
        const HttpResponse answer = client.get(base + "/layers/" + layer + ".exr");
        ASSERT_EQ(answer.status, 200) << answer.body;
        EXPECT_EQ(answer.header("content-type"), "image/x-exr");
        EXPECT_NE(answer.header("content-disposition").find(id + "." + layer + ".exr"), std::string::npos);
        const auto alone = decode_exr({reinterpret_cast<const uint8_t*>(answer.body.data()), answer.body.size()});
        ASSERT_TRUE(alone.has_value()) << alone.error().message;
        EXPECT_TRUE(alone->aovs.empty());
        ASSERT_NE(whole->find_aov(layer), nullptr);
        EXPECT_TRUE(alone->beauty == *whole->find_aov(layer)) << layer;
    }
    const HttpResponse other = client.get(base + "/layers/normal.exr");
    EXPECT_EQ(other.status, 404);
    EXPECT_NE(other.json_body().value("detail", "").find("its output.aovs: albedo, depth"), std::string::npos)
        << other.body;
    EXPECT_EQ(daemon.client().get(base + "/layers/albedo.exr").status, 401);
}

/// puppeteer-core under PHOTOND_BINARY_DIR/npm-tools, installed with `npm` unless an earlier run
/// finished installing it; its directory, or empty with `error` saying why.
fs::path install_puppeteer(const std::string& npm, std::string& error) {
    const fs::path prefix = fs::path(PHOTOND_BINARY_DIR) / "npm-tools" /
                            ("puppeteer-core-" + std::string(kPuppeteerVersion));
    const fs::path finished = prefix / "installed";  // written last: a cut install is redone
    if (fs::exists(finished) && fs::exists(prefix / "node_modules" / "puppeteer-core")) return prefix;
    fs::remove_all(prefix);
    fs::create_directories(prefix);
    // puppeteer-core downloads no browser; the test uses Debian's chromium.
    const auto [status, output] = run_command(
        "PUPPETEER_SKIP_DOWNLOAD=1 npm_config_update_notifier=false " + npm + " install --prefix " +
        quoted(prefix.string()) + " --no-audit --no-fund --loglevel=error puppeteer-core@" +
        std::string(kPuppeteerVersion));
    if (status != 0 || !fs::exists(prefix / "node_modules" / "puppeteer-core")) {
        error = "npm could not install puppeteer-core@" + std::string(kPuppeteerVersion) + " into " +
                prefix.string() + " (is the npm registry reachable?):\n" + output;
        return {};
    }
    write_file(finished, std::string(kPuppeteerVersion) + "\n");
    return prefix;
}

/// Why the browser test cannot run here (a tool missing), or empty.
std::string missing_browser_tools() {
    for (const char* tool : {"node", "npm", "chromium"})
        if (program_path(tool).empty())
            return std::string(tool) + " is not installed (Debian packages nodejs, npm and chromium; "
                                       "`make deps` installs them)";
    return {};
}

/// Runs tests/server/web_page_browser.mjs against a daemon with a token; its RESULT document,
/// or a test failure.
json run_browser(const std::string& mode, json extra = json::object()) {
    const std::string node = program_path("node");
    const std::string npm = program_path("npm");
    const std::string chromium = program_path("chromium");
    std::string error;
    const fs::path puppeteer = install_puppeteer(npm, error);
    if (puppeteer.empty()) {
        ADD_FAILURE() << error;
        return nullptr;
    }
    TokenDaemon fixture;
    Daemon& daemon = *fixture.daemon;
    if (!daemon.started()) {
        ADD_FAILURE() << daemon.first_line() << daemon.log();
        return nullptr;
    }
    const char* screenshots = std::getenv("PHOTOND_WEB_SCREENSHOTS");
    json options = {{"mode", mode},
                    {"base", "http://127.0.0.1:" + std::to_string(daemon.port())},
                    {"token", kToken},
                    {"chromium", chromium},
                    {"puppeteer", puppeteer.string()},
                    {"screenshots", screenshots ? json(screenshots) : json(nullptr)}};
    options.update(extra);
    const fs::path script = fs::path(PHOTOND_SOURCE_DIR) / "tests" / "server" / "web_page_browser.mjs";
    const auto [status, output] =
        run_command(quoted(node) + " " + quoted(script.string()) + " " + quoted(options.dump()));
    std::cout << output;
    const size_t at = output.rfind("RESULT ");
    if (status != 0 || at == std::string::npos) {
        ADD_FAILURE() << "the browser script failed (exit " << status << "):\n" << output << daemon.log();
        return nullptr;
    }
    json result = json::parse(output.substr(at + 7, output.find('\n', at) - at - 7), nullptr, false);
    if (result.contains("error")) ADD_FAILURE() << result["error"].get<std::string>() << "\n" << daemon.log();
    return result;
}

double median(const json& values) {
    std::vector<double> v;
    for (const json& x : values)
        if (x.is_number()) v.push_back(x.get<double>());
    if (v.empty()) return 1e9;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

TEST(WebPage, InChromium) {
    if (const std::string missing = missing_browser_tools(); !missing.empty()) GTEST_SKIP() << missing;
    // Not const: a key the script did not write reads as null (operator[] on a const json is
    // undefined behaviour for a missing key).
    json r = run_browser("short");
    ASSERT_TRUE(r.is_object());
    EXPECT_TRUE(r["errors"].empty()) << r["errors"].dump(2);

    // The token: asked for, refused when wrong, kept in the tab's session storage.
    EXPECT_NE(r.value("token_question", "").find("bearer token"), std::string::npos) << r["token_question"];
    EXPECT_NE(r.value("token_refused_question", "").find("refused"), std::string::npos)
        << r["token_refused_question"];
    EXPECT_EQ(r.value("token_in_session_storage", ""), kToken);

    // The job with its own exposure: the canvas, made of its 10 x 8 tiles alone, is preview.png.
    json& fixed = r["fixed_exposure"];
    EXPECT_EQ(fixed["canvas"], json({320, 240}));
    EXPECT_EQ(fixed["shown"], json({320, 240}));  // small frames are shown as they are
    EXPECT_EQ(fixed["differing_pixels"], 0) << fixed.dump(2);
    EXPECT_EQ(fixed["tiles_drawn"], 80);
    EXPECT_EQ(fixed["final_source"], "tiles");
    EXPECT_LT(fixed["black_pixels"].get<int>(), 320 * 240 / 2);  // a picture, not a black canvas
    EXPECT_TRUE(fixed["tile_errors"].empty()) << fixed["tile_errors"];
    EXPECT_EQ(fixed["status"]["state"], "done");
    EXPECT_EQ(fixed["texts"]["state"], "done");
    EXPECT_FALSE(fixed["texts"]["plan_rows"].empty());
    EXPECT_EQ(fixed["texts"]["plan_rows"].size(), fixed["status"]["plan"].size());
    EXPECT_GE(fixed["texts"]["timing_rows"].size(), fixed["status"]["timings"].size());
    EXPECT_EQ(fixed["texts"]["downloads"],
              json({"image.exr (beauty, albedo, normal)", "albedo.exr", "normal.exr", "preview.png"}));
    for (const char* download : {"image.exr", "albedo.exr"}) {
        const json file = r.value("downloads", json::object()).value(download, json::object());
        EXPECT_GT(file.value("bytes", 0), 1000) << download;
        EXPECT_TRUE(file.value("exr_magic", false)) << download;
    }

    // Automatic exposure: the canvas ends as preview.png too.
    json& automatic = r["automatic_exposure"];
    EXPECT_EQ(automatic["differing_pixels"], 0) << automatic.dump(2);
    EXPECT_TRUE(automatic["tile_errors"].empty()) << automatic["tile_errors"];

    // Cancel from the job's page.
    EXPECT_EQ(r["cancel"]["status"], "cancelled") << r["cancel"].dump(2);
    EXPECT_EQ(r["cancel"]["texts"]["state"], "cancelled");

    // A scene that does not exist: the form says why, marks the field (scene.path) and stays.
    const std::string bad = r["bad_scene"].value("error", "");
    EXPECT_NE(bad.find("no scene file 'no/such/scene.gltf'"), std::string::npos) << bad;
    EXPECT_TRUE(r["bad_scene"].value("marked", false));
    EXPECT_EQ(r["bad_scene"]["hash"], "#/");
    EXPECT_GE(r["queue_rows"].size(), 3u);

    // The goals (README.md, "The web page").
    const double first_paint = median(r["first_paint_ms"]);
    json& latency = fixed["latency_ms"];
    const double peak_mb = r["memory_peak"].value("pss_mb", 1e9);
    std::cout << "first paint (ms, 5 loads of the page): " << r["first_paint_ms"] << ", median " << first_paint
              << "\ntile latency, event to canvas (ms), job of 80 tiles: " << latency
              << "\nautomatic-exposure job: " << automatic["latency_ms"]
              << "\nbrowser memory peak: " << r["memory_peak"] << "\n";
    // Time goals are benchmarks (`make bench-web`): on a shared, loaded CI machine a first paint
    // measured in milliseconds is noise, so ctest prints them and asserts them only when asked.
    if (std::getenv("PHOTOND_WEB_TIME_GOALS") != nullptr) {
        EXPECT_LT(first_paint, 200.0);
        EXPECT_LT(latency.value("median", 1e9), 50.0);
    }
    EXPECT_LT(r["memory_peak"].value("page_renderer_rss_mb", 1e9), 500.0);
    EXPECT_GT(peak_mb, 0.0);
}

// `make test-web-large`: a 4096 x 4096 job (tiles of 32: 16,384 tiles) assembled on the page.
TEST(WebPage, DISABLED_LargeJobInChromium) {
    const char* size_text = std::getenv("PHOTOND_WEB_LARGE_SIZE");
    const int size = size_text ? std::atoi(size_text) : 4096;
    if (const std::string missing = missing_browser_tools(); !missing.empty()) GTEST_SKIP() << missing;
    json r = run_browser("large", {{"large_size", size}});
    ASSERT_TRUE(r.is_object());
    EXPECT_TRUE(r["errors"].empty()) << r["errors"].dump(2);
    const json& large = r["large"];
    const int tiles = ((size + 31) / 32) * ((size + 31) / 32);
    EXPECT_EQ(large["tiles_drawn"], tiles);
    EXPECT_EQ(large["canvas"], json({size, size}));
    EXPECT_EQ(large["differing_pixels"], 0);
    // Shown smaller by a whole factor (server/web/tile_canvas.js), and not black.
    const int shrink = (size + 1279) / 1280;
    EXPECT_EQ(large["shown"], json({(size + shrink - 1) / shrink, (size + shrink - 1) / shrink}));
    EXPECT_LT(large["shown_black_fraction"].get<double>(), 0.5);
    EXPECT_TRUE(large["tile_errors"].empty()) << large["tile_errors"];
    const json& peak = r["memory_peak"];
    const json& before = r["memory_before_job"];
    std::cout << size << "x" << size << " job, " << tiles << " tiles, " << large["seconds"]
              << " s\ntile latency (ms): " << large["latency_ms"]
              << "\nbrowser memory with the page open, before the job: " << before
              << "\nbrowser memory peak during the job: " << peak << "\n"
              << "page: renderer RSS " << peak.value("page_renderer_rss_mb", 0.0) << " MB + JS heap "
              << peak.value("js_heap_used_mb", 0.0) << " MB; the whole browser (every process, PSS) "
              << peak.value("pss_mb", 0.0) << " MB, of which " << before.value("pss_mb", 0.0)
              << " MB before the job\n";
    // The goal: the page holds the job within 500 MB. Its renderer process (canvas, decoded tiles,
    // the JS heap inside it) and what the job adds to the whole browser.
    EXPECT_LT(peak.value("page_renderer_rss_mb", 1e9), 500.0);
    EXPECT_LT(peak.value("pss_mb", 1e9) - before.value("pss_mb", 0.0), 500.0);
}

}  // namespace
}  // namespace photond::test
