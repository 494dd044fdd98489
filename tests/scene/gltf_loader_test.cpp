// Tests of the glTF loader against the hand-made files of tests/data/gltf (written by
// tests/data/gltf/generate.py) and one file written by another tool (tests/data/gltf/external).
#include "core/scene/gltf_loader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace photond {
namespace {

namespace fs = std::filesystem;

fs::path data_path(const std::string& name) {
    return fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / name;
}

std::vector<uint8_t> read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

Scene load_ok(const std::string& name, const GltfLoadOptions& options = {}) {
    Expected<Scene> scene = load_gltf_file(data_path(name), options);
    EXPECT_TRUE(scene.has_value()) << name << ": " << (scene ? "" : scene.error().message);
    return scene ? std::move(scene).value() : Scene{};
}

std::string load_error(const std::string& name, const GltfLoadOptions& options = {}) {
    Expected<Scene> scene = load_gltf_file(data_path(name), options);
    EXPECT_FALSE(scene.has_value()) << name << " loaded although it is broken";
    return scene ? std::string() : scene.error().message;
}

float srgb_eotf(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

void expect_vec_near(const Vec3& actual, const Vec3& expected, float tolerance = 1e-5f) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

void expect_triangle(const Scene& scene, uint32_t t, const Vec3& a, const Vec3& b, const Vec3& c) {
    SCOPED_TRACE("triangle " + std::to_string(t));
    ASSERT_LT(t, scene.triangles.size());
    expect_vec_near(scene.positions[scene.triangles[t].x], a);
    expect_vec_near(scene.positions[scene.triangles[t].y], b);
    expect_vec_near(scene.positions[scene.triangles[t].z], c);
}

// ----------------------------------------------------------------------------- valid files

TEST(GltfLoader, IndexedAndNonIndexedQuads) {
    for (const std::string name :
         {"indexed_u8.gltf", "indexed_u16.gltf", "indexed_u32.gltf", "non_indexed.gltf"}) {
        SCOPED_TRACE(name);
        const Scene scene = load_ok(name);
        ASSERT_EQ(scene.triangles.size(), 2u);
        EXPECT_EQ(scene.positions.size(), name == "non_indexed.gltf" ? 6u : 4u);
        expect_triangle(scene, 0, {0, 0, 0}, {1, 0, 0}, {1, 1, 0});
        expect_triangle(scene, 1, {0, 0, 0}, {1, 1, 0}, {0, 1, 0});
        for (uint32_t t = 0; t < 2; ++t) expect_vec_near(scene.triangle_normal(t), {0, 0, 1});
        for (const Vec3& n : scene.normals) expect_vec_near(n, {0, 0, 1});
        EXPECT_EQ(scene.name, name);
        expect_vec_near(scene.bounds.lower, {0, 0, 0});
        expect_vec_near(scene.bounds.upper, {1, 1, 0});
    }
}

TEST(GltfLoader, NormalizedIntegerTexcoords) {
    // u8 (indexed_u8) and u16 (indexed_u32) normalized texture coordinates: vertex 2 is (1, 1).
    for (const std::string name : {"indexed_u8.gltf", "indexed_u32.gltf", "indexed_u16.gltf"}) {
        SCOPED_TRACE(name);
        const Scene scene = load_ok(name);
        ASSERT_EQ(scene.uvs.size(), 4u);
        EXPECT_FLOAT_EQ(scene.uvs[0].x, 0.0f);
        EXPECT_FLOAT_EQ(scene.uvs[1].x, 1.0f);
        EXPECT_FLOAT_EQ(scene.uvs[1].y, 0.0f);
        EXPECT_FLOAT_EQ(scene.uvs[2].x, 1.0f);
        EXPECT_FLOAT_EQ(scene.uvs[2].y, 1.0f);
        EXPECT_FLOAT_EQ(scene.uvs[3].y, 1.0f);
    }
}

TEST(GltfLoader, TriangleStrip) {
    const Scene scene = load_ok("strip.gltf");
    ASSERT_EQ(scene.triangles.size(), 3u);
    const Vec3 v[5] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 2, 0}};
    expect_triangle(scene, 0, v[0], v[1], v[2]);
    expect_triangle(scene, 1, v[1], v[3], v[2]);  // odd triangles swap to keep the winding
    expect_triangle(scene, 2, v[2], v[3], v[4]);
    for (uint32_t t = 0; t < 3; ++t) expect_vec_near(scene.triangle_normal(t), {0, 0, 1});
}

TEST(GltfLoader, TriangleFan) {
    const Scene scene = load_ok("fan.gltf");
    ASSERT_EQ(scene.triangles.size(), 3u);
    const Vec3 v[5] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {-1, 1, 0}};
    expect_triangle(scene, 0, v[0], v[1], v[2]);
    expect_triangle(scene, 1, v[0], v[2], v[3]);
    expect_triangle(scene, 2, v[0], v[3], v[4]);
    for (uint32_t t = 0; t < 3; ++t) expect_vec_near(scene.triangle_normal(t), {0, 0, 1});
}

