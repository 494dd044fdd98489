// Real glTF content as users bring it: every Khronos sample model under tests/data/gltf-samples
// (unmodified, each with its license) renders through `photond render`, lit by its own lights or
// the default environment, with every pixel finite and something visible.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/image/exr_io.h"

namespace {

namespace fs = std::filesystem;

const std::string kPhotond = std::string(PHOTOND_BINARY_DIR) + "/server/photond";
const fs::path kSamples = fs::path(PHOTOND_TEST_DATA_DIR) / "gltf-samples";

std::vector<std::string> sample_names() {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(kSamples)) {
        if (entry.is_directory()) names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
}

std::string run(const std::string& arguments, int* exit_code) {
    FILE* pipe = popen((kPhotond + " " + arguments + " 2>&1").c_str(), "r");
    std::string output;
    char buffer[4096];
    while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
    const int status = pclose(pipe);
    *exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return output;
}

class GltfSample : public ::testing::TestWithParam<std::string> {};

TEST_P(GltfSample, RendersVisibleAndFiniteUnderItsLightsOrTheDefaultSky) {
    const std::string name = GetParam();
    const fs::path file = kSamples / name / "glTF" / (name + ".gltf");
    ASSERT_TRUE(fs::exists(file)) << file;
    const fs::path dir = fs::temp_directory_path() / ("gltf_samples_test_" + std::to_string(::getpid()) + "_" + name);
    fs::create_directories(dir);
    int exit_code = 0;
    const std::string output = run("render " + file.string() + " --preset preview --width 48 --height 48 --quiet " +
                                       "--set output.pixel_type=float -o " + (dir / "a.exr").string() +
                                       " --stats-json " + (dir / "s.json").string(),
                                   &exit_code);
    ASSERT_EQ(exit_code, 0) << output;
    const auto image = photond::read_exr(dir / "a.exr");
    ASSERT_TRUE(image.has_value()) << image.error().message;
    double sum = 0.0;
    for (const photond::Color& c : image->beauty.pixels()) {
        ASSERT_TRUE(photond::is_finite(c)) << name;
        sum += photond::average(c);
    }
    const double mean = sum / static_cast<double>(image->beauty.pixel_count());

    std::ifstream in(dir / "s.json");
    std::stringstream text;
    text << in.rdbuf();
    const nlohmann::json stats = nlohmann::json::parse(text.str());
    const nlohmann::json& environment = stats.at("plan").at(0);
    EXPECT_EQ(environment.at("pass"), "environment");
    // Only the models with lights of their own go without the default sky: two with punctual
    // lights, and EmissiveStrengthTest, whose glowing cubes are the whole model (they emit more
    // than a white sky would send in; emissive labels and details do not keep the sky away).
    const bool has_lights =
        name == "LightsPunctualLamp" || name == "IridescenceSuzanne" || name == "EmissiveStrengthTest";
    EXPECT_EQ(environment.at("enabled").get<bool>(), !has_lights) << environment.dump();
    // Under the white sky a model shows at about its albedo; by its own lamps it is dimmer.
    EXPECT_GT(mean, has_lights ? 0.0 : 0.02) << name << " renders black";
    fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(KhronosSamples, GltfSample, ::testing::ValuesIn(sample_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
