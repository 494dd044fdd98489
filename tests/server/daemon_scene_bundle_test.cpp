// Scene bundles against the real daemon (POST /v1/scenes with a zip, tar or tar.gz of a .gltf and
// its sibling files): uploaded, rendered by id, and equal to rendering the same files from disk;
// and every sandbox rule and limit refused with a message that names the entry or the limit.
#include <gtest/gtest.h>

#include <memory>
#include <set>

#include "core/image/exr_io.h"
#include "tests/server/bundle_archives.h"
#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

constexpr int kMaxEntries = 16;  // --max-bundle-entries of the daemon under test
constexpr int kMaxMb = 1;        // --max-bundle-mb

json quad_job(const json& scene) {
    return {{"scene", scene},
            {"integrator", "direct"},
            {"camera",
             {{"look_from", {0.5, 0.5, 2.0}}, {"look_at", {0.5, 0.5, 0.0}}, {"vfov_deg", 40}}},
            {"image", {{"width", 32}, {"height", 32}, {"spp", 1}, {"tile_size", 16}}}};
}

/// Renders the job and returns its image.
ImageLayers render(const HttpClient& client, const json& job) {
    const HttpResponse submitted = client.post("/v1/jobs", job.dump());
    EXPECT_EQ(submitted.status, 202) << submitted.body;
    const std::string id = submitted.json_body().value("id", "");
    const json status = wait_for_status(client, id, is_terminal_state);
    EXPECT_EQ(status.value("state", ""), "done") << status.dump();
    const HttpResponse exr = client.get("/v1/jobs/" + id + "/image.exr?wait=true");
    EXPECT_EQ(exr.status, 200);
    auto image = decode_exr({reinterpret_cast<const uint8_t*>(exr.body.data()), exr.body.size()});
    EXPECT_TRUE(image) << (image ? "" : image.error().message);
    return image ? std::move(image).value() : ImageLayers{};
}

class DaemonSceneBundle : public ::testing::Test {
protected:
    void SetUp() override {
        fs::create_directories(root_ / "textures");
        for (const auto& [path, data] : textured_quad_files()) write_file(root_ / path, data);
        daemon_ = std::make_unique<Daemon>(
            dir_.path() / "cache",
            std::vector<std::string>{"--scene-root", root_.string(), "--max-bundle-entries",
                                     std::to_string(kMaxEntries), "--max-bundle-mb",
                                     std::to_string(kMaxMb)});
        ASSERT_TRUE(daemon_->started()) << daemon_->log();
    }

    /// The problem an upload of `archive` gets, with the status and a detail containing each
    /// of `parts`; then checks that nothing of the refused bundle stayed in the scene store.
    void expect_refused(const std::string& archive, int status,
                        const std::vector<std::string>& parts) {
        const HttpResponse response = daemon_->client().post("/v1/scenes", archive);
        EXPECT_EQ(response.status, status) << response.body;
        EXPECT_EQ(response.header("content-type"), "application/problem+json");
        const std::string detail = response.json_body().value("detail", "");
        for (const std::string& part : parts)
            EXPECT_NE(detail.find(part), std::string::npos) << "'" << part << "' in: " << detail;
        std::error_code ignored;
        for (const auto& entry : fs::directory_iterator(scenes_dir(), ignored))
            ADD_FAILURE() << "left in the scene store: " << entry.path();
    }

    fs::path scenes_dir() const { return dir_.path() / "cache" / "scenes"; }

    TempDir dir_{"daemon_scene_bundle"};
    fs::path root_ = dir_.path() / "root";
    std::unique_ptr<Daemon> daemon_;
};