TEST(GltfLoader, NodeHierarchyWithMatrixAndTrs) {
    // Scene 1 is the default: Parent (TRS) with Child (matrix), and Other (matrix). The
    // triangle (0,0,0), (1,0,0), (0,1,0) is instanced by all three.
    const Scene scene = load_ok("hierarchy.gltf");
    ASSERT_EQ(scene.triangles.size(), 3u);
    // Parent: translate (10,0,0) * rotate 90 deg about Z * scale 2: p -> (10 - 2y, 2x, 2z).
    expect_triangle(scene, 0, {10, 0, 0}, {10, 2, 0}, {8, 0, 0});
    // Child: Parent * translate (0,0,5).
    expect_triangle(scene, 1, {10, 0, 10}, {10, 2, 10}, {8, 0, 10});
    // Other: translate (0,-3,0).
    expect_triangle(scene, 2, {0, -3, 0}, {1, -3, 0}, {0, -2, 0});
    for (const Vec3& n : scene.normals) expect_vec_near(n, {0, 0, 1});
    // Node 3 belongs to scene 0 only and must not appear.
    expect_vec_near(scene.bounds.lower, {0, -3, 0});
    expect_vec_near(scene.bounds.upper, {10, 2, 10});
}

TEST(GltfLoader, NegativeScaleKeepsGeometricAndShadingNormalsAgreeing) {
    const Scene scene = load_ok("negative_scale.gltf");
    ASSERT_EQ(scene.triangles.size(), 2u);  // primitive 0 with normals, primitive 1 without
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        SCOPED_TRACE("triangle " + std::to_string(t));
        const glm::uvec3 tri = scene.triangles[t];
        const Vec3 a = scene.positions[tri.x], b = scene.positions[tri.y],
                   c = scene.positions[tri.z];
        const Vec3 geometric = glm::normalize(glm::cross(b - a, c - a));
        expect_vec_near(geometric, {0, 0, 1});
        for (uint32_t v : {tri.x, tri.y, tri.z})
            EXPECT_GT(glm::dot(geometric, scene.normals[v]), 0.99f);
    }
    // The mirror moved (1,0,0) to (-1,0,0).
    expect_vec_near(scene.bounds.lower, {-1, 0, 0});
    expect_vec_near(scene.bounds.upper, {0, 1, 0});
}

TEST(GltfLoader, MissingNormalsGiveFlatNormals) {
    const Scene scene = load_ok("flat_normals.gltf");
    ASSERT_EQ(scene.triangles.size(), 2u);
    EXPECT_EQ(scene.positions.size(), 6u);  // unwelded: one vertex per triangle corner
    for (uint32_t t = 0; t < 2; ++t) {
        const Vec3 n = scene.triangle_normal(t);
        expect_vec_near(n, {0, 0, 1});
        for (uint32_t v : {scene.triangles[t].x, scene.triangles[t].y, scene.triangles[t].z})
            expect_vec_near(scene.normals[v], n);
    }
}

TEST(GltfLoader, SparseAccessor) {
    const Scene scene = load_ok("sparse.gltf");
    ASSERT_EQ(scene.triangles.size(), 2u);
    expect_triangle(scene, 0, {0, 0, 0}, {1, 0, 0}, {2, 2, 0});  // vertex 2 substituted
    expect_triangle(scene, 1, {0, 0, 0}, {2, 2, 0}, {0, 1, 0});
}

TEST(GltfLoader, PerspectiveCamera) {
    const Scene scene = load_ok("camera.gltf");
    ASSERT_EQ(scene.cameras.size(), 2u);  // one per entry of cameras[], in its order
    const CameraDesc& camera = scene.cameras[0];
    EXPECT_EQ(camera.name, "Persp");
    EXPECT_EQ(camera.projection, CameraProjection::Perspective);
    EXPECT_TRUE(camera.placed);
    expect_vec_near(camera.position, {1, 2, 3});
    expect_vec_near(glm::normalize(camera.look_at - camera.position), {-1, 0, 0});
    expect_vec_near(camera.up, {0, 1, 0});
    EXPECT_NEAR(camera.vfov_deg, 0.8f * 180.0f / kPi, 1e-4f);
    EXPECT_FLOAT_EQ(camera.aspect, 1.5f);
}

