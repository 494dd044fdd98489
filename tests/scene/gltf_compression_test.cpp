// Compressed, quantized and instanced copies of a glTF scene render the same image as the
// original: gltfpack's KHR_mesh_quantization, EXT_meshopt_compression and EXT_mesh_gpu_instancing
// copies (tests/data/gltf/compression, written by generate.py), and a KHR_draco_mesh_compression
// copy that this test writes itself with libdraco's encoder (Debian ships no tool that writes
// Draco glTF).
#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/camera/camera.h"
#include "core/image/image_metrics.h"
#include "core/integrators/direct.h"
#include "core/render/tile_renderer.h"
#include "core/scene/gltf_loader.h"

namespace photond {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path data_path(const std::string& name) {
    return fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "compression" / name;
}

Scene load(const fs::path& path) {
    Expected<Scene> scene = load_gltf_file(path);
    EXPECT_TRUE(scene.has_value()) << path << ": " << (scene ? "" : scene.error().message);
    return scene ? std::move(scene).value() : Scene{};
}

/// Direct light and specular recursion from the file's camera: deterministic per pixel sample,
/// so equal geometry gives equal pixels.
Image render(const Scene& scene) {
    static std::shared_ptr<EmbreeDevice> device = EmbreeDevice::create().value();
    auto shared = std::make_shared<const Scene>(scene);
    auto rs = RenderScene::create(device, shared);
    EXPECT_TRUE(rs.has_value());
    if (!rs || scene.cameras.empty()) return Image();
    const Camera camera = Camera::create(scene.cameras[0], 80, 60).value();
    const DirectIntegrator integrator(*rs);
    TileSettings settings;
    settings.tile_size = 16;
    settings.samples_per_pixel = 4;
    settings.seed = 3;
    return render_tiles(integrator, camera, settings).layers.beauty;
}

ImageError compare(const Image& image, const Image& reference) {
    Expected<ImageError> error = compare_images(image, reference);
    EXPECT_TRUE(error.has_value());
    if (error)  // the figures README quotes
        std::printf("  against the original: mean bias %+.2e, relMSE %.2e\n", error->mean_bias,
                    error->relative_mse);
    return error ? *error : ImageError{};
}

const Image& original_image() {
    static const Image image = render(load(data_path("room.gltf")));
    return image;
}

TEST(GltfCompression, OriginalIsLitAndFramed) {
    const Image& image = original_image();
    ASSERT_GT(image.width(), 0);
    double mean = 0.0;
    int black = 0;
    for (const Color& c : image.pixels()) {
        mean += average(c);
        black += max_component(c) == 0.0f;
    }
    mean /= double(image.pixel_count());
    EXPECT_GT(mean, 0.05);
    EXPECT_LT(black, int(image.pixel_count() / 10));  // the camera sees the room, not the void
}

TEST(GltfCompression, MeshoptWithoutQuantizationRendersTheSameImage) {
    // Lossless: gltfpack only reorders vertices and triangles.
    const ImageError e =
        compare(render(load(data_path("room_meshopt_float.glb"))), original_image());
    EXPECT_LT(std::abs(e.mean_bias), 1e-6) << e.mean_bias;  // measured 5e-10
    EXPECT_LT(e.relative_mse, 1e-10) << e.relative_mse;     // measured 3e-15
}

TEST(GltfCompression, QuantizedAndMeshoptCopiesRenderTheSameImageToRounding) {
    // 14-bit positions (0.25 mm in this 4 m room) and 8-bit normals: silhouettes move by a
    // fraction of a pixel and shading by the normals' rounding.
    for (const char* name : {"room_quantized.glb", "room_meshopt.glb"}) {
        SCOPED_TRACE(name);
        const ImageError e = compare(render(load(data_path(name))), original_image());
        EXPECT_LT(std::abs(e.mean_bias), 5e-4) << e.mean_bias;  // measured 7e-5
        EXPECT_LT(e.relative_mse, 1e-4) << e.relative_mse;      // measured 8e-6
    }
}

TEST(GltfCompression, GpuInstancedCopyRendersTheSameImageToRounding) {
    // gltfpack -mi -noq: the six boxes of one mesh become one node with EXT_mesh_gpu_instancing
    // (rotations as 16-bit quaternions); the file must declare it, or this tests nothing.
    std::ifstream in(data_path("shelf_instanced.glb"), std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    ASSERT_NE(bytes.find("\"EXT_mesh_gpu_instancing\":{\"attributes\""), std::string::npos);
    const Image original = render(load(data_path("shelf.gltf")));
    const Scene instanced = load(data_path("shelf_instanced.glb"));
    EXPECT_TRUE(instanced.warnings.empty());
    const ImageError e = compare(render(instanced), original);
    EXPECT_LT(std::abs(e.mean_bias), 1e-5) << e.mean_bias;  // measured 6e-8
    EXPECT_LT(e.relative_mse, 1e-8) << e.relative_mse;      // measured 1e-11
}

std::string base64(const std::vector<uint8_t>& bytes) {
    static const char* kAlphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const uint32_t n = (uint32_t(bytes[i]) << 16) |
                           (i + 1 < bytes.size() ? uint32_t(bytes[i + 1]) << 8 : 0) |
                           (i + 2 < bytes.size() ? uint32_t(bytes[i + 2]) : 0);
        out += kAlphabet[(n >> 18) & 63];
        out += kAlphabet[(n >> 12) & 63];
        out += i + 1 < bytes.size() ? kAlphabet[(n >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? kAlphabet[n & 63] : '=';
    }
    return out;
}

/// room.gltf with its meshes replaced by Draco-compressed ones: the loaded scene's world-space
/// triangles, one primitive per material, encoded as an exporter would (14-bit positions, 10-bit
/// normals), under one node with no transform; the light and camera nodes stay as they were.
std::string draco_copy_of_room() {
    const Scene scene = load(data_path("room.gltf"));
    std::ifstream in(data_path("room.gltf"));
    json doc = json::parse(in);
    std::map<std::string, int> material_index;
    for (size_t i = 0; i < doc["materials"].size(); ++i)
        material_index[doc["materials"][i]["name"].get<std::string>()] = int(i);

    std::vector<uint8_t> buffer;
    json primitives = json::array();
    for (uint32_t m = 0; m < scene.materials.size(); ++m) {
        std::vector<uint32_t> triangles;
        for (uint32_t t = 0; t < scene.triangles.size(); ++t)
            if (scene.triangle_materials[t] == m) triangles.push_back(t);
        if (triangles.empty()) continue;
        draco::TriangleSoupMeshBuilder builder;
        builder.Start(int(triangles.size()));
        const int position =
            builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
        const int normal =
            builder.AddAttribute(draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32);
        for (size_t f = 0; f < triangles.size(); ++f) {
            const glm::uvec3& t = scene.triangles[triangles[f]];
            const draco::FaceIndex face{static_cast<uint32_t>(f)};
            builder.SetAttributeValuesForFace(position, face, &scene.positions[t.x],
                                              &scene.positions[t.y], &scene.positions[t.z]);
            builder.SetAttributeValuesForFace(normal, face, &scene.normals[t.x],
                                              &scene.normals[t.y], &scene.normals[t.z]);
        }
        std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
        EXPECT_TRUE(mesh);
        if (!mesh) return {};
        draco::Encoder encoder;
        encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
        encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, 10);
        draco::EncoderBuffer encoded;
        const draco::Status status = encoder.EncodeMeshToBuffer(*mesh, &encoded);
        EXPECT_TRUE(status.ok()) << status.error_msg_string();
        while (buffer.size() % 4) buffer.push_back(0);
        const size_t offset = buffer.size();
        buffer.insert(buffer.end(), encoded.data(), encoded.data() + encoded.size());

        const int view = int(doc["bufferViews"].size());
        doc["bufferViews"].push_back(
            {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", encoded.size()}});
        const int accessors = int(doc["accessors"].size());
        // Accessors of a Draco primitive have no bufferView; count and type describe the
        // decoded data.
        doc["accessors"].push_back(
            {{"componentType", 5125}, {"count", 3 * triangles.size()}, {"type", "SCALAR"}});
        doc["accessors"].push_back(
            {{"componentType", 5126}, {"count", mesh->num_points()}, {"type", "VEC3"}});
        doc["accessors"].push_back(
            {{"componentType", 5126}, {"count", mesh->num_points()}, {"type", "VEC3"}});
        primitives.push_back(
            {{"indices", accessors},
             {"attributes", {{"POSITION", accessors + 1}, {"NORMAL", accessors + 2}}},
             {"material", material_index.at(scene.materials[m].name)},
             {"extensions",
              {{"KHR_draco_mesh_compression",
                {{"bufferView", view},
                 {"attributes",
                  {{"POSITION", mesh->attribute(position)->unique_id()},
                   {"NORMAL", mesh->attribute(normal)->unique_id()}}}}}}}});
    }
    // The original buffer stays buffer 1 (its views and accessors are unused now).
    json original_buffer = doc["buffers"][0];
    for (size_t v = 0; v + primitives.size() < doc["bufferViews"].size(); ++v)
        doc["bufferViews"][v]["buffer"] = 1;
    doc["buffers"] =
        json::array({{{"byteLength", buffer.size()},
                      {"uri", "data:application/octet-stream;base64," + base64(buffer)}},
                     original_buffer});
    doc["meshes"] = json::array({{{"name", "Draco"}, {"primitives", primitives}}});
    for (json& node : doc["nodes"]) {
        if (!node.contains("mesh")) continue;
        node.erase("mesh");
        node.erase("translation");
        node.erase("rotation");
        node.erase("scale");
    }
    doc["nodes"][0]["mesh"] = 0;
    doc["extensionsUsed"].push_back("KHR_draco_mesh_compression");
    doc["extensionsRequired"] = json::array({"KHR_draco_mesh_compression"});
    return doc.dump();
}

TEST(GltfCompression, DracoCopyRendersTheSameImageToRounding) {
    const std::string text = draco_copy_of_room();
    ASSERT_FALSE(text.empty());
    const fs::path file =
        fs::temp_directory_path() / ("photond_draco_room_" + std::to_string(::getpid()) + ".gltf");
    {
        std::ofstream out(file);
        out << text;
    }
    const Scene draco = load(file);
    fs::remove(file);
    const Scene original = load(data_path("room.gltf"));
    EXPECT_EQ(draco.triangles.size(), original.triangles.size());
    EXPECT_TRUE(draco.warnings.empty()) << draco.warnings.front();
    const ImageError e = compare(render(draco), original_image());
    EXPECT_LT(std::abs(e.mean_bias), 5e-4) << e.mean_bias;  // measured 3e-5
    EXPECT_LT(e.relative_mse, 1e-4) << e.relative_mse;      // measured 1.4e-7
}

}  // namespace
}  // namespace photond
