// Morph targets and skins in the pose a file gives (core/scene/gltf_deformation.cpp): against
// Blender's own deformation of the same scene (tests/data/gltf/blender_skin, written by Blender's
// glTF exporter) and against closed forms on the hand-made files of tests/data/gltf/generate.py.
#include "core/scene/gltf_loader.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <span>
#include <string>

namespace photond {
namespace {

namespace fs = std::filesystem;

fs::path data_path(const std::string& name) { return fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / name; }

Scene load_ok(const std::string& name) {
    Expected<Scene> scene = load_gltf_file(data_path(name));
    EXPECT_TRUE(scene.has_value()) << name << ": " << (scene ? "" : scene.error().message);
    return scene ? std::move(scene).value() : Scene{};
}

std::string load_error(const std::string& name) {
    Expected<Scene> scene = load_gltf_file(data_path(name));
    EXPECT_FALSE(scene.has_value()) << name << " loaded although it is broken";
    return scene ? std::string() : scene.error().message;
}

std::string all_warnings(const Scene& scene) {
    std::string text;
    for (const std::string& w : scene.warnings) text += "\n  " + w;
    return text;
}

/// Each vertex's material name (that of a triangle using it).
std::vector<std::string> vertex_materials(const Scene& s) {
    std::vector<std::string> m(s.positions.size());
    for (size_t t = 0; t < s.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) m[s.triangles[t][k]] = s.materials[s.triangle_materials[t]].name;
    return m;
}

/// How the vertices of `a` match those of `b` (of the same material): the largest distance to the
/// nearest one, and for those of material `normals_of`, taking among the coincident copies (a
/// seam's) the one whose normal agrees best, the largest 1 - cos between their normals.
struct VertexMatch {
    float distance = 0.0f;
    float worst_normal = 0.0f;
};
VertexMatch match_vertices(const Scene& a, const Scene& b, const std::string& normals_of) {
    const std::vector<std::string> ma = vertex_materials(a), mb = vertex_materials(b);
    constexpr float kCoincident = 2e-4f;
    VertexMatch match;
    for (size_t i = 0; i < a.positions.size(); ++i) {
        float nearest = std::numeric_limits<float>::infinity();
        for (size_t j = 0; j < b.positions.size(); ++j)
            if (ma[i] == mb[j]) nearest = std::min(nearest, glm::length(a.positions[i] - b.positions[j]));
        match.distance = std::max(match.distance, nearest);
        if (ma[i] != normals_of) continue;
        float normal = 2.0f;
        for (size_t j = 0; j < b.positions.size(); ++j)
            if (ma[i] == mb[j] && glm::length(a.positions[i] - b.positions[j]) <= nearest + kCoincident)
                normal = std::min(normal, 1.0f - glm::dot(a.normals[i], b.normals[j]));
        match.worst_normal = std::max(match.worst_normal, normal);
    }
    return match;
}

/// The mean 1 - cos between the normals of material `name`'s vertices and the mesh's own normals
/// there (its triangles' normals at the vertex, summed weighted by area; vertices welded by
/// position, so that seams count all their triangles).
float mean_normal_deviation(const Scene& s, const std::string& name) {
    const std::vector<std::string> m = vertex_materials(s);
    std::vector<Vec3> geometric(s.positions.size(), Vec3(0.0f));
    for (size_t t = 0; t < s.triangles.size(); ++t) {
        const glm::uvec3 tri = s.triangles[t];
        const Vec3 area = glm::cross(s.positions[tri.y] - s.positions[tri.x], s.positions[tri.z] - s.positions[tri.x]);
        for (size_t v = 0; v < s.positions.size(); ++v)
            for (int k = 0; k < 3; ++k)
                if (glm::length(s.positions[v] - s.positions[tri[k]]) < 1e-6f) geometric[v] += area;
    }
    double sum = 0.0;
    size_t count = 0;
    for (size_t v = 0; v < s.positions.size(); ++v) {
        if (m[v] != name) continue;
        sum += 1.0 - glm::dot(s.normals[v], glm::normalize(geometric[v]));
        ++count;
    }
    return count ? float(sum / double(count)) : 1.0f;
}

TEST(GltfDeformation, BlenderSkinAndShapeKeyMatchBlendersOwnDeformation) {
    // blender_skin/make_skin.py: a cylinder skinned to two bones, posed (60 and -20 degrees) under
    // a moved and turned rig, and a sphere with a shape key at 0.5. skinned.gltf holds the rest
    // meshes, the skin and the morph target; baked.gltf the meshes Blender deformed itself.
    const Scene skinned = load_ok("blender_skin/skinned.gltf");
    const Scene baked = load_ok("blender_skin/baked.gltf");
    ASSERT_EQ(skinned.triangles.size(), baked.triangles.size());
    ASSERT_FALSE(skinned.positions.empty());
    // Every vertex is where Blender put it, and the skinned cylinder's normals agree with
    // Blender's within the linear blend's own error at the elbow (it turns a vertex's rest normal
    // by the blend of its joints' matrices; Blender's normals are those of the deformed surface).
    for (const bool forward : {true, false}) {
        SCOPED_TRACE(forward ? "skinned.gltf against baked.gltf" : "baked.gltf against skinned.gltf");
        const VertexMatch m = forward ? match_vertices(skinned, baked, "Red") : match_vertices(baked, skinned, "Red");
        EXPECT_LT(m.distance, 1e-4f);
        EXPECT_LT(m.worst_normal, 0.03f);  // 0.012; with unturned normals 0.62
    }
    // Blender's baked sphere keeps its base shape's normals (the exporter does not recompute
    // them after the mix), so the morphed normals are held against the morphed surface itself.
    EXPECT_LT(mean_normal_deviation(skinned, "Blue"), 0.006f);  // 0.0030; the base normals' 0.0132
    // Nothing of the file is left out: no warning about skins or morph targets.
    EXPECT_TRUE(skinned.warnings.empty()) << all_warnings(skinned);
}


void expect_near(const Vec3& actual, const Vec3& expected, const std::string& what) {
    SCOPED_TRACE(what);
    EXPECT_NEAR(actual.x, expected.x, 1e-5f);
    EXPECT_NEAR(actual.y, expected.y, 1e-5f);
    EXPECT_NEAR(actual.z, expected.z, 1e-5f);
}

TEST(GltfDeformation, MorphTargetsAreBlendedByTheNodesOrTheMeshsWeights) {
    // morph.gltf (generate.py): target 0 (sparse) lifts vertices 2 and 3 by 1 and tilts their
    // normals by -0.5 in y, target 1 moves every vertex by +x. Node Shared takes the mesh's
    // weights [0.5, 0.25]; node Own its own [1, 0], and is moved by +5 in x.
    const Scene scene = load_ok("morph.gltf");
    ASSERT_EQ(scene.positions.size(), 8u);
    const Vec3 shared[4] = {{0.25f, 0, 0}, {1.25f, 0, 0}, {1.25f, 1, 0.5f}, {0.25f, 1, 0.5f}};
    const Vec3 own[4] = {{5, 0, 0}, {6, 0, 0}, {6, 1, 1}, {5, 1, 1}};
    for (int v = 0; v < 4; ++v) {
        expect_near(scene.positions[v], shared[v], "Shared vertex " + std::to_string(v));
        expect_near(scene.positions[4 + v], own[v], "Own vertex " + std::to_string(v));
        const bool tilted = v >= 2;
        expect_near(scene.normals[v], tilted ? glm::normalize(Vec3(0, -0.25f, 1)) : Vec3(0, 0, 1),
                    "Shared normal " + std::to_string(v));
        expect_near(scene.normals[4 + v], tilted ? glm::normalize(Vec3(0, -0.5f, 1)) : Vec3(0, 0, 1),
                    "Own normal " + std::to_string(v));
    }
    EXPECT_TRUE(scene.warnings.empty()) << all_warnings(scene);
}

// skin.gltf's strip as its skin places it (below).
const Vec3 kSkinnedStrip[7] = {{10, 0, 0}, {10.5f, 0, 0}, {10, 1, 0}, {10.25f, 1.25f, 0},
                               {9, 1, 0},  {9, 1.5f, 0},  {110, 3, 0}};

TEST(GltfDeformation, SkinsPlaceVerticesByTheirJointsAndIgnoreTheNodesTransform) {
    // skin.gltf (generate.py): the strip's rows are bound to J0, to J0 and J1 half and half, and
    // to J1, which stands turned 90 degrees about z at (10, 1, 0); the skinned node's translation
    // of 100 is ignored, as the specification asks. The last vertex has no weight: its node
    // places it (the root's 10 and the node's 100 in x).
    const Scene scene = load_ok("skin.gltf");
    ASSERT_EQ(scene.positions.size(), 7u);
    const Vec3 diagonal = glm::normalize(Vec3(1, 1, 0));
    const Vec3 normals[7] = {{1, 0, 0}, {1, 0, 0}, diagonal, diagonal, {0, 1, 0}, {0, 1, 0}, {1, 0, 0}};
    for (int v = 0; v < 7; ++v) {
        expect_near(scene.positions[v], kSkinnedStrip[v], "vertex " + std::to_string(v));
        expect_near(scene.normals[v], normals[v], "normal " + std::to_string(v));
    }
    EXPECT_TRUE(scene.warnings.empty()) << all_warnings(scene);
}

TEST(GltfDeformation, SkinInfluencesMayComeInTwoSets) {
    // skin_two_sets.gltf: skin.gltf with the middle row's J1 half in JOINTS_1/WEIGHTS_1; the mesh
    // is placed again by a root node without a skin, which draws it unskinned (its bind-space
    // vertices moved 5 in z) and is named in a warning.
    const Scene scene = load_ok("skin_two_sets.gltf");
    ASSERT_EQ(scene.positions.size(), 14u);
    const Vec3 bind[7] = {{10, 0, 0}, {10.5f, 0, 0}, {10, 1, 0}, {10.5f, 1, 0}, {10, 2, 0}, {10.5f, 2, 0}, {0, 3, 0}};
    for (int v = 0; v < 7; ++v) {
        expect_near(scene.positions[v], kSkinnedStrip[v], "skinned vertex " + std::to_string(v));
        expect_near(scene.positions[7 + v], bind[v] + Vec3(0, 0, 5), "unskinned vertex " + std::to_string(v));
    }
    ASSERT_EQ(scene.warnings.size(), 1u) << all_warnings(scene);
    EXPECT_NE(scene.warnings[0].find("mesh 0 'Strip' has skin influences (JOINTS_0) but node 4 'Unskinned' places "
                                     "it without a skin"),
              std::string::npos)
        << all_warnings(scene);
}

TEST(GltfDeformation, AFlatNormalMappedPrimitiveIsMorphedAndSkinnedWithItsFacesNormals) {
    // morph_skin_flat.gltf: a normal-mapped quad without NORMAL (unwelded for its tangents), its
    // far edge lifted by 1 (quantized morph displacements, weight 1), then turned 90 degrees
    // about z and raised by 3 in y by its joint: the plane z = y becomes z = -x below y = 3..4.
    const Scene scene = load_ok("morph_skin_flat.gltf");
    ASSERT_EQ(scene.triangles.size(), 2u);
    ASSERT_EQ(scene.positions.size(), 6u);
    const Vec3 corners[2][3] = {{{0, 3, 0}, {0, 4, 0}, {-1, 4, 1}}, {{0, 3, 0}, {-1, 4, 1}, {-1, 3, 1}}};
    const Vec3 normal = glm::normalize(Vec3(1, 0, 1));
    for (int t = 0; t < 2; ++t) {
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = scene.triangles[t][k];
            const std::string what = "triangle " + std::to_string(t) + " corner " + std::to_string(k);
            expect_near(scene.positions[v], corners[t][k], what);
            expect_near(scene.normals[v], normal, what + " normal");
            ASSERT_EQ(scene.tangents.size(), scene.positions.size());
            // The tangent, made anew for the morphed face, lies in it.
            EXPECT_NEAR(glm::length(Vec3(scene.tangents[v])), 1.0f, 1e-5f) << what;
            EXPECT_NEAR(glm::dot(Vec3(scene.tangents[v]), normal), 0.0f, 1e-5f) << what;
        }
    }
    EXPECT_TRUE(scene.warnings.empty()) << all_warnings(scene);
}

TEST(GltfDeformation, AMirroringJointFlipsTheTangentsBitangentSign) {
    // skin_mirrored.gltf: a triangle in the xy plane, normal +z, tangent +x with w = 1, bound to
    // a joint of scale (-1, 1, 1).
    const Scene scene = load_ok("skin_mirrored.gltf");
    ASSERT_EQ(scene.positions.size(), 3u);
    ASSERT_EQ(scene.tangents.size(), 3u);
    const Vec3 mirrored[3] = {{0, 0, 0}, {-1, 0, 0}, {0, 1, 0}};
    for (int v = 0; v < 3; ++v) {
        expect_near(scene.positions[v], mirrored[v], "vertex " + std::to_string(v));
        expect_near(scene.normals[v], Vec3(0, 0, 1), "normal " + std::to_string(v));
        expect_near(Vec3(scene.tangents[v]), Vec3(-1, 0, 0), "tangent " + std::to_string(v));
        EXPECT_EQ(scene.tangents[v].w, -1.0f) << "vertex " << v;
    }
}

TEST(GltfDeformation, MorphTargetsBeyondTheLimitAreRefusedBeforeTheyAreDecoded) {
    // 900 targets that all name the 21,000 positions of the mesh itself: 18.9 M displacements to
    // decode from a file of 350 kB. Refused by count before any is decoded.
    constexpr int kVertices = 21000, kTargets = 900;
    const std::string buffer(size_t(kVertices) * 12, '\0');
    std::string targets;
    for (int t = 0; t < kTargets; ++t) targets += std::string(t ? "," : "") + "{\"POSITION\":0}";
    const std::string json =
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":" + std::to_string(buffer.size()) +
        ",\"uri\":\"data:application/octet-stream;base64," + std::string(buffer.size() / 3 * 4, 'A') +
        "\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":" + std::to_string(buffer.size()) +
        "}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":" + std::to_string(kVertices) +
        ",\"type\":\"VEC3\"}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"targets\":[" +
        targets + "]}]}],\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}";
    const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(json.data()), json.size());
    const Expected<Scene> scene = load_gltf_memory(bytes, "many_targets.gltf");
    ASSERT_FALSE(scene.has_value());
    EXPECT_NE(scene.error().message.find("the file's morph targets hold more than 16777216 displacements"),
              std::string::npos)
        << scene.error().message;
}

TEST(GltfDeformation, BrokenSkinsAndMorphWeightsAreRefusedSayingWhy) {
    EXPECT_NE(load_error("broken/morph_weights_count.gltf")
                  .find("mesh 0 'Quad' gives 1 morph weights, but primitive 0 of mesh 0 'Quad' has 2 morph targets"),
              std::string::npos);
    EXPECT_NE(load_error("broken/skin_joint_out_of_range.gltf")
                  .find("mesh 0 'Strip' primitive 0: accessor 3 (JOINTS_0), vertex 2 names joint 2, but skin 0 "
                        "'Rig' of node 3 'Skinned' has 2 joints"),
              std::string::npos);
    EXPECT_NE(load_error("broken/skin_inverse_bind_count.gltf")
                  .find("skin 0 'Rig' has 2 joints but 1 inverse bind matrices"),
              std::string::npos);
    EXPECT_NE(load_error("broken/skin_joints_without_weights.gltf").find("JOINTS_0 has no WEIGHTS_0"),
              std::string::npos);
}

}  // namespace
}  // namespace photond
