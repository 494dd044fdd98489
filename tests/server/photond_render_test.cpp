// `photond render` as a user runs it: real processes, real files.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "core/image/exr_io.h"
#include "core/image/png_preview.h"

#ifndef PHOTOND_TEST_DATA_DIR
#error "PHOTOND_TEST_DATA_DIR must be defined"
#endif

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kPhotond = std::string(PHOTOND_BINARY_DIR) + "/server/photond";

struct CommandResult {
    int exit_code;
    std::string output;  // stdout and stderr
};

CommandResult run(const std::string& arguments) {
    const std::string command = kPhotond + " " + arguments + " 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    std::string output;
    char buffer[4096];
    while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
    const int status = pclose(pipe);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

class PhotondRender : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("photond_render_test_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

TEST_F(PhotondRender, SameBytesForOneAndTwoThreads) {
    const std::string common = "render builtin:cornell-box --integrator path --spp 2 --width 64 --height 48 --quiet ";
    const auto one = run(common + "--threads 1 -o " + (dir_ / "one.exr").string());
    const auto two = run(common + "--threads 2 -o " + (dir_ / "two.exr").string() + " --preview " +
                         (dir_ / "two.png").string() + " --stats-json " + (dir_ / "stats.json").string());
    ASSERT_EQ(one.exit_code, 0) << one.output;
    ASSERT_EQ(two.exit_code, 0) << two.output;
    const std::string a = read_file(dir_ / "one.exr"), b = read_file(dir_ / "two.exr");
    ASSERT_FALSE(a.empty());
    EXPECT_EQ(a, b);
    EXPECT_TRUE(fs::file_size(dir_ / "two.png") > 100);

    const auto image = photond::read_exr(dir_ / "one.exr");
    ASSERT_TRUE(image.has_value()) << image.error().message;
    EXPECT_EQ(image->beauty.width(), 64);
    EXPECT_EQ(image->beauty.height(), 48);
    for (const auto& c : image->beauty.pixels()) ASSERT_TRUE(photond::is_finite(c));

    const auto stats = nlohmann::json::parse(read_file(dir_ / "stats.json"));
    EXPECT_EQ(stats.at("integrator"), "path");
    EXPECT_EQ(stats.at("threads"), 2);
    EXPECT_GT(stats.at("rays").get<uint64_t>(), 64u * 48u * 2u);
    EXPECT_EQ(stats.at("job").at("image").at("spp"), 2);
}

TEST_F(PhotondRender, RegionsRenderedApartAssembleIntoTheBytesOfTheWholeFrame) {
    // photon-map with the irradiance cache: each region builds the frame's cache (a region's own
    // prepass gave other records, relMSE 1.5e-4 against the frame on cornell-box-diffuse, and
    // seams); `photond assemble` joins the parts into the frame's file, byte for byte.
    const std::string common = "render builtin:cornell-box-diffuse --preset preview --width 72 --height 40 "
                               "--set image.tile_size=16 --quiet ";
    const fs::path whole = dir_ / "whole.exr";
    ASSERT_EQ(run(common + "-o " + whole.string()).exit_code, 0);
    const std::vector<std::string> regions = {"0,0,40,24", "40,0,72,24", "0,24,30,40", "30,24,72,40"};
    std::string parts;
    for (size_t i = 0; i < regions.size(); ++i) {
        const fs::path part = dir_ / ("part" + std::to_string(i) + ".exr");
        const auto rendered = run(common + "--set 'image.region=[" + regions[i] + "]' -o " + part.string());
        ASSERT_EQ(rendered.exit_code, 0) << rendered.output;
        parts += " " + part.string();
    }
    const fs::path assembled = dir_ / "assembled.exr";
    const auto joined = run("assemble -o " + assembled.string() + parts);
    ASSERT_EQ(joined.exit_code, 0) << joined.output;
    EXPECT_TRUE(read_file(assembled) == read_file(whole)) << "the assembled frame differs from the whole render";
    // Three of the four parts leave a hole, named.
    const auto short_of_one = run("assemble -o " + (dir_ / "short.exr").string() + " " + (dir_ / "part0.exr").string() +
                                  " " + (dir_ / "part1.exr").string() + " " + (dir_ / "part2.exr").string());
    EXPECT_EQ(short_of_one.exit_code, 1);
    EXPECT_NE(short_of_one.output.find("672 pixel(s) within [30,72)x[24,40) are in no part"), std::string::npos)
        << short_of_one.output;
    EXPECT_FALSE(fs::exists(dir_ / "short.exr"));
}

TEST_F(PhotondRender, ACacheDirectoryPreparedOnceServesLaterRendersWithTheSameBytes) {
    // A render farm's steps: --caches-only builds the photon maps and the irradiance cache into a
    // shared directory; later renders (here a region and the whole view) take both from there.
    const std::string common = "render builtin:cornell-box-diffuse --preset preview --width 48 --height 32 --quiet ";
    const std::string cache = "--cache-dir " + (dir_ / "cache").string() + " ";
    const auto refused = run(common + "--caches-only");
    EXPECT_EQ(refused.exit_code, 2);
    EXPECT_NE(refused.output.find("--caches-only: give the --cache-dir"), std::string::npos) << refused.output;
    const auto prepared = run(common + cache + "--caches-only --stats-json " + (dir_ / "prepared.json").string());
    ASSERT_EQ(prepared.exit_code, 0) << prepared.output;
    const json built = json::parse(read_file(dir_ / "prepared.json"));
    EXPECT_EQ(built.at("photons").at("cache"), "miss");
    EXPECT_EQ(built.at("irradiance_cache").at("cache"), "miss");
    ASSERT_EQ(run(common + cache + "-o " + (dir_ / "cached.exr").string() + " --stats-json " +
                  (dir_ / "cached.json").string())
                  .exit_code,
              0);
    const json taken = json::parse(read_file(dir_ / "cached.json"));
    EXPECT_EQ(taken.at("photons").at("cache"), "hit");
    EXPECT_EQ(taken.at("irradiance_cache").at("cache"), "hit");
    EXPECT_EQ(taken.at("irradiance_cache").at("key"), built.at("irradiance_cache").at("key"));
    ASSERT_EQ(run(common + "-o " + (dir_ / "alone.exr").string()).exit_code, 0);
    EXPECT_TRUE(read_file(dir_ / "cached.exr") == read_file(dir_ / "alone.exr"));
}

TEST_F(PhotondRender, AViewsIrradianceCacheStartsFromAnEarlierViewsDeterministically) {
    // irradiance_cache.start_from: the second view's cache begins with the first view's records
    // and adds records only where they do not serve; the same for any thread count.
    const std::string common = "render builtin:cornell-box-diffuse --preset preview --width 64 --height 48 --quiet ";
    const std::string second_view =
        "--set 'camera.look_from=[1.8,2.2,-7.0]' --set 'camera.look_at=[3.2,2.5,2.8]' --set camera.vfov_deg=38 ";
    const std::string cache = "--cache-dir " + (dir_ / "cache").string() + " ";
    ASSERT_EQ(run(common + cache + "-o " + (dir_ / "first.exr").string() + " --stats-json " +
                  (dir_ / "first.json").string())
                  .exit_code,
              0);
    const json first = json::parse(read_file(dir_ / "first.json")).at("irradiance_cache");
    const std::string start = "--set irradiance_cache.start_from=" + first.at("key").get<std::string>() + " ";
    for (const char* threads : {"1", "2"}) {
        const auto chained = run(common + cache + second_view + start + "--threads " + threads + " -o " +
                                 (dir_ / (std::string("chained") + threads + ".exr")).string() + " --stats-json " +
                                 (dir_ / "chained.json").string());
        ASSERT_EQ(chained.exit_code, 0) << chained.output;
        fs::remove_all(dir_ / "cache" / "render-caches");  // built again: the same bytes
        ASSERT_EQ(run(common + cache + "-o " + (dir_ / "first.exr").string()).exit_code, 0);
    }
    EXPECT_TRUE(read_file(dir_ / "chained1.exr") == read_file(dir_ / "chained2.exr"));
    const json chained = json::parse(read_file(dir_ / "chained.json")).at("irradiance_cache");
    EXPECT_EQ(chained.at("start_from"), first.at("key"));
    EXPECT_EQ(chained.at("records_reused"), first.at("records"));
    EXPECT_GT(chained.at("records").get<uint64_t>(), first.at("records").get<uint64_t>());
    ASSERT_EQ(run(common + cache + second_view + "-o " + (dir_ / "alone.exr").string() + " --stats-json " +
                  (dir_ / "alone.json").string())
                  .exit_code,
              0);
    const json alone = json::parse(read_file(dir_ / "alone.json")).at("irradiance_cache");
    EXPECT_NE(alone.at("key"), chained.at("key"));
    // It needs the store, the key must be there, and be a key.
    const auto no_store = run(common + second_view + start + "-o " + (dir_ / "x.exr").string());
    EXPECT_EQ(no_store.exit_code, 1);
    EXPECT_NE(no_store.output.find("needs --cache-dir"), std::string::npos) << no_store.output;
    const auto missing = run(common + cache + second_view + "--set irradiance_cache.start_from=rc1-" +
                             std::string(64, 'a') + " -o " + (dir_ / "x.exr").string());
    EXPECT_EQ(missing.exit_code, 1);
    EXPECT_NE(missing.output.find("no render cache rc1-aaaa"), std::string::npos) << missing.output;
    const auto malformed = run(common + cache + "--set irradiance_cache.start_from=view1 -o " + (dir_ / "x.exr").string());
    EXPECT_EQ(malformed.exit_code, 2);
    EXPECT_NE(malformed.output.find("irradiance_cache.start_from: must be a render-cache key"), std::string::npos)
        << malformed.output;
    EXPECT_FALSE(fs::exists(dir_ / "x.exr"));
}

TEST_F(PhotondRender, ThePassesAddUpToTheTotal) {
    // Every second accounted for: the photon pass in its parts (the irradiance precomputed at
    // photons was in no pass: at 10M photons most of the time), on a trace and on a cache hit.
    // Large enough that the few microseconds between passes stay far below 2 % on a loaded machine.
    const std::string common = "render builtin:cornell-box-diffuse --preset preview --width 256 --height 192 --quiet "
                               "--cache-dir " + (dir_ / "cache").string() + " --stats-json ";
    for (const char* run_name : {"traced", "cached"}) {
        const fs::path stats_file = dir_ / (std::string(run_name) + ".json");
        ASSERT_EQ(run(common + stats_file.string() + " -o " + (dir_ / "out.exr").string()).exit_code, 0);
        const json stats = json::parse(read_file(stats_file));
        double sum = 0.0;
        std::set<std::string> names;
        for (const json& pass : stats.at("passes")) {
            sum += pass.at("seconds").get<double>();
            names.insert(pass.at("name").get<std::string>());
        }
        const double total = stats.at("total_seconds").get<double>();
        EXPECT_GT(total, 0.0);
        EXPECT_NEAR(sum, total, 0.02 * total) << run_name << ": " << stats.at("passes").dump();
        for (const char* name : {"scene", "acceleration", "photon_tracing", "photon_kdtree", "photon_irradiance",
                                 "photon_map_store", "irradiance_cache", "render"})
            EXPECT_TRUE(names.contains(name)) << run_name << " lacks the pass " << name;
    }
}

TEST_F(PhotondRender, JobFileAndSetOverrides) {
    std::ofstream(dir_ / "job.json") << R"({"scene": {"builtin": "furnace"}, "integrator": "direct",
        "image": {"width": 16, "height": 8, "spp": 1}})";
    const auto r = run("render --job " + (dir_ / "job.json").string() + " --set image.width=24 --quiet " +
                       "--stats-json " + (dir_ / "s.json").string() + " -o " + (dir_ / "f.exr").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto stats = nlohmann::json::parse(read_file(dir_ / "s.json"));
    EXPECT_EQ(stats.at("width"), 24);
    EXPECT_EQ(stats.at("integrator"), "direct");
}

TEST_F(PhotondRender, BadInputGetsAClearErrorNamingTheField) {
    const std::string out = " -o " + (dir_ / "x.exr").string();
    auto r = run("render builtin:cornell-box --set image.sppp=3" + out);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.output.find("image.sppp"), std::string::npos) << r.output;

    r = run("render builtin:no-such-scene" + out);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("no-such-scene"), std::string::npos) << r.output;

    r = run("render builtin:cornell-box --width -5" + out);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.output.find("image.width"), std::string::npos) << r.output;

    std::ofstream(dir_ / "broken.json") << "{\"scene\": ";
    r = run("render --job " + (dir_ / "broken.json").string() + out);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.output.find("malformed JSON"), std::string::npos) << r.output;

    r = run("render " + (dir_ / "missing.gltf").string() + out);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("missing.gltf"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "x.exr"));
}

