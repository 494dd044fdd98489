// Joining the EXRs of a frame's regions: the same bytes as the whole frame written at once, and
// parts that cannot make the frame refused by name.
#include "core/image/exr_assemble.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>
#include <vector>

namespace photond {
namespace {

namespace fs = std::filesystem;

class ExrAssemble : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() / ("photond_exr_assemble_test_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    /// Writes `rect` of `layers` as a region render writes it.
    fs::path write_part(const std::string& name, const ImageLayers& layers, PixelRect rect, ExrWriteOptions options) {
        options.data_window = rect;
        const fs::path path = dir_ / name;
        EXPECT_TRUE(write_exr(path, layers, options)) << name;
        return path;
    }

    fs::path dir_;
};

ImageLayers frame_layers(int width, int height, bool with_aov) {
    ImageLayers layers;
    layers.beauty = Image(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) layers.beauty.at(x, y) = Color(0.01f * x + 1.0f, 0.37f * y, 3.0f + x * y);
    if (with_aov) {
        Image albedo(width, height);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) albedo.at(x, y) = Color(0.5f, 0.001f * (x + y), 0.25f);
        layers.aovs.emplace_back("albedo", std::move(albedo));
    }
    return layers;
}

std::vector<uint8_t> read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST_F(ExrAssemble, RegionsJoinIntoTheBytesOfTheWholeFrame) {
    for (const ExrPixelType type : {ExrPixelType::Half, ExrPixelType::Float}) {
        const ImageLayers layers = frame_layers(70, 45, true);
        ExrWriteOptions options;
        options.pixel_type = type;
        options.tile_size = 16;
        // Regions that cut through tiles, in no particular order.
        const std::vector<fs::path> parts = {
            write_part("c.exr", layers, {0, 20, 33, 45}, options), write_part("a.exr", layers, {0, 0, 50, 20}, options),
            write_part("b.exr", layers, {50, 0, 70, 20}, options), write_part("d.exr", layers, {33, 20, 70, 45}, options)};
        const auto assembled = assemble_exr_parts(parts);
        ASSERT_TRUE(assembled.has_value()) << assembled.error().message;
        const auto whole = encode_exr(layers, options);
        ASSERT_TRUE(whole.has_value());
        EXPECT_EQ(assembled->bytes, *whole);
        EXPECT_EQ(assembled->width, 70);
        // One part alone covering the frame is the frame.
        const fs::path all = write_part("all.exr", layers, {0, 0, 70, 45}, options);
        EXPECT_EQ(read_bytes(all), *whole);
    }
}

TEST_F(ExrAssemble, PartsThatCannotMakeTheFrameAreRefusedByName) {
    const ImageLayers layers = frame_layers(40, 30, false);
    const ExrWriteOptions options;
    const fs::path left = write_part("left.exr", layers, {0, 0, 20, 30}, options);
    const fs::path right = write_part("right.exr", layers, {20, 0, 40, 30}, options);
    const fs::path wide = write_part("wide.exr", layers, {10, 0, 40, 30}, options);
    const fs::path top_right = write_part("top_right.exr", layers, {20, 0, 40, 12}, options);
    ASSERT_TRUE(assemble_exr_parts({left, right}).has_value());

    const auto overlap = assemble_exr_parts({left, wide});
    ASSERT_FALSE(overlap.has_value());
    EXPECT_NE(overlap.error().message.find("'" + wide.string() + "' and '" + left.string() + "' overlap in [10,20)x[0,30)"),
              std::string::npos)
        << overlap.error().message;

    const auto missing = assemble_exr_parts({left, top_right});
    ASSERT_FALSE(missing.has_value());
    EXPECT_NE(missing.error().message.find("360 pixel(s) within [20,40)x[12,30) are in no part"), std::string::npos)
        << missing.error().message;

    const ImageLayers other_frame = frame_layers(40, 31, false);
    const fs::path other = write_part("other.exr", other_frame, {20, 0, 40, 31}, options);
    const auto frames = assemble_exr_parts({left, other});
    ASSERT_FALSE(frames.has_value());
    EXPECT_NE(frames.error().message.find("regions of different frames"), std::string::npos) << frames.error().message;

    ExrWriteOptions float_options;
    float_options.pixel_type = ExrPixelType::Float;
    const fs::path float_part = write_part("float.exr", layers, {20, 0, 40, 30}, float_options);
    const auto types = assemble_exr_parts({left, float_part});
    ASSERT_FALSE(types.has_value());
    EXPECT_NE(types.error().message.find("pixel type"), std::string::npos) << types.error().message;

    const ImageLayers with_aov = frame_layers(40, 30, true);
    const fs::path aov_part = write_part("aov.exr", with_aov, {20, 0, 40, 30}, options);
    const auto channels = assemble_exr_parts({left, aov_part});
    ASSERT_FALSE(channels.has_value());
    EXPECT_NE(channels.error().message.find("different channels"), std::string::npos) << channels.error().message;

    // A tile as the daemon streams it (a scanline EXR) is no region render: refused by name.
    const fs::path scanline = dir_ / "scanline.exr";
    {
        const auto tile = encode_tile_exr(copy_rect(layers, {20, 0, 40, 30}), {20, 0, 40, 30}, 40, 30, ExrPixelType::Half);
        ASSERT_TRUE(tile.has_value());
        std::ofstream(scanline, std::ios::binary).write(reinterpret_cast<const char*>(tile->data()),
                                                         static_cast<std::streamsize>(tile->size()));
    }
    const auto foreign = assemble_exr_parts({scanline});
    ASSERT_FALSE(foreign.has_value());
    EXPECT_NE(foreign.error().message.find("'" + scanline.string() + "': not a region of a photond render"),
              std::string::npos)
        << foreign.error().message;
    EXPECT_FALSE(assemble_exr_parts({dir_ / "absent.exr"}).has_value());
}

}  // namespace
}  // namespace photond
