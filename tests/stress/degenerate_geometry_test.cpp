// Degenerate geometry: zero-area and sliver triangles, duplicate vertices, inverted, missing and
// zero normals render the image of the clean scene; NaN and infinity in vertex data are refused
// with a message naming the vertex (SceneBuilder) or the accessor (glTF in memory). Every render
// is small (48 x 48), so a hang would show as a test timeout, never as a stuck CI.
#include <gtest/gtest.h>

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/scene/gltf_loader.h"
#include "core/scene/scene_transform.h"
#include "tests/stress/stress_support.h"

namespace photond {
namespace {

using stress::make_room;
using stress::RoomMaterials;
using stress::render_ok;
using stress::settings_for;
using stress::StressRenderSettings;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

class DegenerateGeometry : public testing::TestWithParam<std::string> {
protected:
    /// The clean room's image with this test's integrator, rendered once per integrator.
    const Image& clean_image() {
        static std::map<std::string, Image> images;
        auto it = images.find(GetParam());
        if (it == images.end())
            it = images.emplace(GetParam(), render_ok(make_room(), settings_for(GetParam()))).first;
        return it->second;
    }
    /// The clean room rendered with other seeds (render and photons): the noise level.
    const Image& other_seed_image() {
        static std::map<std::string, Image> images;
        auto it = images.find(GetParam());
        if (it == images.end()) {
            StressRenderSettings s = settings_for(GetParam());
            s.seed = 2;
            s.photon_seed = 2;
            it = images.emplace(GetParam(), render_ok(make_room(), s)).first;
        }
        return it->second;
    }
    Image render(Expected<Scene> scene) {
        return render_ok(std::move(scene), settings_for(GetParam()));
    }
};

// ------------------------------------------------------------------------ zero-area and slivers

/// Triangles of no (or almost no) area across the middle of the room: three equal vertices, three
/// collinear ones spanning the room, a sliver 1e-7 wide across the view, and one of each with an
/// emissive material (a zero-area light emits nothing and is skipped by the light set).
Status add_degenerate_triangles(SceneBuilder& builder, const RoomMaterials& m) {
    const std::vector<Vec3> positions = {
        {0.1f, 1.0f, 0.0f},   {0.1f, 1.0f, 0.0f},  {0.1f, 1.0f, 0.0f},    // a point
        {-0.9f, 0.3f, -0.5f}, {0.0f, 0.8f, -0.5f}, {0.9f, 1.3f, -0.5f},   // collinear
        {-0.9f, 1.5f, -0.8f}, {0.9f, 0.2f, 0.2f},  {-0.9f, 1.5f, -0.8f},  // a sliver ...
    };
    std::vector<Vec3> sliver = positions;
    sliver[8] += Vec3(0.0f, 1e-7f, 0.0f);  // ... 1e-7 wide
    const std::vector<glm::uvec3> triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
    if (Status s = builder.add_mesh(sliver, {}, {}, triangles, m.white); !s) return s;
    const std::vector<glm::uvec3> lights = {{0, 1, 2}, {3, 4, 5}};
    return builder.add_mesh(positions, {}, {}, lights, m.light);
}

TEST_P(DegenerateGeometry, ZeroAreaAndSliverTrianglesChangeNothing) {
    const Scene scene = make_room({}, add_degenerate_triangles).value();
    // The exactly degenerate emitter is skipped; the collinear one keeps the float rounding of its
    // cross product (area ~1e-8) and so a negligible power.
    const Scene clean = make_room().value();
    const Color power = LightSet(scene).total_power(), clean_power = LightSet(clean).total_power();
    EXPECT_NEAR(power.x, clean_power.x, 1e-6f * clean_power.x);
    // The same random streams see the same room: measured relMSE <= 8e-15.
    EXPECT_LT(stress::relative_mse(render(scene), clean_image()), 1e-9);
}

// ----------------------------------------------------------------------------- duplicate vertices

/// The room's walls unwelded (every triangle its own three vertices), every vertex repeated once
/// more, and zero-area triangles joining a vertex, its duplicate and a neighbour.
Status add_walls_with_duplicates(SceneBuilder& builder, uint32_t material) {
    MeshData walls = make_box(Vec3(-1.0f, 0.0f, -1.0f), Vec3(1.0f, 2.0f, 1.0f));
    flip_orientation(walls);
    MeshData unwelded;
    for (const glm::uvec3& t : walls.triangles) {
        const uint32_t base = static_cast<uint32_t>(unwelded.positions.size());
        for (const uint32_t v : {t.x, t.y, t.z}) {
            unwelded.positions.push_back(walls.positions[v]);
            unwelded.normals.push_back(walls.normals[v]);
            unwelded.uvs.push_back(walls.uvs[v]);
        }
        unwelded.triangles.emplace_back(base, base + 1, base + 2);
    }
    const uint32_t count = static_cast<uint32_t>(unwelded.positions.size());
    for (uint32_t v = 0; v < count; ++v) {
        unwelded.positions.push_back(unwelded.positions[v]);
        unwelded.normals.push_back(unwelded.normals[v]);
        unwelded.uvs.push_back(unwelded.uvs[v]);
    }
    for (uint32_t v = 0; v + 1 < count; v += 3)
        unwelded.triangles.emplace_back(v, v + count, v + 1);
    return add_mesh(builder, unwelded, material);
}

TEST_P(DegenerateGeometry, DuplicateVerticesChangeNothing) {
    // A room of walls and light only, once welded and once with the duplicates.
    const auto build = [](bool duplicates) {
        SceneBuilder builder("duplicates");
        const uint32_t white =
            builder.add_material(stress::lambertian_material("white", Color(0.7f)));
        Material light = stress::lambertian_material("light", Color(0.0f));
        light.emission = Color(8.0f);
        const uint32_t emitter = builder.add_material(light);
        MeshData walls = make_box(Vec3(-1.0f, 0.0f, -1.0f), Vec3(1.0f, 2.0f, 1.0f));
        flip_orientation(walls);
        EXPECT_TRUE(duplicates ? add_walls_with_duplicates(builder, white)
                               : add_mesh(builder, walls, white));
        EXPECT_TRUE(add_mesh(builder,
                             make_quad(Vec3(-0.3f, 1.98f, -0.3f), Vec3(0.6f, 0.0f, 0.0f),
                                       Vec3(0.0f, 0.0f, 0.6f), Vec3(0.0f, -1.0f, 0.0f)),
                             emitter));
        builder.add_camera(CameraDesc{
            "room", {0.0f, 1.0f, 0.95f}, {0.0f, 0.7f, -1.0f}, {0.0f, 1.0f, 0.0f}, 70.0f, 0.0f});
        return builder.build();
    };
    const Image welded = render(build(false));
    const Image duplicated = render(build(true));
    ASSERT_FALSE(welded.empty());
    EXPECT_GT(stress::mean_luminance(welded), 0.05);
    // Measured: bit-identical images.
    EXPECT_LT(stress::relative_mse(duplicated, welded), 1e-9);
}

// --------------------------------------------------------------- inverted, missing, zero normals

/// The room's walls with their normals replaced: negated (pointing against the winding), absent
/// (flat normals generated) or zero (the face normal is used), or the walls facing outwards (the
/// camera sees their back faces; opaque surfaces are shaded two-sided).
enum class NormalDefect { Negated, Missing, Zero, OutwardWalls };

Expected<Scene> room_with(NormalDefect defect) {
    stress::RoomOptions options;
    if (defect == NormalDefect::OutwardWalls) {
        options.inward_walls = false;
        return make_room(options);
    }
    // make_room adds the walls itself; rebuild the room with the altered walls instead.
    SceneBuilder builder("normals");
    const uint32_t white = builder.add_material(stress::lambertian_material("white", Color(0.7f)));
    const uint32_t red =
        builder.add_material(stress::lambertian_material("red", Color(0.7f, 0.15f, 0.1f)));
    Material light = stress::lambertian_material("light", Color(0.0f));
    light.emission = options.light_radiance;
    const uint32_t emitter = builder.add_material(light);
    MeshData walls = make_box(Vec3(-1.0f, 0.0f, -1.0f), Vec3(1.0f, 2.0f, 1.0f));
    flip_orientation(walls);
    switch (defect) {
        case NormalDefect::Negated:
            for (Vec3& n : walls.normals) n = -n;
            break;
        case NormalDefect::Missing:
            walls.normals.clear();
            break;
        case NormalDefect::Zero:
            for (Vec3& n : walls.normals) n = Vec3(0.0f);
            break;
        case NormalDefect::OutwardWalls:
            break;
    }
    if (Status s = add_mesh(builder, walls, white); !s) return s.error();
    if (Status s =
            add_mesh(builder, make_box(Vec3(-0.6f, 0.0f, -0.5f), Vec3(-0.1f, 0.7f, 0.0f)), red);
        !s)
        return s.error();
    const MeshData quad = make_quad(Vec3(-0.3f, 1.98f, -0.3f), Vec3(0.6f, 0.0f, 0.0f),
                                    Vec3(0.0f, 0.0f, 0.6f), Vec3(0.0f, -1.0f, 0.0f));
    if (Status s = add_mesh(builder, quad, emitter); !s) return s.error();
    builder.add_camera(CameraDesc{
        "room", {0.0f, 1.0f, 0.95f}, {0.0f, 0.7f, -1.0f}, {0.0f, 1.0f, 0.0f}, 70.0f, 0.0f});
    return builder.build();
}

TEST_P(DegenerateGeometry, InvertedMissingAndZeroNormalsRenderTheCleanImage) {
    // Missing and zero normals give the face normals the clean room has: the same image. Negated
    // vertex normals are turned back to the geometric side, and opaque back faces are shaded as
    // front faces, so those images differ only where the shading frame's tangents differ (its
    // construction follows the sign of a zero normal component, Frame in core/math/frame.h):
    // other random directions, noise. They must then stay within half of the difference a
    // second seed makes. Measured (block relMSE, see stress_support.h): path 0.0025 against
    // 0.0135 for a new seed; photon-map 0.00028 against 0.0013; direct: identical.
    const Image& clean = clean_image();
    const Image& noise = other_seed_image();
    const double noise_blocks = stress::block_relative_mse(noise, clean);
    ASSERT_GT(noise_blocks, 0.0);
    for (const auto& [defect, label] :
         {std::pair{NormalDefect::Negated, "negated vertex normals"},
          std::pair{NormalDefect::Missing, "missing normals"},
          std::pair{NormalDefect::Zero, "zero normals"},
          std::pair{NormalDefect::OutwardWalls, "walls facing outwards"}}) {
        SCOPED_TRACE(label);
        const Image image = render(room_with(defect));
        ASSERT_FALSE(image.empty());
        if (defect == NormalDefect::Missing || defect == NormalDefect::Zero ||
            GetParam() == "direct") {
            EXPECT_LT(stress::relative_mse(image, clean), 1e-9);
        } else {
            EXPECT_LT(stress::block_relative_mse(image, clean), 0.5 * noise_blocks);
            EXPECT_LT(std::abs(stress::mean_bias(image, clean)), 0.02);
        }
    }
}

// ----------------------------------------------------------------------- NaN and infinity: builder

/// A triangle with one bad value; add_mesh must refuse it with the vertex and the field named.
std::string add_mesh_error(std::vector<Vec3> positions, std::vector<Vec3> normals,
                           std::vector<Vec2> uvs) {
    SceneBuilder builder("bad");
    const uint32_t material =
        builder.add_material(stress::lambertian_material("white", Color(0.5f)));
    const std::vector<glm::uvec3> triangles = {{0, 1, 2}};
    const Status status = builder.add_mesh(positions, normals, uvs, triangles, material);
    EXPECT_FALSE(status) << "a mesh with a non-finite value was accepted";
    // Nothing of the refused mesh was added: the builder still builds an empty, valid scene.
    Expected<Scene> rest = builder.build();
    EXPECT_TRUE(rest.has_value());
    if (rest) {
        EXPECT_TRUE(rest->positions.empty());
    }
    return status ? std::string() : status.error().message;
}

TEST(NonFiniteInput, SceneBuilderRefusesNaNAndInfinityNamingTheVertex) {
    const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const std::vector<Vec3> n = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    const std::vector<Vec2> uv = {{0, 0}, {1, 0}, {0, 1}};
    auto with = [](auto v, size_t i, auto value) {
        v[i] = value;
        return v;
    };
    EXPECT_EQ(add_mesh_error(with(p, 2, Vec3(0, kNaN, 0)), n, uv),
              "vertex 2 has a non-finite position");
    EXPECT_EQ(add_mesh_error(with(p, 1, Vec3(kInf, 0, 0)), n, uv),
              "vertex 1 has a non-finite position");
    EXPECT_EQ(add_mesh_error(with(p, 0, Vec3(0, 0, -kInf)), {}, {}),
              "vertex 0 has a non-finite position");
    EXPECT_EQ(add_mesh_error(p, with(n, 1, Vec3(0, kInf, 1)), uv),
              "vertex 1 has a non-finite normal");
    EXPECT_EQ(add_mesh_error(p, with(n, 0, Vec3(kNaN)), uv), "vertex 0 has a non-finite normal");
    EXPECT_EQ(add_mesh_error(p, n, with(uv, 2, Vec2(kNaN, 0))),
              "vertex 2 has a non-finite texture coordinate");
}

TEST(NonFiniteInput, OverflowingTransformsLightsMaterialsAndCamerasAreRefused) {
    const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const std::vector<glm::uvec3> triangles = {{0, 1, 2}};
    {
        // Finite input, but the transform overflows the float range: build() refuses the result.
        SceneBuilder builder("overflow");
        const uint32_t material =
            builder.add_material(stress::lambertian_material("white", Color(0.5f)));
        Mat4 huge(1.0f);
        huge[0][0] = 1e38f;  // vertex 1 lands at 1e38 + 3e38, beyond the float range
        huge[3] = Vec4(3e38f, 0.0f, 0.0f, 1.0f);
        ASSERT_TRUE(builder.add_mesh(p, {}, {}, triangles, material, huge));
        Expected<Scene> scene = builder.build();
        ASSERT_FALSE(scene.has_value());
        EXPECT_NE(scene.error().message.find("non-finite position"), std::string::npos)
            << scene.error().message;
        EXPECT_NE(scene.error().message.find("'overflow'"), std::string::npos)
            << scene.error().message;
    }
    {
        SceneBuilder builder("bad light");
        PunctualLight light;
        light.name = "lamp";
        light.intensity = Color(1.0f, kNaN, 1.0f);
        builder.add_light(light);
        Expected<Scene> scene = builder.build();
        ASSERT_FALSE(scene.has_value());
        EXPECT_NE(scene.error().message.find("light 'lamp' has a non-finite value"),
                  std::string::npos)
            << scene.error().message;
    }
    {
        SceneBuilder builder("bad material");
        Material m = stress::lambertian_material("glow", Color(0.5f));
        m.emission = Color(kInf);
        const uint32_t material = builder.add_material(m);
        ASSERT_TRUE(builder.add_mesh(p, {}, {}, triangles, material));
        Expected<Scene> scene = builder.build();
        ASSERT_FALSE(scene.has_value());
        EXPECT_NE(scene.error().message.find("material 'glow' has a non-finite factor"),
                  std::string::npos)
            << scene.error().message;
    }
    {
        CameraDesc camera;
        camera.name = "eye";
        camera.position = Vec3(0.0f, kNaN, 0.0f);
        Expected<Camera> created = Camera::create(camera, 8, 8);
        ASSERT_FALSE(created.has_value());
        EXPECT_NE(created.error().message.find("camera 'eye'"), std::string::npos)
            << created.error().message;
    }
    {
        // transform_scene refuses what leaves the float range, naming it.
        Expected<Scene> scene = transform_scene(make_room().value(), {1e39, DVec3(0.0)});
        ASSERT_FALSE(scene.has_value());
        EXPECT_NE(scene.error().message.find("leaves the float range"), std::string::npos)
            << scene.error().message;
        EXPECT_FALSE(transform_scene(make_room().value(), {0.0, DVec3(0.0)}).has_value());
        EXPECT_FALSE(transform_scene(make_room().value(), {-1.0, DVec3(0.0)}).has_value());
        EXPECT_FALSE(
            transform_scene(make_room().value(), {1.0, DVec3(kNaN, 0.0, 0.0)}).has_value());
    }
}

// ------------------------------------------------------------------------ NaN and infinity: glTF

std::string base64(const std::vector<uint8_t>& bytes) {
    static const char* kAlphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        const uint32_t b0 = bytes[i], b1 = i + 1 < bytes.size() ? bytes[i + 1] : 0u,
                       b2 = i + 2 < bytes.size() ? bytes[i + 2] : 0u;
        const uint32_t triple = (b0 << 16) | (b1 << 8) | b2;
        out += kAlphabet[(triple >> 18) & 63];
        out += kAlphabet[(triple >> 12) & 63];
        out += i + 1 < bytes.size() ? kAlphabet[(triple >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? kAlphabet[triple & 63] : '=';
    }
    return out;
}

/// A self-contained glTF of one triangle with POSITION, NORMAL and TEXCOORD_0 (in that order in
/// one buffer), a point light and a camera; `node_extra` is spliced into the mesh node.
std::vector<uint8_t> triangle_gltf(const std::vector<Vec3>& positions,
                                   const std::vector<Vec3>& normals, const std::vector<Vec2>& uvs,
                                   const std::string& node_extra = "",
                                   const std::string& light_intensity = "10") {
    std::vector<uint8_t> buffer;
    const auto append = [&buffer](const float* data, size_t count) {
        const auto* bytes = reinterpret_cast<const uint8_t*>(data);
        buffer.insert(buffer.end(), bytes, bytes + count * sizeof(float));
    };
    append(&positions[0].x, 9);
    append(&normals[0].x, 9);
    append(&uvs[0].x, 6);
    const std::string json = R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": )" +
                             light_intensity + R"(}]}},
  "buffers": [{"byteLength": 96, "uri": "data:application/octet-stream;base64,)" +
                             base64(buffer) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 72, "byteLength": 24}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}],
  "meshes": [{"name": "Tri",
              "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}]}],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
  "nodes": [{"name": "Mesh", "mesh": 0)" +
                             node_extra + R"(},
            {"name": "Lamp", "translation": [0.3, 0.3, 1],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "Eye", "camera": 0, "translation": [0.3, 0.3, 2]}],
  "scenes": [{"nodes": [0, 1, 2]}],
  "scene": 0
})";
    return {json.begin(), json.end()};
}

TEST(NonFiniteInput, GltfInMemoryRefusesNaNAndInfinityNamingTheAccessor) {
    const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const std::vector<Vec3> n = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    const std::vector<Vec2> uv = {{0, 0}, {1, 0}, {0, 1}};
    {
        // The valid file loads and renders a finite image (so the refusals below are the values').
        Expected<Scene> scene = load_gltf_memory(triangle_gltf(p, n, uv), "upload.gltf");
        ASSERT_TRUE(scene.has_value()) << scene.error().message;
        EXPECT_EQ(scene->triangles.size(), 1u);
        StressRenderSettings settings = settings_for("path");
        settings.width = settings.height = 16;
        const Image image = render_ok(std::move(scene).value(), settings);
        EXPECT_GT(stress::max_luminance(image), 0.0);
    }
    struct BadCase {
        const char* label;
        std::vector<Vec3> positions, normals;
        std::vector<Vec2> uvs;
        std::string expected;
    };
    const std::vector<BadCase> cases = {
        {"NaN position",
         {{0, 0, 0}, {kNaN, 0, 0}, {0, 1, 0}},
         n,
         uv,
         "accessor 0 (POSITION) has a non-finite value at element 1"},
        {"infinite position",
         {{0, 0, 0}, {1, 0, 0}, {0, -kInf, 0}},
         n,
         uv,
         "accessor 0 (POSITION) has a non-finite value at element 2"},
        {"infinite normal",
         p,
         {{0, 0, kInf}, {0, 0, 1}, {0, 0, 1}},
         uv,
         "accessor 1 (NORMAL) has a non-finite value at element 0"},
        {"NaN normal",
         p,
         {{0, 0, 1}, {0, 0, 1}, {kNaN, 0, 1}},
         uv,
         "accessor 1 (NORMAL) has a non-finite value at element 2"},
        {"NaN texture coordinate",
         p,
         n,
         {{0, 0}, {kNaN, 0}, {0, 1}},
         "(TEXCOORD_0) has a non-finite value at element 1"},
    };
    for (const BadCase& c : cases) {
        SCOPED_TRACE(c.label);
        Expected<Scene> scene =
            load_gltf_memory(triangle_gltf(c.positions, c.normals, c.uvs), "upload.gltf");
        ASSERT_FALSE(scene.has_value());
        const std::string& message = scene.error().message;
        EXPECT_EQ(message.rfind("upload.gltf: ", 0), 0u) << message;
        EXPECT_NE(message.find("mesh 0 'Tri' primitive 0"), std::string::npos) << message;
        EXPECT_NE(message.find(c.expected), std::string::npos) << message;
    }
    // Numbers that are finite in JSON but overflow the renderer's floats are refused too.
    for (const auto& [label, gltf] :
         {std::pair{"translation 1e39",
                    triangle_gltf(p, n, uv, R"(, "translation": [1e39, 0, 0])")},
          std::pair{"scale 1e39", triangle_gltf(p, n, uv, R"(, "scale": [1e39, 1e39, 1e39])")},
          std::pair{"light intensity 1e39", triangle_gltf(p, n, uv, "", "1e39")}}) {
        SCOPED_TRACE(label);
        Expected<Scene> scene = load_gltf_memory(gltf, "upload.gltf");
        ASSERT_FALSE(scene.has_value());
        EXPECT_NE(scene.error().message.find("upload.gltf"), std::string::npos)
            << scene.error().message;
        EXPECT_NE(scene.error().message.find("non-finite"), std::string::npos)
            << scene.error().message;
    }
}

INSTANTIATE_TEST_SUITE_P(Integrators, DegenerateGeometry,
                         testing::Values("path", "photon-map", "direct"),
                         [](const testing::TestParamInfo<std::string>& info) {
                             return info.param == "photon-map" ? std::string("photon_map")
                                                               : info.param;
                         });

}  // namespace
}  // namespace photond