/// The mean of an EXR's beauty pixels (every one finite).
photond::Color mean_of(const fs::path& path) {
    const auto image = photond::read_exr(path);
    EXPECT_TRUE(image.has_value()) << (image ? "" : image.error().message);
    if (!image) return photond::Color(0.0f);
    photond::DVec3 sum(0.0);
    for (const auto& c : image->beauty.pixels()) {
        EXPECT_TRUE(photond::is_finite(c));
        sum += photond::DVec3(c);
    }
    return photond::Color(sum / static_cast<double>(image->beauty.pixel_count()));
}

const fs::path kLightlessScene = fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "texture.gltf";

TEST_F(PhotondRender, SceneWithoutLightRendersUnderTheDefaultEnvironmentAndSaysSo) {
    const std::string common = "render " + kLightlessScene.string() + " --width 32 --height 32 --spp 2 ";
    const auto r = run(common + "-o " + (dir_ / "a.exr").string() + " --stats-json " + (dir_ / "s.json").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("default: a uniform white environment"), std::string::npos) << r.output;
    EXPECT_GT(photond::max_component(mean_of(dir_ / "a.exr")), 0.1f);
    const auto stats = nlohmann::json::parse(read_file(dir_ / "s.json"));
    EXPECT_EQ(stats.at("lighting").at("environment"), "default");
    EXPECT_EQ(stats.at("plan").at(0).at("pass"), "environment");
    EXPECT_EQ(stats.at("plan").at(0).at("enabled"), true);

    // Turned off, the job fails and says what to add.
    const auto off = run(common + "--set environment=null -o " + (dir_ / "b.exr").string());
    EXPECT_NE(off.exit_code, 0);
    EXPECT_NE(off.output.find("no light"), std::string::npos) << off.output;
    EXPECT_NE(off.output.find("\"lights\""), std::string::npos) << off.output;
    EXPECT_FALSE(fs::exists(dir_ / "b.exr"));

    // A light from the job lights it instead, and the default stays off.
    const auto lit = run(common + "--set 'lights=[{\"type\": \"directional\", \"direction\": [0, 0, -1], "
                                  "\"irradiance\": 3}]' --integrator direct -o " +
                         (dir_ / "c.exr").string() + " --stats-json " + (dir_ / "c.json").string());
    ASSERT_EQ(lit.exit_code, 0) << lit.output;
    const auto lit_stats = nlohmann::json::parse(read_file(dir_ / "c.json"));
    EXPECT_EQ(lit_stats.at("lighting").at("job_lights"), 1);
    EXPECT_EQ(lit_stats.at("lighting").at("environment"), "");
    EXPECT_GT(photond::max_component(mean_of(dir_ / "c.exr")), 0.0f);

    // A light that cannot contribute is a warning, not silence.
    const auto dark = run(common + "--set 'lights=[{\"type\": \"point\", \"position\": [0, 0, 2], "
                                   "\"intensity\": 0}]' --integrator direct -o " +
                          (dir_ / "d.exr").string() + " --stats-json " + (dir_ / "d.json").string());
    ASSERT_EQ(dark.exit_code, 0) << dark.output;
    EXPECT_NE(dark.output.find("lights[0] (point) has no intensity"), std::string::npos) << dark.output;
    const auto dark_stats = nlohmann::json::parse(read_file(dir_ / "d.json"));
    EXPECT_NE(dark_stats.at("warnings").dump().find("adds no light"), std::string::npos) << dark_stats.dump();
}

