// EXT_texture_webp: a texture's WebP image, decoded by libwebp, is the one used, not the PNG
// fallback beside it, from a file or a .glb's bufferView; a data: URI of WebP (which tinygltf
// does not decode), an animated WebP and a corrupt one are refused by name. The WebP images are written here with
// libwebp's lossless encoder, so the texels must come back exactly.
#include <gtest/gtest.h>
#include <unistd.h>
#include <webp/encode.h>
#include <webp/mux.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/scene/gltf_loader.h"

namespace photond {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 4, kHeight = 2;

/// RGBA texels, row by row: distinct colours and alphas, so that a swapped channel or row shows.
std::vector<uint8_t> pattern() {
    std::vector<uint8_t> rgba;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x)
            rgba.insert(rgba.end(), {uint8_t(40 * x + 10), uint8_t(100 * y + 20), uint8_t(200 - 30 * x),
                                     uint8_t(255 - 60 * y)});
    return rgba;
}

std::vector<uint8_t> lossless_webp(const std::vector<uint8_t>& rgba) {
    uint8_t* out = nullptr;
    const size_t size = WebPEncodeLosslessRGBA(rgba.data(), kWidth, kHeight, kWidth * 4, &out);
    std::vector<uint8_t> bytes(out, out + size);
    WebPFree(out);
    return bytes;
}

/// Two frames of the pattern, the second with its colours inverted: an animated WebP.
std::vector<uint8_t> animated_webp(const std::vector<uint8_t>& rgba) {
    WebPAnimEncoderOptions options;
    WebPAnimEncoderOptionsInit(&options);
    WebPAnimEncoder* encoder = WebPAnimEncoderNew(kWidth, kHeight, &options);
    WebPConfig config;
    WebPConfigInit(&config);
    config.lossless = 1;
    std::vector<uint8_t> inverted = rgba;
    for (size_t i = 0; i < inverted.size(); ++i)
        if (i % 4 != 3) inverted[i] = uint8_t(255 - inverted[i]);
    const std::vector<uint8_t>* frames[] = {&rgba, &inverted};
    int timestamp = 0;
    for (const std::vector<uint8_t>* frame : frames) {
        WebPPicture picture;
        WebPPictureInit(&picture);
        picture.use_argb = 1;
        picture.width = kWidth;
        picture.height = kHeight;
        WebPPictureImportRGBA(&picture, frame->data(), kWidth * 4);
        WebPAnimEncoderAdd(encoder, &picture, timestamp, &config);
        WebPPictureFree(&picture);
        timestamp += 100;
    }
    WebPAnimEncoderAdd(encoder, nullptr, timestamp, nullptr);
    WebPData data;
    WebPDataInit(&data);
    WebPAnimEncoderAssemble(encoder, &data);
    std::vector<uint8_t> bytes(data.bytes, data.bytes + data.size);
    WebPDataClear(&data);
    WebPAnimEncoderDelete(encoder);
    return bytes;
}