TEST_F(DaemonSceneBundle, ZipTarAndTarGzRenderLikeTheFilesOnDisk) {
    const HttpClient client = daemon_->client();
    const ImageLayers from_disk = render(client, quad_job({{"path", "scene.gltf"}}));
    ASSERT_FALSE(from_disk.beauty.empty());
    float brightest = 0.0f;
    for (const Color& c : from_disk.beauty.pixels()) brightest = std::max(brightest, c.y);
    EXPECT_GT(brightest, 0.0f) << "the quad is not lit";

    const auto files = textured_quad_files();
    // A tar of a folder ("scene/...") is found inside its one top-level directory.
    const std::vector<std::pair<std::string, std::vector<ArchiveEntry>>> bundles = {
        {"zip", as_entries(files)},
        {"tar.gz", as_entries(files)},
        {"tar", as_entries(files, "scene/")}};
    std::set<std::string> ids;
    for (const auto& [format, entries] : bundles) {
        SCOPED_TRACE(format);
        const std::string archive = make_archive(entries, format);
        const HttpResponse created =
            client.post("/v1/scenes", archive, {{"Content-Type", "application/octet-stream"}});
        ASSERT_EQ(created.status, 201) << created.body;
        const json info = created.json_body();
        EXPECT_EQ(info.at("bundle"), format);
        EXPECT_EQ(info.at("format"), "gltf");
        EXPECT_EQ(info.at("entry"), format == "tar" ? "scene/scene.gltf" : "scene.gltf");
        EXPECT_EQ(info.at("files"), 3);
        EXPECT_EQ(info.at("bytes"), archive.size());
        EXPECT_EQ(info.at("textures"), 1);  // read from the bundle's textures/checker.png
        EXPECT_EQ(info.at("lights"), 1);
        const std::string id = info.at("id");
        ids.insert(id);
        EXPECT_EQ(client.get("/v1/scenes/" + id).json_body().value("entry", ""), info.at("entry"));
        EXPECT_EQ(client.post("/v1/scenes", archive).status, 200);  // the same bytes again

        const ImageLayers uploaded = render(client, quad_job({{"id", id}}));
        ASSERT_EQ(uploaded.beauty.width(), from_disk.beauty.width());
        EXPECT_TRUE(uploaded.beauty.pixels() == from_disk.beauty.pixels());
    }
    EXPECT_EQ(ids.size(), 3u);
    EXPECT_EQ(client.get("/v1/scenes").json_body().at("scenes").size(), 3u);

    // Deleting a bundle removes its unpacked files; its jobs are then refused.
    const std::string id = *ids.begin();
    EXPECT_TRUE(fs::is_directory(scenes_dir() / (id.substr(7) + ".bundle")));
    EXPECT_EQ(client.request("DELETE", "/v1/scenes/" + id).status, 204);
    EXPECT_FALSE(fs::exists(scenes_dir() / (id.substr(7) + ".bundle")));
    EXPECT_EQ(client.get("/v1/scenes/" + id).status, 404);
    EXPECT_EQ(client.post("/v1/jobs", quad_job({{"id", id}}).dump()).status, 422);
}

TEST_F(DaemonSceneBundle, EnvironmentImagesAreReadFromTheUploadedBundle) {
    const HttpClient client = daemon_->client();
    // A Radiance RGBE sky of 4 x 1 texels of grey 0.5 (rows under 8 texels are not run-length
    // encoded), in the bundle beside the scene.
    std::string hdr = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 4\n";
    for (int i = 0; i < 4; ++i) hdr += std::string(4, char(128));
    auto files = textured_quad_files();
    files.push_back({"skies/grey.hdr", hdr});
    const HttpResponse created = client.post("/v1/scenes", make_archive(as_entries(files), "zip"));
    ASSERT_EQ(created.status, 201) << created.body;
    const std::string id = created.json_body().at("id");

    // Looking away from the quad, the camera sees the sky: 0.5 x intensity 3.
    json job = quad_job({{"id", id}});
    job["camera"] = {{"look_from", {0.5, 0.5, 2.0}}, {"look_at", {0.5, 0.5, 4.0}}, {"vfov_deg", 40}};
    job["environment"] = {{"image", "skies/grey.hdr"}, {"intensity", 3}};
    const ImageLayers sky = render(client, job);
    ASSERT_FALSE(sky.beauty.empty());
    for (const Color& c : sky.beauty.pixels()) ASSERT_NEAR(c.y, 1.5f, 1e-3f);

    // Not in the bundle, or outside it: refused at submission, naming the field.
    for (const std::string image : {"skies/none.hdr", "../root/skies/grey.hdr"}) {
        job["environment"] = {{"image", image}};
        const HttpResponse refused = client.post("/v1/jobs", job.dump());
        EXPECT_EQ(refused.status, 422) << image << ": " << refused.body;
        EXPECT_EQ(refused.json_body().value("field", ""), "environment.image") << refused.body;
    }
    // A plain upload has no files besides the scene.
    const HttpResponse plain = client.post("/v1/scenes", read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "texture.gltf"));
    ASSERT_EQ(plain.status, 201) << plain.body;
    json plain_job = quad_job({{"id", plain.json_body().at("id")}});
    plain_job["environment"] = {{"image", "sky.hdr"}};
    const HttpResponse no_bundle = client.post("/v1/jobs", plain_job.dump());
    EXPECT_EQ(no_bundle.status, 422) << no_bundle.body;
    EXPECT_NE(no_bundle.body.find("bundle"), std::string::npos) << no_bundle.body;
}