/// A Radiance RGBE file of one row of `width` texels of grey 0.5 (uncompressed: rows under 8
/// texels are never run-length encoded).
void write_grey_hdr(const fs::path& path, int width) {
    std::ofstream out(path, std::ios::binary);
    out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X " << width << "\n";
    for (int i = 0; i < width; ++i) out << char(128) << char(128) << char(128) << char(128);  // 0.5 each
}

TEST_F(PhotondRender, EnvironmentImagesComeFromTheSceneRootOnly) {
    // An EXR sky of one colour: camera rays that miss the scene see exactly it.
    photond::ImageLayers sky;
    sky.beauty = photond::Image(4, 2);
    for (auto& c : sky.beauty.pixels()) c = photond::Color(0.25f, 0.5f, 1.0f);
    ASSERT_TRUE(photond::write_exr(dir_ / "sky.exr", sky, {photond::ExrPixelType::Float, 32}).is_ok());
    write_grey_hdr(dir_ / "grey.hdr", 4);
    fs::copy_file(kLightlessScene, dir_ / "scene.gltf");
    for (const auto& entry : fs::directory_iterator(kLightlessScene.parent_path())) {
        if (entry.path().extension() == ".png" || entry.path().extension() == ".bin")
            fs::copy_file(entry.path(), dir_ / entry.path().filename(), fs::copy_options::skip_existing);
    }
    const std::string common = "render " + (dir_ / "scene.gltf").string() +
                               " --integrator direct --width 16 --height 16 --spp 1 ";
    for (const auto& [file, expected] : {std::pair<std::string, photond::Color>{"sky.exr", {0.25f, 0.5f, 1.0f}},
                                         {"grey.hdr", {0.5f, 0.5f, 0.5f}}}) {
        const auto r = run(common + "--set 'environment={\"image\": \"" + file + "\", \"intensity\": 2}' " +
                           "--set camera.look_from=[0,0,50] --set camera.look_at=[0,0,100] -o " +
                           (dir_ / "e.exr").string());
        ASSERT_EQ(r.exit_code, 0) << r.output;
        const photond::Color mean = mean_of(dir_ / "e.exr");
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], 2.0f * expected[c], 2e-3f) << file;
    }
    // Outside the scene root, through a link or not, and missing files are refused by name.
    const fs::path outside = dir_.parent_path() / ("outside_" + std::to_string(::getpid()) + ".exr");
    fs::copy_file(dir_ / "sky.exr", outside, fs::copy_options::overwrite_existing);
    fs::create_symlink(outside, dir_ / "link.exr");
    auto r = run(common + "--set 'environment={\"image\": \"link.exr\"}' -o " + (dir_ / "x.exr").string());
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("outside the scene root"), std::string::npos) << r.output;
    r = run(common + "--set 'environment={\"image\": \"none.exr\"}' -o " + (dir_ / "x.exr").string());
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("none.exr"), std::string::npos) << r.output;
    std::ofstream(dir_ / "broken.hdr") << "#?RADIANCE\nnot really\n";
    r = run(common + "--set 'environment={\"image\": \"broken.hdr\"}' -o " + (dir_ / "x.exr").string());
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("broken.hdr"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "x.exr"));
    fs::remove(outside);
}