TEST(GltfLoader, PunctualLights) {
    const Scene scene = load_ok("lights.gltf");
    ASSERT_EQ(scene.lights.size(), 3u);
    const auto find = [&](const std::string& name) -> const PunctualLight& {
        for (const PunctualLight& l : scene.lights)
            if (l.name == name) return l;
        ADD_FAILURE() << "no light named " << name;
        return scene.lights[0];
    };
    const PunctualLight& bulb = find("Bulb");
    EXPECT_EQ(bulb.type, PunctualLightType::Point);
    expect_vec_near(bulb.position, {0, 5, 0});
    // KHR_lights_punctual is photometric: 10 cd is 10 / 683 W/sr.
    expect_vec_near(bulb.intensity, Vec3(10, 5, 2.5f) / 683.0f, 1e-7f);

    const PunctualLight& spot = find("Spot");
    EXPECT_EQ(spot.type, PunctualLightType::Spot);
    expect_vec_near(spot.position, {1, 2, 3});
    expect_vec_near(spot.direction, {0, -1, 0});
    expect_vec_near(spot.intensity, Vec3(2.0f / 683.0f), 1e-7f);
    EXPECT_NEAR(spot.cos_inner, std::cos(0.2f), 1e-6f);
    EXPECT_NEAR(spot.cos_outer, std::cos(0.6f), 1e-6f);

    const PunctualLight& sun = find("Sun");
    EXPECT_EQ(sun.type, PunctualLightType::Directional);
    expect_vec_near(sun.direction, {-1, 0, 0});
    expect_vec_near(sun.intensity, Vec3(3.0f / 683.0f), 1e-7f);  // 3 lx
    // Point and spot positions extend the scene bounds.
    EXPECT_GE(scene.bounds.upper.y, 5.0f);
}

bool has_warning(const Scene& scene, const std::string& text) {
    for (const std::string& w : scene.warnings)
        if (w.find(text) != std::string::npos) return true;
    return false;
}

std::string all_warnings(const Scene& scene) {
    std::string text;
    for (const std::string& w : scene.warnings) text += "\n  " + w;
    return text;
}

TEST(GltfLoader, CamerasAreIndexedByTheirPlaceInCamerasArray) {
    const Scene scene = load_ok("camera_indexing.gltf");
    ASSERT_EQ(scene.cameras.size(), 3u);
    // cameras[0] is placed by no node: kept at its index, unusable, and said so.
    EXPECT_EQ(scene.cameras[0].name, "Unplaced");
    EXPECT_FALSE(scene.cameras[0].placed);
    EXPECT_TRUE(has_warning(scene, "camera 0 'Unplaced' is placed by no node")) << all_warnings(scene);
    // cameras[1] is placed by two nodes: the first in the walk (SharedFirst) places it.
    EXPECT_TRUE(scene.cameras[1].placed);
    expect_vec_near(scene.cameras[1].position, {0, 0, 5});
    EXPECT_NEAR(scene.cameras[1].vfov_deg, 0.6f * 180.0f / kPi, 1e-4f);
    EXPECT_TRUE(has_warning(scene, "camera 1 'Shared' is placed by 2 nodes (2, 3)"))
        << all_warnings(scene);
    // cameras[2]: orthographic, ymag is the half-height, xmag / ymag the aspect.
    const CameraDesc& ortho = scene.cameras[2];
    EXPECT_EQ(ortho.projection, CameraProjection::Orthographic);
    EXPECT_FLOAT_EQ(ortho.ortho_half_height, 1.0f);
    EXPECT_FLOAT_EQ(ortho.aspect, 2.0f);
    expect_vec_near(ortho.position, {0.25f, 0.25f, 4});
    expect_vec_near(glm::normalize(ortho.look_at - ortho.position), {0, 0, -1});
}

TEST(GltfLoader, OrthographicCameraOfTheCameraFile) {
    const Scene scene = load_ok("camera.gltf");
    ASSERT_EQ(scene.cameras.size(), 2u);
    EXPECT_EQ(scene.cameras[1].name, "Ortho");
    EXPECT_EQ(scene.cameras[1].projection, CameraProjection::Orthographic);
    EXPECT_FLOAT_EQ(scene.cameras[1].ortho_half_height, 1.0f);
    EXPECT_TRUE(scene.warnings.empty()) << all_warnings(scene);
}

TEST(GltfLoader, MeshQuantization) {
    // SHORT positions 0..1000 under scale 0.002 and translation (1, 0, 0); BYTE normals; BYTE
    // texture coordinates that are not normalized (0 or 2).
    const Scene scene = load_ok("quantized.gltf");
    ASSERT_EQ(scene.triangles.size(), 2u);
    expect_triangle(scene, 0, {1, 0, 0}, {3, 0, 0}, {3, 2, 0});
    expect_triangle(scene, 1, {1, 0, 0}, {3, 2, 0}, {1, 2, 0});
    for (const Vec3& n : scene.normals) expect_vec_near(n, {0, 0, 1});
    const glm::uvec3& t = scene.triangles[0];
    EXPECT_EQ(scene.uvs[t.y], Vec2(2, 0));
    EXPECT_EQ(scene.uvs[t.z], Vec2(2, 2));
    EXPECT_FALSE(has_warning(scene, "KHR_mesh_quantization")) << all_warnings(scene);
}

TEST(GltfLoaderErrors, QuantizedAttributesNeedTheExtension) {
    const std::string error = load_error("broken/quantized_undeclared.gltf");
    EXPECT_NE(error.find("(POSITION) has componentType SHORT, which POSITION does not allow "
                         "without KHR_mesh_quantization in extensionsUsed"),
              std::string::npos)
        << error;
}