void write_file(const fs::path& path, const std::vector<uint8_t>& bytes) {
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// Positions (4 x VEC3), texture coordinates (4 x VEC2), indices (6 x u16): a unit quad.
std::vector<uint8_t> quad_buffer() {
    const float positions[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const float uvs[8] = {0, 1, 1, 1, 1, 0, 0, 0};
    const uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
    std::vector<uint8_t> buffer(sizeof(positions) + sizeof(uvs) + sizeof(indices) + 2);  // + padding
    std::memcpy(buffer.data(), positions, sizeof(positions));
    std::memcpy(buffer.data() + sizeof(positions), uvs, sizeof(uvs));
    std::memcpy(buffer.data() + sizeof(positions) + sizeof(uvs), indices, sizeof(indices));
    return buffer;
}

/// The glTF JSON of the textured quad: its texture's WebP image is `webp_image` (an image
/// object), with the PNG fallback.png as the core source unless `fallback` is false.
std::string scene_json(const std::string& webp_image, const std::string& buffer, const std::string& extra_views,
                       bool fallback) {
    const std::string texture = fallback ? R"({"source": 1, "extensions": {"EXT_texture_webp": {"source": 0}}})"
                                         : R"({"extensions": {"EXT_texture_webp": {"source": 0}}})";
    const std::string required = fallback ? "" : R"("extensionsRequired": ["EXT_texture_webp"],)";
    return R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["EXT_texture_webp"], )" + required + R"(
  "buffers": [)" + buffer + R"(],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                  {"buffer": 0, "byteOffset": 80, "byteLength": 12})" + extra_views + R"(],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
  "images": [)" + webp_image + R"(, {"uri": "fallback.png"}],
  "textures": [)" + texture + R"(],
  "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}, "alphaMode": "BLEND"}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
  "nodes": [{"mesh": 0}],
  "scenes": [{"nodes": [0]}], "scene": 0
})";
}

void copy_fallback(const fs::path& dir) {
    fs::copy_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf-samples" / "TextureTransformTest" / "glTF" / "Error.png",
                  dir / "fallback.png", fs::copy_options::overwrite_existing);
}

/// scene.gltf beside quad.bin and fallback.png (the PNG of TextureTransformTest's "Error.png"),
/// its WebP image `webp_image` (texture.webp, which the test writes, unless given).
void write_scene(const fs::path& dir, bool fallback,
                 const std::string& webp_image = R"({"uri": "texture.webp", "mimeType": "image/webp"})") {
    copy_fallback(dir);
    const std::vector<uint8_t> buffer = quad_buffer();
    write_file(dir / "quad.bin", buffer);
    std::ofstream(dir / "scene.gltf")
        << scene_json(webp_image, R"({"uri": "quad.bin", "byteLength": )" + std::to_string(buffer.size()) + "}", "",
                      fallback);
}

/// scene.glb: the quad and the WebP image in its binary chunk, the image by a bufferView (as
/// exporters write a .glb).
void write_glb(const fs::path& dir, const std::vector<uint8_t>& webp) {
    copy_fallback(dir);
    std::vector<uint8_t> bin = quad_buffer();
    const size_t image_offset = bin.size();
    bin.insert(bin.end(), webp.begin(), webp.end());
    while (bin.size() % 4) bin.push_back(0);
    std::string json = scene_json(R"({"bufferView": 3, "mimeType": "image/webp"})",
                                  R"({"byteLength": )" + std::to_string(bin.size()) + "}",
                                  R"(, {"buffer": 0, "byteOffset": )" + std::to_string(image_offset) +
                                      R"(, "byteLength": )" + std::to_string(webp.size()) + "}",
                                  true);
    while (json.size() % 4) json.push_back(' ');
    const auto u32 = [](std::vector<uint8_t>& out, uint32_t v) {
        for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
    };
    std::vector<uint8_t> glb;
    u32(glb, 0x46546C67);  // "glTF"
    u32(glb, 2);
    u32(glb, uint32_t(12 + 8 + json.size() + 8 + bin.size()));
    u32(glb, uint32_t(json.size()));
    u32(glb, 0x4E4F534A);  // "JSON"
    glb.insert(glb.end(), json.begin(), json.end());
    u32(glb, uint32_t(bin.size()));
    u32(glb, 0x004E4942);  // "BIN\0"
    glb.insert(glb.end(), bin.begin(), bin.end());
    write_file(dir / "scene.glb", glb);
}

class GltfWebp : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("photond_webp_" + std::to_string(getpid()));
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    /// The refusal of dir_/name.
    std::string load_error(const std::string& name) const {
        Expected<Scene> scene = load_gltf_file(dir_ / name);
        EXPECT_FALSE(scene.has_value()) << name << " loaded";
        return scene ? std::string() : scene.error().message;
    }
    fs::path dir_;
};