TEST_F(PhotondRender, PreviewTakesTheExposureAndTheFilmicCurve) {
    const std::string common =
        "render builtin:cornell-box --integrator direct --spp 1 --width 32 --height 24 --quiet "
        "--set output.pixel_type=float -o " + (dir_ / "a.exr").string() + " --preview ";
    const auto automatic = run(common + (dir_ / "auto.png").string());
    const auto flag = run(common + (dir_ / "flag.png").string() + " --exposure -1.5");
    const auto set = run(common + (dir_ / "set.png").string() + " --set output.exposure_ev=-1.5");
    ASSERT_EQ(automatic.exit_code, 0) << automatic.output;
    ASSERT_EQ(flag.exit_code, 0) << flag.output;
    ASSERT_EQ(set.exit_code, 0) << set.output;
    const auto image = photond::read_exr(dir_ / "a.exr");  // float: the very pixels rendered
    ASSERT_TRUE(image.has_value()) << image.error().message;

    auto expected = photond::encode_render_preview(image->beauty, -1.5f);
    ASSERT_TRUE(expected);
    const std::string manual(expected->begin(), expected->end());
    EXPECT_EQ(read_file(dir_ / "flag.png"), manual);
    EXPECT_EQ(read_file(dir_ / "set.png"), manual);
    auto automatic_png = photond::encode_render_preview(image->beauty);
    ASSERT_TRUE(automatic_png);
    EXPECT_EQ(read_file(dir_ / "auto.png"),
              std::string(automatic_png->begin(), automatic_png->end()));
    EXPECT_NE(read_file(dir_ / "auto.png"), manual);

    // The field is validated by name, through the flag as through --set.
    for (const std::string bad : {"--exposure 31", "--exposure bright", "--set output.exposure_ev=NaN"}) {
        const auto refused = run(common + (dir_ / "bad.png").string() + " " + bad);
        EXPECT_EQ(refused.exit_code, 2) << bad << ": " << refused.output;
        EXPECT_NE(refused.output.find("output.exposure_ev"), std::string::npos) << refused.output;
    }
    EXPECT_FALSE(fs::exists(dir_ / "bad.png"));
}

