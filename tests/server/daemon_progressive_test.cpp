// Progressive jobs through the real daemon (README.md, "Progressive previews"): the preview's
// tiles cover the frame before any final tile, are served with ?preview=true until their final
// tiles replace them, are never kept for a resume, cost a pass of their own, and change no byte
// of the final image; the job field is a boolean, on by default, and `photond render` ignores it.
#include <gtest/gtest.h>

#include <set>

#include "core/image/exr_io.h"
#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

/// A photon-map job whose irradiance-cache prepass lasts a while (the `final` preset's gathering),
/// so that the preview is whole long before the first final tile.
json progressive_job() {
    return {{"scene", {{"builtin", "cornell-box"}}},
            {"preset", "final"},
            {"image", {{"width", 256}, {"height", 192}, {"spp", 2}, {"tile_size", 32}}},
            {"photons", {{"global", 40000}, {"caustic", 20000}}},
            {"output", {{"pixel_type", "float"}, {"aovs", {"caustic", "albedo", "depth"}}}}};
}

constexpr size_t kTiles = 8 * 6;  // 256 x 192 in tiles of 32

std::string submit(const HttpClient& client, const json& job) {
    const HttpResponse submitted = client.post("/v1/jobs", job.dump());
    EXPECT_EQ(submitted.status, 202) << submitted.body;
    return submitted.json_body().value("id", "");
}

class DaemonProgressive : public ::testing::Test {
protected:
    TempDir dir_{"daemon_progressive"};
};