TEST(GltfLoader, UnsupportedFeaturesAreWarnedAboutByName) {
    const Scene scene = load_ok("warnings.gltf");
    for (const char* expected :
         {"glTF extension KHR_materials_sheen is not supported",
          "glTF extension KHR_materials_iridescence is not supported",
          "glTF extension KHR_materials_anisotropy is not supported",
          "1 point or line primitive(s) are not rendered", "light 0 'Ranged': range 5",
          "camera 0 'Nowhere' is placed by no node",
          "KHR_materials_clearcoat's clearcoatNormalTexture is not applied (material 'Lacquer')"}) {
        EXPECT_TRUE(has_warning(scene, expected)) << expected << " not in:" << all_warnings(scene);
    }
    // Supported extensions and material features are not warned about: the normal texture,
    // alpha MASK, the clamping sampler and COLOR_0 of the file are all rendered.
    for (const char* supported : {"KHR_lights_punctual", "normalTexture", "alphaMode", "sampler", "COLOR"})
        EXPECT_FALSE(has_warning(scene, supported)) << supported << " in:" << all_warnings(scene);
    // Lacquer's specular textures are applied: no warning.
    EXPECT_FALSE(has_warning(scene, "specular")) << all_warnings(scene);
    EXPECT_EQ(scene.warnings.size(), 7u) << all_warnings(scene);
}

TEST(GltfLoader, ClosedTransmissiveMeshWithoutVolumeIsWarnedAbout) {
    const Scene scene = load_ok("transmission.gltf");
    EXPECT_TRUE(has_warning(scene, "KHR_materials_transmission without KHR_materials_volume on a "
                                   "closed mesh (materials 'BoxGlass' and 'SplitGlass')"))
        << all_warnings(scene);
    EXPECT_FALSE(has_warning(scene, "PaneGlass")) << all_warnings(scene);  // an open pane
}

TEST(GltfLoader, OpenTransmissiveMeshesAreThinWalls) {
    // The materials of transmission.gltf's triangles, by mesh: 12 of the box, 2 of the pane, 13
    // of the box split into two primitives (closed together; the last triangle has a repeated
    // corner), 2 of the pane whose volume has thicknessFactor 0.
    const Scene scene = load_ok("transmission.gltf");
    ASSERT_EQ(scene.triangles.size(), 29u);
    const auto material_of = [&](size_t triangle) { return scene.materials[scene.triangle_materials[triangle]]; };
    for (size_t t = 0; t < 29; ++t) {
        const Material& m = material_of(t);
        SCOPED_TRACE(testing::Message() << "triangle " << t << " material '" << m.name << "'");
        EXPECT_FLOAT_EQ(m.transmission, 1.0f);
        const bool thin = (t >= 12 && t < 14) || t >= 27;
        EXPECT_EQ(m.thin_walled, thin);
        EXPECT_EQ(m.name, t < 12 ? "BoxGlass" : t < 14 ? "PaneGlass" : t < 27 ? "SplitGlass" : "ThinVolumePane");
        // A thin wall has no inside to attenuate in.
        if (thin) {
            EXPECT_FALSE(m.has_volume());
        }
    }
}

TEST(GltfLoader, PhotometricLightsAsBlenderWritesThem) {
    // Blender's exporter writes a 1000 W point lamp as 1000 / (4 pi) * 683 cd and a 3 W/m^2 sun
    // as 3 * 683 lx: read back, they are 1000 / (4 pi) W/sr and 3 W/m^2 again.
    const Scene scene = load_ok("blender_lights.gltf");
    ASSERT_EQ(scene.lights.size(), 2u);
    EXPECT_NEAR(scene.lights[0].intensity.x, 1000.0f / (4.0f * kPi), 1e-3f);
    EXPECT_NEAR(scene.lights[1].intensity.x, 3.0f, 1e-5f);
    EXPECT_EQ(scene.lights[1].type, PunctualLightType::Directional);
    // Emission is not converted: emissiveFactor 1 x emissiveStrength 2.
    bool found = false;
    for (const Material& m : scene.materials) {
        if (m.name != "Emitter") continue;
        found = true;
        expect_vec_near(m.emission, {2, 2, 2});
    }
    EXPECT_TRUE(found);
}

double total_area(const Scene& scene) {
    double area = 0.0;
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) area += scene.triangle_area(t);
    return area;
}