const fs::path kGltfData = fs::path(PHOTOND_TEST_DATA_DIR) / "gltf";

bool contains_warning(const nlohmann::json& warnings, const std::string& text) {
    for (const auto& w : warnings)
        if (w.get<std::string>().find(text) != std::string::npos) return true;
    return false;
}

TEST_F(PhotondRender, BadOutputsAndThreadCountsAreRefusedBeforeTheRenderAndLeaveNothing) {
    const std::string small = "render builtin:cornell-box --integrator direct --width 16 --height 16 --spp 1 ";
    // oneTBB failed inside its arena at 100,000 threads; serve caps at 4096, so does render.
    const auto threads = run(small + "--threads 100000 -o " + (dir_ / "t.exr").string());
    EXPECT_EQ(threads.exit_code, 2) << threads.output;
    EXPECT_NE(threads.output.find("--threads: at most 4096"), std::string::npos) << threads.output;
    // A missing output directory: refused up front, by name (it failed after the whole render).
    const auto missing = run(small + "-o " + (dir_ / "nowhere" / "m.exr").string());
    EXPECT_EQ(missing.exit_code, 2) << missing.output;
    EXPECT_NE(missing.output.find("nowhere does not exist"), std::string::npos) << missing.output;
    const auto preview = run(small + "-o " + (dir_ / "p.exr").string() + " --preview " + (dir_ / "no" / "p.png").string());
    EXPECT_EQ(preview.exit_code, 2) << preview.output;
    EXPECT_FALSE(fs::exists(dir_ / "p.exr"));
    // A statistics file that cannot be written once the render is done (no file can be made in
    // /proc, not even by root): no EXR is left behind.
    const auto stats = run(small + "-o " + (dir_ / "s.exr").string() + " --stats-json /proc/photond-test-stats.json");
    EXPECT_EQ(stats.exit_code, 1) << stats.output;
    EXPECT_FALSE(fs::exists(dir_ / "s.exr")) << "an EXR was left behind by a failed run";
    // A file where the statistics should go is a directory: refused up front as well.
    fs::create_directories(dir_ / "stats-dir");
    const auto dir_stats = run(small + "-o " + (dir_ / "d.exr").string() + " --stats-json " + (dir_ / "stats-dir").string());
    EXPECT_EQ(dir_stats.exit_code, 2) << dir_stats.output;
    EXPECT_FALSE(fs::exists(dir_ / "d.exr"));
}

TEST_F(PhotondRender, DeeplyNestedJobsAndGltfFilesAreRefusedByName) {
    // 100,000 levels overflowed the stack of the parsers; refused before parsing, exit 2 / 1.
    std::ofstream(dir_ / "deep.json") << ("{\"scene\": " + std::string(100000, '[') + std::string(100000, ']') + "}");
    const auto job = run("render --job " + (dir_ / "deep.json").string() + " -o " + (dir_ / "d.exr").string());
    EXPECT_EQ(job.exit_code, 2) << job.output;
    EXPECT_NE(job.output.find("nest more than 128 levels deep"), std::string::npos) << job.output;
    std::ofstream(dir_ / "deep.gltf") << ("{\"asset\": {\"version\": \"2.0\"}, \"extras\": " + std::string(100000, '{') +
                                       std::string(100000, '}') + "}");
    const auto gltf = run("render " + (dir_ / "deep.gltf").string() + " -o " + (dir_ / "g.exr").string());
    EXPECT_NE(gltf.exit_code, 0) << gltf.output;
    EXPECT_NE(gltf.output.find("deep.gltf: arrays and objects nest more than 128"), std::string::npos) << gltf.output;
    EXPECT_FALSE(fs::exists(dir_ / "g.exr"));
}

TEST_F(PhotondRender, RadianceCacheIsAPassThePlanAndTheStatisticsAccountFor) {
    // builtin:glossy-objects: the aluminium sphere (roughness 0.5) is cached, the sharper metals
    // keep their rays; the plan names both, the pass is timed, and the passes still add up.
    const std::string common = "render builtin:glossy-objects --preset preview --width 96 --height 64 --threads 2 ";
    const auto on = run(common + "--set radiance_cache.enabled=true --stats-json " + (dir_ / "on.json").string() +
                        " -o " + (dir_ / "on.exr").string());
    ASSERT_EQ(on.exit_code, 0) << on.output;
    EXPECT_NE(on.output.find("plan: radiance_cache run"), std::string::npos) << on.output;
    EXPECT_NE(on.output.find("cached in 8 bands: 'aluminium'"), std::string::npos) << on.output;
    EXPECT_NE(on.output.find("sharper than 16 bands resolve): 'gold'"), std::string::npos) << on.output;
    const json stats = json::parse(read_file(dir_ / "on.json"));
    EXPECT_GT(stats.at("radiance_cache").at("records").get<uint64_t>(), 10u);
    EXPECT_GT(stats.at("radiance_cache").at("interpolated_share").get<double>(), 0.9);
    double sum = 0.0;
    bool timed = false;
    for (const json& pass : stats.at("passes")) {
        sum += pass.at("seconds").get<double>();
        timed = timed || pass.at("name") == "radiance_cache";
    }
    EXPECT_TRUE(timed) << stats.at("passes").dump();
    EXPECT_NEAR(sum, stats.at("total_seconds").get<double>(), 0.02 * stats.at("total_seconds").get<double>());
    // Off (the presets' default): the plan says so and no records are made.
    const auto off = run(common + "--stats-json " + (dir_ / "off.json").string() + " -o " + (dir_ / "off.exr").string());
    ASSERT_EQ(off.exit_code, 0) << off.output;
    EXPECT_NE(off.output.find("plan: radiance_cache skipped  the job leaves it off"), std::string::npos) << off.output;
    EXPECT_FALSE(json::parse(read_file(dir_ / "off.json")).contains("radiance_cache"));
}