TEST_F(DaemonProgressive, PreviewTilesCoverTheFrameBeforeTheFinalTilesReplaceThem) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string id = submit(client, progressive_job());

    // In the stream, right after the event that completes the preview (the prepass is running,
    // no final tile yet): a tile's preview is served, its final pixels are not.
    HttpResponse preview_tile, final_tile, preview_png_tile;
    const auto events = follow_events(client, id, [&](const SseEvent& e) {
        if (e.type == "tile" && e.data.value("preview", false) &&
            e.data.value("preview_tiles_done", 0u) == kTiles) {
            preview_tile = client.get("/v1/jobs/" + id + "/tiles/3/2.exr?preview=true");
            final_tile = client.get("/v1/jobs/" + id + "/tiles/3/2.exr");
            preview_png_tile = client.get("/v1/jobs/" + id + "/tiles/3/2.png?preview=true");
        }
        return true;
    });
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back().type, "done") << events.back().data.dump();

    std::set<std::pair<int, int>> preview_tiles, final_tiles;
    size_t preview_done = 0;
    for (const SseEvent& e : events) {
        if (e.type != "tile") continue;
        const std::pair<int, int> tile{e.data.at("tx").get<int>(), e.data.at("ty").get<int>()};
        if (e.data.value("preview", false)) {
            EXPECT_TRUE(final_tiles.empty()) << "a preview tile after a final one: " << e.data.dump();
            EXPECT_TRUE(preview_tiles.insert(tile).second) << "preview tile twice: " << e.data.dump();
            EXPECT_EQ(e.data.at("preview_tiles_done").get<size_t>(), ++preview_done);
            EXPECT_EQ(e.data.at("tiles_done"), 0) << "preview tiles are not final ones";
            EXPECT_NE(e.data.at("url").get<std::string>().find("?preview=true"), std::string::npos);
        } else {
            EXPECT_FALSE(e.data.contains("preview_tiles_done"));
            EXPECT_TRUE(final_tiles.insert(tile).second) << "final tile twice: " << e.data.dump();
        }
    }
    // The preview covers the whole frame, in the final render's tiles, and each is replaced.
    EXPECT_EQ(preview_tiles.size(), kTiles);
    EXPECT_EQ(final_tiles, preview_tiles);

    ASSERT_EQ(preview_tile.status, 200) << preview_tile.body;
    EXPECT_EQ(preview_tile.header("x-tile-kind"), "preview");
    EXPECT_EQ(final_tile.status, 404) << "the final tile was finished during the prepass?";
    ASSERT_EQ(preview_png_tile.status, 200) << preview_png_tile.body;
    EXPECT_EQ(preview_png_tile.header("x-tile-kind"), "preview");
    // The preview tile is of the frame: not black, the tile's rectangle.
    const auto decoded = decode_tile_exr({reinterpret_cast<const uint8_t*>(preview_tile.body.data()),
                                          preview_tile.body.size()});
    ASSERT_TRUE(decoded.has_value()) << decoded.error().message;
    EXPECT_EQ(decoded->rect, (PixelRect{96, 64, 128, 96}));
    EXPECT_EQ(decoded->tile.aovs.size(), 3u);
    double sum = 0.0;
    for (const Color& c : decoded->tile.beauty.pixels()) sum += c.x + c.y + c.z;
    EXPECT_GT(sum, 0.0);

    // Done: ?preview=true gives the final tile now, the same bytes as without it.
    const HttpResponse after = client.get("/v1/jobs/" + id + "/tiles/3/2.exr?preview=true");
    EXPECT_EQ(after.status, 200);
    EXPECT_EQ(after.header("x-tile-kind"), "final");
    EXPECT_TRUE(after.body == client.get("/v1/jobs/" + id + "/tiles/3/2.exr").body);

    // The preview is a pass of its own, before the prepass, and the passes add up to the total.
    const json status = client.get("/v1/jobs/" + id).json_body();
    const json& statistics = status.at("statistics");
    ASSERT_TRUE(statistics.contains("preview")) << statistics.dump();
    EXPECT_EQ(statistics.at("preview").at("tiles"), kTiles);
    EXPECT_GE(statistics.at("preview").at("stride").get<int>(), 2);
    std::vector<std::string> names;
    double sum_of_passes = 0.0;
    for (const json& pass : statistics.at("passes")) {
        names.push_back(pass.at("name"));
        sum_of_passes += pass.at("seconds").get<double>();
    }
    const auto at = [&](const std::string& name) { return std::find(names.begin(), names.end(), name) - names.begin(); };
    ASSERT_LT(at("preview"), static_cast<long>(names.size())) << statistics.at("passes").dump();
    EXPECT_LT(at("preview"), at("irradiance_cache"));
    EXPECT_LT(at("photon_map_store"), at("preview"));
    const double total = statistics.at("total_seconds").get<double>();
    EXPECT_NEAR(sum_of_passes, total, 0.02 * total) << statistics.at("passes").dump();
    EXPECT_TRUE(status.at("timings").contains("preview")) << status.at("timings").dump();
    // ... and /metrics has it among the passes.
    EXPECT_NE(client.get("/metrics").body.find("photond_pass_duration_seconds_count{pass=\"preview\"} 1"),
              std::string::npos);
}

TEST_F(DaemonProgressive, TheFinalImageIsByteIdenticalWithoutThePreview) {
    // Two daemons with caches of their own, so that neither image is made of the other's
    // irradiance cache: the progressive job's EXR, AOV layers included, is the non-progressive's.
    std::string images[2];
    for (int progressive = 0; progressive < 2; ++progressive) {
        Daemon daemon(dir_.path() / (progressive ? "progressive" : "plain"));
        ASSERT_TRUE(daemon.started()) << daemon.log();
        json job = progressive_job();
        job["progressive"] = progressive == 1;
        const std::string id = submit(daemon.client(), job);
        const auto events = follow_events(daemon.client(), id);
        size_t previews = 0;
        for (const SseEvent& e : events) previews += e.type == "tile" && e.data.value("preview", false);
        EXPECT_EQ(previews, progressive ? kTiles : 0u);
        const json status = daemon.client().get("/v1/jobs/" + id).json_body();
        ASSERT_EQ(status.at("state"), "done") << status.dump();
        EXPECT_EQ(status.at("statistics").contains("preview"), progressive == 1);
        EXPECT_EQ(status.at("job").at("progressive"), progressive == 1);
        images[progressive] = daemon.client().get("/v1/jobs/" + id + "/image.exr").body;
    }
    ASSERT_GT(images[0].size(), 100000u);  // a whole float image with its layers (compressed)
    EXPECT_TRUE(images[0] == images[1]) << "the progressive job's EXR differs from the plain one's";
}