TEST(GltfLoader, MeshoptCompressedCopiesHoldTheSameGeometry) {
    const Scene original = load_ok("compression/room.gltf");
    // gltfpack -cc -noq: meshopt's codecs without quantization are lossless (it may reorder).
    const Scene lossless = load_ok("compression/room_meshopt_float.glb");
    EXPECT_EQ(lossless.triangles.size(), original.triangles.size());
    EXPECT_NEAR(total_area(lossless), total_area(original), 1e-5 * total_area(original));
    expect_vec_near(lossless.bounds.lower, original.bounds.lower);
    expect_vec_near(lossless.bounds.upper, original.bounds.upper);
    // gltfpack -cc and plain gltfpack: quantized (14-bit positions, 8-bit normals) and, for -cc,
    // compressed with the octahedral filter on normals.
    for (const char* name : {"compression/room_meshopt.glb", "compression/room_quantized.glb"}) {
        SCOPED_TRACE(name);
        const Scene quantized = load_ok(name);
        EXPECT_EQ(quantized.triangles.size(), original.triangles.size());
        EXPECT_NEAR(total_area(quantized), total_area(original), 2e-3 * total_area(original));
        expect_vec_near(quantized.bounds.lower, original.bounds.lower, 1e-3f);
        expect_vec_near(quantized.bounds.upper, original.bounds.upper, 1e-3f);
        ASSERT_EQ(quantized.lights.size(), 1u);
        expect_vec_near(quantized.lights[0].position, original.lights[0].position, 1e-5f);
        ASSERT_EQ(quantized.cameras.size(), 1u);
        expect_vec_near(quantized.cameras[0].position, original.cameras[0].position, 1e-5f);
        EXPECT_FALSE(has_warning(quantized, "EXT_meshopt_compression")) << all_warnings(quantized);
        EXPECT_FALSE(has_warning(quantized, "KHR_mesh_quantization")) << all_warnings(quantized);
    }
}

TEST(GltfLoader, GpuInstancesArePlacedLikeNodes) {
    // EXT_mesh_gpu_instancing: three instances of one triangle under a moved, scaled node
    // (rotations as normalized SHORT quaternions), against the same three placed by child nodes.
    const Scene instanced = load_ok("instancing.gltf");
    const Scene flat = load_ok("instancing_flat.gltf");
    ASSERT_EQ(instanced.triangles.size(), 3u);  // the instances alone, not the node's own copy
    ASSERT_EQ(flat.triangles.size(), 3u);
    for (uint32_t t = 0; t < 3; ++t) {
        SCOPED_TRACE("triangle " + std::to_string(t));
        const glm::uvec3 a = instanced.triangles[t], b = flat.triangles[t];
        // 16-bit quaternions: off by under 1e-4 of the distance from the instance's origin (2).
        for (int v = 0; v < 3; ++v) expect_vec_near(instanced.positions[a[v]], flat.positions[b[v]], 1e-3f);
        expect_vec_near(instanced.normals[a.x], flat.normals[b.x], 1e-3f);
    }
    // Instance 1: Parent (translate (1,1,0), scale 2) * translate (2,0,0) * 90 deg about z *
    // scale 0.5: (1,0,0) -> (5,2,0).
    expect_vec_near(instanced.positions[instanced.triangles[1].y], {5, 2, 0}, 1e-3f);
    EXPECT_TRUE(has_warning(instanced, "EXT_mesh_gpu_instancing attribute(s) _ID are ignored"))
        << all_warnings(instanced);
    EXPECT_FALSE(has_warning(instanced, "glTF extension EXT_mesh_gpu_instancing")) << all_warnings(instanced);
    EXPECT_TRUE(flat.warnings.empty()) << all_warnings(flat);
}

TEST(GltfLoaderErrors, GpuInstancingAttributesOfDifferentCounts) {
    const std::string error = load_error("broken/instancing_count_mismatch.gltf");
    EXPECT_NE(error.find("node 0 'Parent': EXT_mesh_gpu_instancing SCALE has 3 elements, the other "
                         "attributes 2 (all must have the same count)"),
              std::string::npos)
        << error;
    // A custom attribute is ignored, but must have one element per instance too.
    const std::string custom = load_error("broken/instancing_id_count_mismatch.gltf");
    EXPECT_NE(custom.find("EXT_mesh_gpu_instancing _ID has 2 elements, the other attributes 3"), std::string::npos)
        << custom;
}