TEST_F(PhotondRender, GlossyCausticsLeaveNoBlotchesOnTheWallTheyLight) {
    // builtin:glossy-objects, preset final: the polished metals reflect the ceiling light onto
    // the back wall. Carried by final gathering, that light reached the irradiance cache's
    // records one gather ray in many, and the wall was blotched with the records' disks; the
    // caustic map carries it now. Compared in 8 x 8 blocks (where pixel noise averages out and
    // blotches do not) over the wall above the objects with the path-traced reference.
    const fs::path reference =
        fs::path(PHOTOND_SOURCE_DIR) / "bench" / "references" / "glossy-objects-256" / "path_half_a.exr";
    const auto r = run("render builtin:glossy-objects --preset final --width 256 --height 256 --threads 2 -o " +
                       (dir_ / "g.exr").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("plan: caustic_map  run      ideal specular and sharply glossy"), std::string::npos) << r.output;
    const auto compared = run("compare --json --block 8 --region 24,8,232,112 " + (dir_ / "g.exr").string() + " " +
                              reference.string());
    ASSERT_EQ(compared.exit_code, 0) << compared.output;
    const auto c = nlohmann::json::parse(compared.output);
    std::printf("glossy-objects back wall, 8 x 8 blocks against path: relMSE %.6f, p99 %.4f, mean %+.2f %%\n",
                c.at("relmse").get<double>(), c.at("p99").get<double>(), 100.0 * c.at("bias").get<double>());
    // Measured: relMSE 0.000138, p99 0.0138, mean -0.34 %; with only the lobes sharper than
    // roughness 0.25 in the caustic map (the torus's and the steel sphere's highlights read
    // through the cache) 0.000229, 0.0172 and -0.69 %; with none, 0.000853, 0.0747 and +1.03 %
    // (the path reference's two halves differ by 0.000008 here).
    EXPECT_LT(c.at("relmse").get<double>(), 0.00018);
    EXPECT_LT(c.at("p99").get<double>(), 0.03);
}