TEST_F(DaemonProgressive, PreviewTilesAreNeverKeptForAResume) {
    const fs::path cache = dir_.path() / "cache";
    Daemon daemon(cache);
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    const std::string id = submit(client, progressive_job());
    const fs::path tiles = cache / "jobs" / id / "tiles";
    const auto kept_tiles = [&] {
        size_t kept = 0;
        std::error_code ignored;
        for (const auto& entry : fs::directory_iterator(tiles, ignored)) kept += entry.path().extension() == ".tile";
        return kept;
    };
    // Once the preview is whole and before any final tile: nothing kept.
    size_t kept_after_preview = 1000;
    bool seen = false;
    follow_events(client, id, [&](const SseEvent& e) {
        if (!seen && e.type == "tile" && e.data.value("preview", false) &&
            e.data.value("preview_tiles_done", 0u) == kTiles) {
            seen = true;
            kept_after_preview = kept_tiles();
            EXPECT_EQ(client.get("/v1/jobs/" + id).json_body().at("progress").at("tiles_done"), 0);
        }
        return true;
    });
    ASSERT_TRUE(seen);
    EXPECT_EQ(kept_after_preview, 0u) << "preview tiles were written to the tile journal";
    EXPECT_EQ(client.get("/v1/jobs/" + id).json_body().at("state"), "done");
}

TEST_F(DaemonProgressive, TheFieldIsABooleanOnByDefault) {
    Daemon daemon(dir_.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.log();
    const HttpClient client = daemon.client();
    json job = {{"scene", {{"builtin", "cornell-box"}}},
                {"integrator", "direct"},
                {"image", {{"width", 64}, {"height", 48}, {"spp", 1}}}};
    for (const json& wrong : {json("yes"), json(1), json(nullptr)}) {
        job["progressive"] = wrong;
        const HttpResponse refused = client.post("/v1/jobs", job.dump());
        EXPECT_EQ(refused.status, 422) << wrong.dump() << ": " << refused.body;
        EXPECT_EQ(refused.json_body().value("field", ""), "progressive") << refused.body;
    }
    job.erase("progressive");
    const std::string id = submit(client, job);
    EXPECT_EQ(client.get("/v1/jobs/" + id).json_body().at("job").at("progressive"), true);
    const json schema = client.get("/v1/openapi.json").json_body();
    EXPECT_NE(schema.dump().find("\"progressive\""), std::string::npos);
    const json done = wait_for_status(client, id, is_terminal_state);
    EXPECT_EQ(done.at("statistics").at("preview").at("tiles"), 4) << done.dump();  // 64 x 48 in tiles of 32

    // `photond render` streams no tiles: it renders no preview whatever the job says.
    const fs::path stats = dir_.path() / "stats.json";
    const auto [exit_code, output] =
        run_command(kPhotondBinary + " render builtin:cornell-box --integrator direct --width 64 --height 48 "
                    "--spp 1 --quiet --set progressive=true --stats-json " + stats.string() + " -o " +
                    (dir_.path() / "out.exr").string() + " 2>&1");
    ASSERT_EQ(exit_code, 0) << output;
    const json statistics = json::parse(read_file(stats));
    EXPECT_FALSE(statistics.contains("preview")) << statistics.dump();
    for (const json& pass : statistics.at("passes")) EXPECT_NE(pass.at("name"), "preview");
}

}  // namespace
}  // namespace photond::test