TEST(GltfLoader, MaterialsWithExtensionsAndDefaults) {
    const Scene scene = load_ok("materials.gltf");
    ASSERT_EQ(scene.triangles.size(), 3u);
    // The three, and the thin-walled copy of the transmissive one, whose triangle is open.
    ASSERT_EQ(scene.materials.size(), 4u);

    const Material& m = scene.materials[scene.triangle_materials[0]];
    EXPECT_EQ(m.name, "Everything");
    EXPECT_TRUE(m.thin_walled);
    expect_vec_near(m.base_color, {0.5f, 0.25f, 0.125f});
    EXPECT_FLOAT_EQ(m.metallic, 0.3f);
    EXPECT_FLOAT_EQ(m.roughness, 0.7f);
    expect_vec_near(m.emission, {4.0f, 2.0f, 1.0f});  // emissiveFactor * emissiveStrength
    EXPECT_TRUE(m.double_sided);
    EXPECT_FLOAT_EQ(m.transmission, 0.9f);
    EXPECT_FLOAT_EQ(m.ior, 1.33f);
    EXPECT_FLOAT_EQ(m.specular, 0.6f);
    expect_vec_near(m.specular_color, {0.9f, 0.8f, 0.7f});
    EXPECT_EQ(m.base_color_texture.texture, -1);
    EXPECT_TRUE(m.is_emissive());

    // No material: the glTF default material (base 1, metallic 1, roughness 1).
    const Material& d = scene.materials[scene.triangle_materials[1]];
    expect_vec_near(d.base_color, {1, 1, 1});
    EXPECT_FLOAT_EQ(d.metallic, 1.0f);
    EXPECT_FLOAT_EQ(d.roughness, 1.0f);
    EXPECT_FALSE(d.is_emissive());

    // A material without pbrMetallicRoughness takes the glTF defaults, not photond's.
    const Material& bare = scene.materials[scene.triangle_materials[2]];
    EXPECT_EQ(bare.name, "Bare");
    expect_vec_near(bare.base_color, {1, 1, 1});
    EXPECT_FLOAT_EQ(bare.metallic, 1.0f);
    EXPECT_FLOAT_EQ(bare.roughness, 1.0f);
    EXPECT_FLOAT_EQ(bare.ior, 1.5f);
    EXPECT_FLOAT_EQ(bare.transmission, 0.0f);
    EXPECT_FLOAT_EQ(bare.specular, 1.0f);
    EXPECT_FALSE(bare.double_sided);
}

void expect_checker_texture(const Scene& scene) {
    ASSERT_EQ(scene.textures.size(), 1u);
    const Texture& tex = *scene.textures[0];
    ASSERT_EQ(tex.width, 2);
    ASSERT_EQ(tex.height, 2);
    // An 8-bit image keeps its bytes, read through the sRGB curve.
    EXPECT_EQ(tex.encoding, TexelEncoding::Srgb8);
    ASSERT_EQ(tex.texel_count(), 4u);
    // Row 0 is the first image row: (255,0,0) (0,128,0) / (0,0,64) (188,188,188), sRGB.
    expect_vec_near(Vec3(tex.texel(0)), {1, 0, 0});
    expect_vec_near(Vec3(tex.texel(1)), {0, 0.21586050f, 0});
    expect_vec_near(Vec3(tex.texel(1)), {0, srgb_eotf(128.0f / 255.0f), 0});
    expect_vec_near(Vec3(tex.texel(2)), {0, 0, srgb_eotf(64.0f / 255.0f)});
    expect_vec_near(Vec3(tex.texel(3)), Vec3(srgb_eotf(188.0f / 255.0f)));
    EXPECT_FLOAT_EQ(tex.texel(3).w, 1.0f);
    // Texture times baseColorFactor (0.5, 1, 1) at texel centres.
    ASSERT_EQ(scene.materials.size(), 1u);
    EXPECT_EQ(scene.materials[0].base_color_texture.texture, 0);
    expect_vec_near(scene.base_color(0, {0.25f, 0.25f}), {0.5f, 0, 0});
    expect_vec_near(scene.base_color(0, {0.75f, 0.25f}), {0, 0.21586050f, 0});
    expect_vec_near(scene.base_color(0, {0.25f, 0.75f}), {0, 0, srgb_eotf(64.0f / 255.0f)});
}

TEST(GltfLoader, BaseColorTexturePngDataUri) {
    const Scene scene = load_ok("texture.gltf");
    ASSERT_EQ(scene.triangles.size(), 2u);
    expect_checker_texture(scene);
}

TEST(GltfLoader, SixteenBitTextureKeepsPrecision) {
    const Scene scene = load_ok("texture16.gltf");
    ASSERT_EQ(scene.textures.size(), 1u);
    const Texture& tex = *scene.textures[0];
    EXPECT_EQ(tex.encoding, TexelEncoding::Float);
    ASSERT_EQ(tex.texels.size(), 4u);
    // 32768/65535 decodes to 0.21404; truncation to 8 bits (128/255) would give 0.21586.
    expect_vec_near(tex.texels[0], Vec3(srgb_eotf(32768.0f / 65535.0f)), 1e-5f);
    EXPECT_LT(std::abs(tex.texels[0].x - srgb_eotf(128.0f / 255.0f)), 0.01f);
    EXPECT_GT(std::abs(tex.texels[0].x - srgb_eotf(128.0f / 255.0f)), 1e-3f);
    expect_vec_near(tex.texels[1], {1, 0, 0});
    expect_vec_near(tex.texels[2], {0, 1, 0});
    expect_vec_near(tex.texels[3], {0, 0, 1});
}

TEST(GltfLoader, GlbWithImageInBufferView) {
    const Scene from_file = load_ok("textured_quad.glb");
    ASSERT_EQ(from_file.triangles.size(), 2u);
    expect_checker_texture(from_file);

    const std::vector<uint8_t> bytes = read_bytes(data_path("textured_quad.glb"));
    Expected<Scene> from_memory = load_gltf_memory(bytes, "upload.glb");
    ASSERT_TRUE(from_memory.has_value()) << from_memory.error().message;
    EXPECT_EQ(from_memory->name, "upload.glb");
    ASSERT_EQ(from_memory->triangles.size(), 2u);
    expect_checker_texture(*from_memory);
}