TEST_F(PhotondRender, ACausticMapThatWouldNotShowIsDroppedAndThePlanSaysSo) {
    // A wide mirror reflecting 0.1 % of the light: its caustic is under a thousandth of the light
    // where it lands (tests/data/gltf/generate.py).
    const auto r = run("render " + (kGltfData / "faint_caustics.gltf").string() +
                       " --width 16 --height 16 --spp 1 --set photons.caustic=2000"
                       " --set photons.global=2000 --set gather.rays=16 --stats-json " +
                       (dir_ / "s.json").string() + " -o " + (dir_ / "c.exr").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("plan: caustic_map  skipped"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("where they land the caustic is at most"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("photon map incomplete"), std::string::npos) << r.output;
    const auto stats = nlohmann::json::parse(read_file(dir_ / "s.json"));
    EXPECT_TRUE(stats.at("photons").at("caustic_dropped").get<bool>());
    EXPECT_LT(stats.at("photons").at("caustic_peak_ratio").get<double>(), 0.01);
    EXPECT_EQ(stats.at("photons").at("caustic_points").get<uint64_t>(), 0u);
}

TEST_F(PhotondRender, IncompletePhotonMapIsAWarningThatSaysWhatToChange) {
    // A mirror sends its light up to a small tile that catches about 1 in 4,700 photons: 2,000
    // caustic photons would need 9 M emissions, beyond the cap of 1,000 per requested photon
    // (tests/data/gltf/generate.py).
    const auto r = run("render " + (kGltfData / "sparse_caustics.gltf").string() +
                       " --width 16 --height 16 --spp 1 --set photons.caustic=2000"
                       " --set photons.global=2000 --set gather.rays=16 --stats-json " +
                       (dir_ / "s.json").string() + " -o " + (dir_ / "c.exr").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("  warning: photon map incomplete: the caustic map holds "),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("of the 2,000 photons requested"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("Set photons.caustic=0 to skip the caustic map"), std::string::npos)
        << r.output;
    const auto stats = nlohmann::json::parse(read_file(dir_ / "s.json"));
    EXPECT_FALSE(stats.at("photons").at("caustic_complete").get<bool>());
    EXPECT_TRUE(contains_warning(stats.at("warnings"), "photon map incomplete: the caustic map"))
        << stats.at("warnings").dump();
    EXPECT_FALSE(contains_warning(stats.at("warnings"), "the global map")) << stats.dump();
}

TEST_F(PhotondRender, MaterialMediaOnAThinWallIsRefused) {
    // transmission.gltf: PaneGlass is only on an open pane (a thin wall, no inside), BoxGlass on
    // a closed box (a solid).
    const std::string scene = (kGltfData / "transmission.gltf").string();
    const auto thin = run("render " + scene + " --integrator path --width 8 --height 8 --spp 1 --quiet " +
                          "--set 'material_media={\"PaneGlass\": {\"sigma_s\": 1}}' -o " + (dir_ / "t.exr").string());
    EXPECT_NE(thin.exit_code, 0) << thin.output;
    EXPECT_NE(thin.output.find("material 'PaneGlass' is only on open meshes"), std::string::npos) << thin.output;
    const auto solid = run("render " + scene + " --integrator path --width 8 --height 8 --spp 1 --quiet " +
                           "--set 'material_media={\"BoxGlass\": {\"sigma_s\": 1}}' -o " + (dir_ / "s.exr").string());
    EXPECT_EQ(solid.exit_code, 0) << solid.output;
}

TEST_F(PhotondRender, IgnoredGltfFeaturesAreWarningsEvenWhenQuiet) {
    const auto r = run("render " + (kGltfData / "warnings.gltf").string() +
                       " --integrator direct --width 8 --height 8 --spp 1 --quiet --stats-json " +
                       (dir_ / "s.json").string() + " -o " + (dir_ / "w.exr").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("photond render: warning: glTF extension KHR_materials_sheen is not "
                            "supported"),
              std::string::npos)
        << r.output;
    const auto stats = nlohmann::json::parse(read_file(dir_ / "s.json"));
    for (const char* name : {"KHR_materials_sheen", "KHR_materials_iridescence",
                             "KHR_materials_anisotropy", "point or line primitive"})
        EXPECT_TRUE(contains_warning(stats.at("warnings"), name)) << name << stats.dump();
    // A file without ignored features has an empty list.
    const auto clean = run("render builtin:furnace --integrator direct --width 8 --height 8 "
                           "--spp 1 --quiet --stats-json " + (dir_ / "f.json").string() + " -o " +
                           (dir_ / "f.exr").string());
    ASSERT_EQ(clean.exit_code, 0) << clean.output;
    EXPECT_EQ(nlohmann::json::parse(read_file(dir_ / "f.json")).at("warnings"),
              nlohmann::json::array());
}

TEST_F(PhotondRender, GltfCameraIndexesTheFilesCamerasArray) {
    const std::string scene = (kGltfData / "camera_indexing.gltf").string();
    const std::string common = " --integrator direct --width 8 --height 8 --spp 1 --quiet -o ";
    // cameras[0] is placed by no node: refused by name.
    auto r = run("render " + scene + " --set camera.gltf_camera=0" + common +
                 (dir_ / "0.exr").string());
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("camera.gltf_camera: camera 0 'Unplaced' is placed by no node"),
              std::string::npos)
        << r.output;
    // cameras[2] is orthographic, cameras[1] placed twice: both render.
    for (const char* index : {"1", "2"}) {
        r = run("render " + scene + " --set camera.gltf_camera=" + index + common +
                (dir_ / "c.exr").string());
        EXPECT_EQ(r.exit_code, 0) << index << ": " << r.output;
    }
    r = run("render " + scene + " --set camera.gltf_camera=3" + common + (dir_ / "3.exr").string());
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("the scene has 3 camera(s); index 3 does not exist"),
              std::string::npos)
        << r.output;
}

TEST_F(PhotondRender, QuadLightOfTheJobIsVisibleGeometryAlsoOnNormalMappedScenes) {
    // NormalTangentMirrorTest has normal textures, so its scene carries tangents: the quad's
    // vertices get theirs too. Seen straight on, the quad shows its radiance.
    const fs::path scene = fs::path(PHOTOND_TEST_DATA_DIR) / "gltf-samples" / "NormalTangentMirrorTest" / "glTF" /
                           "NormalTangentMirrorTest.gltf";
    const auto r = run("render " + scene.string() +
                       " --integrator direct --width 16 --height 16 --spp 1 --quiet --set output.pixel_type=float "
                       "--set 'lights=[{\"type\": \"quad\", \"position\": [-50, -50, 20], \"edge_u\": [100, 0, 0], "
                       "\"edge_v\": [0, 100, 0], \"radiance\": 3, \"color\": [1, 0.5, 0.25]}]' "
                       "--set camera.look_from=[0,0,10] --set camera.look_at=[0,0,30] -o " +
                       (dir_ / "q.exr").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const photond::Color mean = mean_of(dir_ / "q.exr");
    // Its front face looks towards +z, away from this camera: seen from behind, it is black...
    EXPECT_EQ(mean, photond::Color(0.0f));
    const auto front = run("render " + scene.string() +
                           " --integrator direct --width 16 --height 16 --spp 1 --quiet --set output.pixel_type=float "
                           "--set 'lights=[{\"type\": \"quad\", \"position\": [-50, -50, 20], \"edge_u\": [0, 100, 0], "
                           "\"edge_v\": [100, 0, 0], \"radiance\": 3, \"color\": [1, 0.5, 0.25]}]' "
                           "--set camera.look_from=[0,0,10] --set camera.look_at=[0,0,30] -o " +
                           (dir_ / "f.exr").string());
    ASSERT_EQ(front.exit_code, 0) << front.output;
    // ... and from the front, exactly its radiance times its colour.
    const photond::Color seen = mean_of(dir_ / "f.exr");
    EXPECT_NEAR(seen.x, 3.0f, 1e-3f);
    EXPECT_NEAR(seen.y, 1.5f, 1e-3f);
    EXPECT_NEAR(seen.z, 0.75f, 1e-3f);
}

}  // namespace

TEST_F(PhotondRender, FoggyBoxWithAVolumePhotonMapAgreesWithPath) {
    // The atmosphere through the photon-map integrator (a volume photon map for its multiple
    // scattering and the gather rays, light samples for its single scattering) against path
    // tracing, whose fog is free flights and light samples at every scattering event.
    const std::string common = "render builtin:cornell-box-diffuse --width 32 --height 32 --set output.pixel_type=float "
                               "--set 'atmosphere={\"sigma_a\": 0.05, \"sigma_s\": 0.5, \"g\": 0.3}' ";
    const auto path = run(common + "--integrator path --spp 1024 -o " + (dir_ / "path.exr").string());
    ASSERT_EQ(path.exit_code, 0) << path.output;
    const auto map = run(common + "-o " + (dir_ / "map.exr").string() + " --stats-json " + (dir_ / "s.json").string());
    ASSERT_EQ(map.exit_code, 0) << map.output;
    const auto stats = nlohmann::json::parse(read_file(dir_ / "s.json"));
    EXPECT_EQ(stats.at("photons").at("stored_volume"), 400000) << stats.dump();
    EXPECT_NE(map.output.find("volume_map"), std::string::npos) << map.output;
    const auto compared = run("compare --json " + (dir_ / "map.exr").string() + " " + (dir_ / "path.exr").string());
    ASSERT_EQ(compared.exit_code, 0) << compared.output;
    const auto c = nlohmann::json::parse(compared.output);
    const double bias = c.at("mean").get<double>() / c.at("reference_mean").get<double>() - 1.0;
    std::printf("photon-map against path in the foggy box: mean %+.2f %%\n", 100.0 * bias);
    EXPECT_LT(std::abs(bias), 0.04);
    // The same bytes for 1, 2 and 7 threads (photons, the volume map, the cache, the tiles).
    const std::string small = common + "--width 24 --height 16 --set photons.volume=20000 --set photons.global=20000 ";
    std::string first;
    for (const int threads : {1, 2, 7}) {
        const fs::path out = dir_ / ("t" + std::to_string(threads) + ".exr");
        const auto r = run(small + "--threads " + std::to_string(threads) + " -o " + out.string());
        ASSERT_EQ(r.exit_code, 0) << r.output;
        if (threads == 1) first = read_file(out);
        else EXPECT_EQ(read_file(out), first) << threads << " threads";
    }
    EXPECT_FALSE(first.empty());
}

TEST_F(PhotondRender, CompareListsTheWorstPixelsAndBlocks) {
    // Two real EXR files, 16 x 8 of 0.5, the image with one bright pixel at (13, 5) and a dimmer
    // one at (2, 1): `--worst` names them in order, with their share of the relMSE.
    photond::ImageLayers reference{photond::Image(16, 8, photond::Color(0.5f)), {}};
    photond::ImageLayers image = reference;
    image.beauty.at(13, 5) = photond::Color(2.5f);
    image.beauty.at(2, 1) = photond::Color(1.5f);
    ASSERT_TRUE(photond::write_exr(dir_ / "ref.exr", reference, {photond::ExrPixelType::Float, 32}).is_ok());
    ASSERT_TRUE(photond::write_exr(dir_ / "img.exr", image, {photond::ExrPixelType::Float, 32}).is_ok());
    const std::string files = (dir_ / "img.exr").string() + " " + (dir_ / "ref.exr").string();

    const auto pixels = run("compare --json --worst 2 " + files);
    ASSERT_EQ(pixels.exit_code, 0) << pixels.output;
    const auto p = json::parse(pixels.output);
    ASSERT_EQ(p.at("worst").size(), 2u) << pixels.output;
    EXPECT_EQ(p["worst"][0].at("x"), 13);
    EXPECT_EQ(p["worst"][0].at("y"), 5);
    EXPECT_NEAR(p["worst"][0].at("value")[0].get<double>(), 2.5, 1e-9);
    EXPECT_NEAR(p["worst"][0].at("reference")[0].get<double>(), 0.5, 1e-9);
    // (2^2) / (0.25 + 0.01) against (1^2) / 0.26: 4 of 5 of the sum.
    EXPECT_NEAR(p["worst"][0].at("share").get<double>(), 0.8, 1e-6);
    EXPECT_EQ(p["worst"][1].at("x"), 2);
    EXPECT_EQ(p["worst"][1].at("y"), 1);
    EXPECT_NEAR(p["worst"][1].at("share").get<double>(), 0.2, 1e-6);

    // In 4 x 4 blocks the bright pixel's block is named by its top-left pixel.
    const auto blocks = run("compare --worst 1 --block 4 " + files);
    ASSERT_EQ(blocks.exit_code, 0) << blocks.output;
    EXPECT_NE(blocks.output.find("worst block at (12, 4): relmse"), std::string::npos) << blocks.output;
    // Without --worst the JSON has no listing; a count that is no count is refused by name.
    EXPECT_FALSE(json::parse(run("compare --json " + files).output).contains("worst"));
    const auto bad = run("compare --worst none " + files);
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.output.find("--worst expects a count"), std::string::npos) << bad.output;
}
