// Inputs fuzz/gltf_fuzzer.cpp found, each refused with a message that names the member: numbers
// of the JSON that reached a conversion to an integer type out of its range (undefined
// behaviour, reported by UBSan; `make asan` runs this suite under it).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/scene/gltf_loader.h"

namespace photond {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path data_path(const std::string& name) {
    return fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / name;
}

std::vector<uint8_t> read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string load_error(const std::vector<uint8_t>& bytes, const std::string& name) {
    Expected<Scene> scene = load_gltf_memory(bytes, name);
    EXPECT_FALSE(scene.has_value()) << name << " loaded";
    return scene ? std::string() : scene.error().message;
}

std::vector<uint8_t> text_bytes(const json& document) {
    const std::string text = document.dump();
    return {text.begin(), text.end()};
}

/// A GLB's JSON chunk, and the GLB again with `document` as its JSON (binary chunk kept).
json glb_json(const std::vector<uint8_t>& glb) {
    uint32_t length = 0;
    std::memcpy(&length, glb.data() + 12, 4);
    return json::parse(glb.begin() + 20, glb.begin() + 20 + length);
}

std::vector<uint8_t> with_glb_json(const std::vector<uint8_t>& glb, const json& document) {
    uint32_t old_length = 0;
    std::memcpy(&old_length, glb.data() + 12, 4);
    std::string text = document.dump();
    text.append((4 - text.size() % 4) % 4, ' ');
    const std::vector<uint8_t> binary(glb.begin() + 20 + old_length, glb.end());
    std::vector<uint8_t> out(20 + text.size() + binary.size());
    const uint32_t header[5] = {0x46546C67u /* glTF */, 2, static_cast<uint32_t>(out.size()),
                                static_cast<uint32_t>(text.size()), 0x4E4F534Au /* JSON */};
    std::memcpy(out.data(), header, sizeof header);
    std::memcpy(out.data() + 20, text.data(), text.size());
    if (!binary.empty()) std::memcpy(out.data() + 20 + text.size(), binary.data(), binary.size());
    return out;
}

// The fuzzer's input: an EXT_meshopt_compression view whose byteLength lost its name
// ("byteLengtH"), which became -1 and was converted to uint64_t for the message.
TEST(GltfLoaderFuzz, MeshoptViewWithoutByteLengthIsRefused) {
    const std::string error =
        load_error(read_bytes(data_path("fuzz/meshopt_negative_offset.glb")), "fuzz.glb");
    EXPECT_NE(error.find("bufferView 1 (EXT_meshopt_compression): buffer, byteLength, byteStride "
                         "and count must be given as numbers"),
              std::string::npos)
        << error;
}

TEST(GltfLoaderFuzz, MeshoptNegativeOrHugeNumbersAreNamedAsWritten) {
    const std::vector<uint8_t> glb = read_bytes(data_path("compression/room_meshopt.glb"));
    json document = glb_json(glb);
    json& meshopt = document["bufferViews"][0]["extensions"]["EXT_meshopt_compression"];
    meshopt["byteOffset"] = -1;
    std::string error = load_error(with_glb_json(glb, document), "offset.glb");
    EXPECT_NE(error.find("bufferView 0 (EXT_meshopt_compression) (bytes -1 + 869) reaches past "
                         "the end of buffer 0"),
              std::string::npos)
        << error;
    meshopt["byteOffset"] = 0;
    meshopt["buffer"] = 1e300;
    error = load_error(with_glb_json(glb, document), "buffer.glb");
    EXPECT_NE(error.find("uses buffer 1.0000000000000001e+300, which does not exist"),
              std::string::npos)
        << error;
    meshopt["buffer"] = 0;
    meshopt["count"] = 1e30;
    error = load_error(with_glb_json(glb, document), "count.glb");
    EXPECT_NE(error.find("bufferView 0 (EXT_meshopt_compression) decodes to more than"),
              std::string::npos)
        << error;
    meshopt["count"] = 194;
    meshopt["byteStride"] = 1e30;
    error = load_error(with_glb_json(glb, document), "stride.glb");
    EXPECT_NE(error.find("has byteStride 1e+30 and count 194 (the stride must be "
                         "1 to 256)"),
              std::string::npos)
        << error;
}

TEST(GltfLoaderFuzz, TextureTransformTexCoordBeyondIntIsRefused) {
    json document = json::parse(read_bytes(data_path("texture_transform.gltf")));
    document["materials"][1]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
            ["KHR_texture_transform"]["texCoord"] = 1e10;
    const std::string error = load_error(text_bytes(document), "transform.gltf");
    EXPECT_NE(error.find("KHR_texture_transform.texCoord is not a TEXCOORD_ set"),
              std::string::npos)
        << error;
}

TEST(GltfLoaderFuzz, ClearcoatTextureNumbersBeyondIntAreRefused) {
    json document = json::parse(read_bytes(data_path("coat_volume.gltf")));
    json& texture =
        document["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatTexture"];
    texture["index"] = 1e10;
    std::string error = load_error(text_bytes(document), "coat.gltf");
    EXPECT_NE(error.find("KHR_materials_clearcoat.clearcoatTexture has no texture index"),
              std::string::npos)
        << error;
    texture["index"] = 0;
    texture["texCoord"] = -1e10;
    error = load_error(text_bytes(document), "coat.gltf");
    EXPECT_NE(
        error.find("KHR_materials_clearcoat.clearcoatTexture.texCoord is not a TEXCOORD_ set"),
        std::string::npos)
        << error;
}

}  // namespace
}  // namespace photond