TEST(GltfLoader, SelfContainedGltfFromMemory) {
    const std::vector<uint8_t> bytes = read_bytes(data_path("materials.gltf"));
    Expected<Scene> scene = load_gltf_memory(bytes, "materials.gltf");
    ASSERT_TRUE(scene.has_value()) << scene.error().message;
    EXPECT_EQ(scene->triangles.size(), 3u);
}

TEST(GltfLoader, ExternalBoxSampleModel) {
    // Khronos glTF-Sample-Models Box (COLLADA2GLTF output); see tests/data/gltf/external.
    const Scene scene = load_ok("external/Box.gltf");
    EXPECT_EQ(scene.triangles.size(), 12u);
    EXPECT_EQ(scene.positions.size(), 24u);
    expect_vec_near(scene.bounds.lower, Vec3(-0.5f));
    expect_vec_near(scene.bounds.upper, Vec3(0.5f));
    ASSERT_EQ(scene.materials.size(), 1u);
    expect_vec_near(scene.materials[0].base_color, {0.8f, 0, 0});
    // A closed cube: shading normals agree with the outward geometric normals.
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        const Vec3 n = scene.triangle_normal(t);
        const Vec3 centroid =
            (scene.positions[scene.triangles[t].x] + scene.positions[scene.triangles[t].y] +
             scene.positions[scene.triangles[t].z]) /
            3.0f;
        EXPECT_GT(glm::dot(n, centroid), 0.0f) << "triangle " << t << " faces inwards";
        EXPECT_GT(glm::dot(n, scene.normals[scene.triangles[t].x]), 0.99f);
    }
}

// ----------------------------------------------------------------------------- broken files

TEST(GltfLoaderErrors, InvalidJson) {
    const std::string error = load_error("broken/invalid_json.gltf");
    EXPECT_NE(error.find("invalid_json.gltf: cannot load glTF: "), std::string::npos) << error;
    // tinygltf's own parse message follows.
    EXPECT_GT(error.size(), std::string("invalid_json.gltf: cannot load glTF: ").size()) << error;
}

TEST(GltfLoaderErrors, TruncatedGlb) {
    const std::string error = load_error("broken/truncated.glb");
    EXPECT_NE(error.find("truncated.glb: GLB is truncated"), std::string::npos) << error;
}

TEST(GltfLoaderErrors, MissingBufferFile) {
    const std::string error = load_error("broken/missing_buffer.gltf");
    EXPECT_NE(error.find("missing_buffer.gltf"), std::string::npos) << error;
    EXPECT_NE(error.find("does_not_exist.bin"), std::string::npos) << error;
}

TEST(GltfLoaderErrors, AccessorOutOfBounds) {
    const std::string error = load_error("broken/accessor_out_of_bounds.gltf");
    EXPECT_NE(error.find("mesh 0 'TooLong' primitive 0: accessor 0 (POSITION) (100 elements"),
              std::string::npos)
        << error;
    EXPECT_NE(error.find("reads past the end of its bufferView 0"), std::string::npos) << error;
}

TEST(GltfLoaderErrors, IndexOutOfRange) {
    const std::string error = load_error("broken/index_out_of_range.gltf");
    EXPECT_NE(error.find("accessor 1 (indices) element 5 is 7, out of range of the 4 vertices"),
              std::string::npos)
        << error;
}

TEST(GltfLoaderErrors, NanPosition) {
    const std::string error = load_error("broken/nan_position.gltf");
    EXPECT_EQ(error,
              "nan_position.gltf: mesh 0 'Chair' primitive 0: accessor 0 (POSITION) has a "
              "non-finite value at element 2");
}

TEST(GltfLoaderErrors, UriTraversalIsRefused) {
    const std::string error = load_error("broken/traversal/traversal.gltf");
    EXPECT_NE(error.find("uri '../outside.bin' escapes the bundle root"), std::string::npos)
        << error;
    // The same file loads when the bundle root includes the referenced file: the refusal above
    // comes from the sandbox, not from a missing file.
    GltfLoadOptions options;
    options.bundle_root = data_path("broken");
    const Scene scene = load_ok("broken/traversal/traversal.gltf", options);
    EXPECT_EQ(scene.triangles.size(), 1u);
}

TEST(GltfLoaderErrors, AbsoluteUriIsRefused) {
    const std::string error = load_error("broken/absolute_uri.gltf");
    EXPECT_NE(error.find("uri '/etc/passwd' is absolute"), std::string::npos) << error;
}