void expect_pattern(const Scene& scene) {
    ASSERT_EQ(scene.textures.size(), 1u);
    const Texture& texture = *scene.textures[0];
    ASSERT_EQ(texture.width, kWidth);  // Error.png is 8x8
    ASSERT_EQ(texture.height, kHeight);
    ASSERT_EQ(texture.encoding, TexelEncoding::Srgb8);
    const std::vector<uint8_t> expected = pattern();
    ASSERT_EQ(texture.rgba8.size(), size_t(kWidth * kHeight));
    for (size_t i = 0; i < texture.rgba8.size(); ++i) {
        const uint32_t texel = texture.rgba8[i];
        for (int c = 0; c < 4; ++c) EXPECT_EQ((texel >> (8 * c)) & 0xff, expected[4 * i + size_t(c)]) << i << " " << c;
    }
}

TEST_F(GltfWebp, TheWebpImageIsUsedNotTheFallback) {
    write_file(dir_ / "texture.webp", lossless_webp(pattern()));
    write_scene(dir_, true);
    Expected<Scene> scene = load_gltf_file(dir_ / "scene.gltf");
    ASSERT_TRUE(scene.has_value()) << scene.error().message;
    expect_pattern(*scene);
    for (const std::string& w : scene->warnings) EXPECT_EQ(w.find("EXT_texture_webp"), std::string::npos) << w;
}

TEST_F(GltfWebp, AFileThatRequiresWebpWithoutFallbackLoads) {
    write_file(dir_ / "texture.webp", lossless_webp(pattern()));
    write_scene(dir_, false);
    Expected<Scene> scene = load_gltf_file(dir_ / "scene.gltf");
    ASSERT_TRUE(scene.has_value()) << scene.error().message;
    expect_pattern(*scene);
}

TEST_F(GltfWebp, AWebpInAGlbBufferViewIsUsed) {
    write_glb(dir_, lossless_webp(pattern()));
    Expected<Scene> scene = load_gltf_file(dir_ / "scene.glb");
    ASSERT_TRUE(scene.has_value()) << scene.error().message;
    expect_pattern(*scene);
}

TEST_F(GltfWebp, AWebpDataUriIsRefusedSayingWhereTheImageCanGo) {
    // tinygltf decodes no data:image/webp URI: the refusal says so, not "absolute or remote".
    write_scene(dir_, true,
                R"({"uri": "data:image/webp;base64,UklGRh4AAABXRUJQVlA4TBEAAAAvA0AAAAdQsiJXpv+BiOh/AAA=", "mimeType": "image/webp"})");
    const std::string error = load_error("scene.gltf");
    EXPECT_NE(error.find("uri 'data:image/webp;base64,...' is a data: URI of a type the glTF reader does not "
                         "decode (it reads buffers and PNG or JPEG images so; put a WebP image in a file or a "
                         "bufferView)"),
              std::string::npos)
        << error;
}

TEST_F(GltfWebp, AnAnimatedWebpIsRefusedAsSuch) {
    const std::vector<uint8_t> bytes = animated_webp(pattern());
    ASSERT_GT(bytes.size(), 12u);
    write_file(dir_ / "texture.webp", bytes);
    write_scene(dir_, true);
    const std::string error = load_error("scene.gltf");
    EXPECT_NE(error.find("image 0 (uri 'texture.webp') is an animated WebP"), std::string::npos) << error;
}

TEST_F(GltfWebp, ACorruptWebpIsAnErrorNamingTheImage) {
    std::vector<uint8_t> bytes = lossless_webp(pattern());
    bytes.resize(bytes.size() / 2);  // the RIFF header promises more
    write_file(dir_ / "texture.webp", bytes);
    write_scene(dir_, true);
    const std::string error = load_error("scene.gltf");
    EXPECT_NE(error.find("image 0 (uri 'texture.webp') cannot be decoded"), std::string::npos) << error;
}

}  // namespace
}  // namespace photond