TEST_F(DaemonSceneBundle, AGltfWithUstarAtTheTarMagicsOffsetIsNoTar) {
    // A self-contained .gltf whose byte 257 starts "ustar" (where a tar has its magic).
    const std::string gltf = read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "texture.gltf");
    const std::string text = "{" + std::string(255, ' ') + "\"ustar\": 1," + gltf.substr(1);
    ASSERT_EQ(text.substr(257, 5), "ustar");
    const HttpResponse created = daemon_->client().post("/v1/scenes", text);
    ASSERT_EQ(created.status, 201) << created.body;
    EXPECT_EQ(created.json_body().at("format"), "gltf");
    EXPECT_FALSE(created.json_body().contains("bundle"));
}

TEST_F(DaemonSceneBundle, SandboxRulesAndLimitsAreRefusedByName) {
    const auto files = textured_quad_files();
    using Kind = ArchiveEntry::Kind;
    auto with = [&](ArchiveEntry extra) {
        std::vector<ArchiveEntry> entries = as_entries(files);
        entries.push_back(std::move(extra));
        return entries;
    };
    expect_refused(make_archive(with({"../x", "escape"}), "tar"), 422, {"'../x'", "'..'"});
    expect_refused(make_archive(with({"textures/../../x", "escape"}), "zip"), 422,
                   {"'textures/../../x'", "'..'"});
    expect_refused(make_archive(with({"/tmp/photond_absolute", "escape"}), "tar"), 422,
                   {"'/tmp/photond_absolute'", "absolute"});
    expect_refused(make_archive(with({"link.png", "", Kind::Symlink, "/etc/passwd"}), "zip"), 422,
                   {"'link.png'", "symbolic link"});
    expect_refused(make_archive(with({"link.png", "", Kind::Symlink, "quad.bin"}), "tar.gz"), 422,
                   {"'link.png'", "symbolic link"});
    expect_refused(make_archive(with({"hard.bin", "", Kind::Hardlink, "quad.bin"}), "tar"), 422,
                   {"'hard.bin'", "hard link"});
    expect_refused(make_archive(with({"quad.bin", "twice"}), "tar"), 422, {"'quad.bin'", "twice"});

    // Limits: 413 naming the limit and its flag.
    std::vector<ArchiveEntry> many = as_entries(files);
    for (int i = 0; i < kMaxEntries; ++i) many.push_back({"extra/" + std::to_string(i), "x"});
    expect_refused(make_archive(many, "zip"), 413,
                   {std::to_string(kMaxEntries) + " entries", "--max-bundle-entries"});
    // A zip bomb in small: 2 MiB of zeros deflate to a few kB.
    const std::string zeros(size_t{2 * kMaxMb} << 20, '\0');
    const std::string bomb = make_archive(with({"bomb.bin", zeros}), "zip");
    ASSERT_LT(bomb.size(), size_t{64} << 10);
    expect_refused(bomb, 413, {std::to_string(kMaxMb) + " MiB", "--max-bundle-mb", "'bomb.bin'"});
    expect_refused(make_archive(with({"bomb.bin", zeros}), "tar.gz"), 413,
                   {"--max-bundle-mb", "'bomb.bin'"});

    // The glTF file: exactly one at the top level.
    std::vector<ArchiveEntry> without_gltf = as_entries(files);
    without_gltf.erase(without_gltf.begin());
    expect_refused(make_archive(without_gltf, "zip"), 422,
                   {"no .gltf or .glb", "'quad.bin'", "'textures/'"});
    expect_refused(make_archive(with({"other.glb", files[0].second}), "zip"), 422,
                   {"2 glTF files", "'other.glb'", "'scene.gltf'"});
    // A sibling file the glTF names but the bundle lacks: the loader's error names it.
    std::vector<ArchiveEntry> no_texture = as_entries(files);
    no_texture.pop_back();
    expect_refused(make_archive(no_texture, "zip"), 422, {"textures/checker.png"});
    // Neither a bundle nor glTF.
    expect_refused(std::string("PK\x03\x04 this is no zip", 20), 422, {"zip"});

    EXPECT_EQ(daemon_->client().get("/healthz").status, 200);
    EXPECT_TRUE(daemon_->client().get("/v1/scenes").json_body().at("scenes").empty());
}

}  // namespace
}  // namespace photond::test