TEST(GltfLoaderErrors, SymlinkEscapingTheBundleIsRefused) {
    // One directory per process: several build trees may run this test at the same time.
    const fs::path dir =
        fs::temp_directory_path() / ("photond_gltf_symlink_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir / "bundle");
    // A valid buffer outside the bundle, reached through a symbolic link inside it.
    fs::copy_file(data_path("broken/outside.bin"), dir / "outside.bin");
    fs::create_symlink(dir / "outside.bin", dir / "bundle" / "link.bin");
    std::string text;
    {
        std::ifstream in(data_path("broken/traversal/traversal.gltf"));
        text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const size_t at = text.find("../outside.bin");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, std::string("../outside.bin").size(), "link.bin");
    std::ofstream(dir / "bundle" / "scene.gltf") << text;

    Expected<Scene> scene = load_gltf_file(dir / "bundle" / "scene.gltf");
    ASSERT_FALSE(scene.has_value());
    EXPECT_NE(scene.error().message.find("uri 'link.bin' escapes the bundle root"),
              std::string::npos)
        << scene.error().message;
    GltfLoadOptions options;
    options.bundle_root = dir;  // now the link target is inside
    EXPECT_TRUE(load_gltf_file(dir / "bundle" / "scene.gltf", options).has_value());
    fs::remove_all(dir);
}

TEST(GltfLoaderErrors, UnsupportedRequiredExtension) {
    const std::string error = load_error("broken/unsupported_extension.gltf");
    EXPECT_NE(error.find("requires the unsupported extension KHR_texture_basisu"),
              std::string::npos)
        << error;
}

TEST(GltfLoaderErrors, NoTriangles) {
    const std::string error = load_error("broken/no_triangles.gltf");
    EXPECT_EQ(error, "no_triangles.gltf: contains no triangles");
}

TEST(GltfLoaderErrors, NodeCycle) {
    const std::string error = load_error("broken/cycle.gltf");
    EXPECT_NE(error.find("node 0 'A': is its own ancestor"), std::string::npos) << error;
}

TEST(GltfLoaderErrors, WrongAttributeType) {
    const std::string error = load_error("broken/wrong_normal_type.gltf");
    EXPECT_NE(error.find("accessor 1 (NORMAL) has type VEC2, expected VEC3"), std::string::npos)
        << error;
}

TEST(GltfLoaderErrors, MissingFile) {
    const std::string error = load_error("does_not_exist.gltf");
    EXPECT_NE(error.find("does_not_exist.gltf"), std::string::npos) << error;
}

TEST(GltfLoaderErrors, MemoryRefusesExternalUri) {
    // From disk the file is fine (its buffer sits next to it) ...
    EXPECT_EQ(load_ok("broken/external_buffer.gltf").triangles.size(), 2u);
    // ... but an upload must be self-contained.
    const std::vector<uint8_t> bytes = read_bytes(data_path("broken/external_buffer.gltf"));
    Expected<Scene> scene = load_gltf_memory(bytes, "upload.gltf");
    ASSERT_FALSE(scene.has_value());
    EXPECT_NE(scene.error().message.find(
                  "upload.gltf: uri 'external_buffer.bin' refers to an external file"),
              std::string::npos)
        << scene.error().message;
}

TEST(GltfLoaderErrors, MemoryGarbage) {
    const std::vector<uint8_t> empty;
    EXPECT_FALSE(load_gltf_memory(empty, "empty.glb").has_value());
    const std::vector<uint8_t> magic_only = {'g', 'l', 'T', 'F'};
    EXPECT_FALSE(load_gltf_memory(magic_only, "short.glb").has_value());
    const std::vector<uint8_t> text = {'{', '}'};
    Expected<Scene> scene = load_gltf_memory(text, "empty.gltf");
    ASSERT_FALSE(scene.has_value());
    EXPECT_EQ(scene.error().message.rfind("empty.gltf: ", 0), 0u) << scene.error().message;
}

// Every prefix and many single-byte corruptions of valid files must give a scene or an error,
// never a crash (run under ASan/UBSan with PHOTOND_SANITIZE for full effect).
TEST(GltfLoaderErrors, TruncationsAndCorruptionsNeverCrash) {
    for (const std::string name : {"textured_quad.glb", "indexed_u16.gltf", "sparse.gltf"}) {
        SCOPED_TRACE(name);
        const std::vector<uint8_t> bytes = read_bytes(data_path(name));
        ASSERT_FALSE(bytes.empty());
        size_t failures = 0;
        for (size_t length = 0; length < bytes.size(); length += 7) {
            const std::span<const uint8_t> prefix(bytes.data(), length);
            failures += load_gltf_memory(prefix, name).has_value() ? 0 : 1;
        }
        EXPECT_GT(failures, 0u);
        for (size_t i = 0; i < bytes.size(); i += 3) {
            for (uint8_t value : {uint8_t('9'), uint8_t(0xff), uint8_t('-')}) {
                std::vector<uint8_t> corrupt = bytes;
                corrupt[i] = value;
                Expected<Scene> scene = load_gltf_memory(corrupt, name);
                if (scene) {
                    EXPECT_TRUE(scene->validate().is_ok());
                }
            }
        }
    }
}

}  // namespace
}  // namespace photond
