#include "core/scene/builtin_scenes.h"
#include "core/scene/scene_lighting.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "core/accel/ray_tracer.h"
#include "core/integrators/path.h"
#include "core/material/bsdf.h"
#include "core/math/rng.h"
#include "core/math/sampling.h"
#include "core/render/tile_renderer.h"
#include "core/scene/scene_hash.h"
#include "core/scene/shapes.h"

namespace photond {
namespace {

// ---------------------------------------------------------------------------------------------
// Helpers

Scene build_or_die(std::string_view name) {
    Expected<Scene> scene = make_builtin_scene(name);
    EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().message);
    if (!scene) return Scene{};
    return std::move(scene).value();
}

uint32_t material_index(const Scene& scene, const std::string& name) {
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        if (scene.materials[i].name == name) return static_cast<uint32_t>(i);
    }
    ADD_FAILURE() << "scene '" << scene.name << "' has no material '" << name << "'";
    return 0;
}

std::vector<glm::uvec3> triangles_of(const Scene& scene, uint32_t material) {
    std::vector<glm::uvec3> out;
    for (size_t i = 0; i < scene.triangles.size(); ++i) {
        if (scene.triangle_materials[i] == material) out.push_back(scene.triangles[i]);
    }
    return out;
}

Vec3 geometric_normal(const std::vector<Vec3>& positions, const glm::uvec3& t) {
    return glm::normalize(
        glm::cross(positions[t.y] - positions[t.x], positions[t.z] - positions[t.x]));
}

Vec3 centroid(const std::vector<Vec3>& positions, const glm::uvec3& t) {
    return (positions[t.x] + positions[t.y] + positions[t.z]) / 3.0f;
}

/// Smallest dot product between a vertex normal and its triangle's geometric normal.
float min_normal_agreement(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                           const std::vector<glm::uvec3>& triangles) {
    float worst = 1.0f;
    for (const glm::uvec3& t : triangles) {
        const Vec3 ng = geometric_normal(positions, t);
        for (uint32_t v : {t.x, t.y, t.z}) worst = std::min(worst, glm::dot(ng, normals[v]));
    }
    return worst;
}

/// Irradiance at `x` (surface normal `n`) from the scene's emissive triangles, ignoring
/// occlusion: Lambert's formula for a polygon of uniform radiance, E = L / 2 * sum_i
/// beta_i (n . gamma_i) (e.g. Arvo 1994, "The Irradiance Jacobian for Partially Occluded
/// Polyhedral Sources", eq. 1), per triangle whose front face sees x.
Color direct_irradiance(const Scene& scene, const Vec3& x, const Vec3& n) {
    DVec3 e(0.0);
    for (size_t i = 0; i < scene.triangles.size(); ++i) {
        const Material& m = scene.materials[scene.triangle_materials[i]];
        if (!m.is_emissive()) continue;
        const glm::uvec3& t = scene.triangles[i];
        if (glm::dot(geometric_normal(scene.positions, t), x - centroid(scene.positions, t)) <= 0)
            continue;
        const DVec3 u[3] = {glm::normalize(DVec3(scene.positions[t.x] - x)),
                            glm::normalize(DVec3(scene.positions[t.y] - x)),
                            glm::normalize(DVec3(scene.positions[t.z] - x))};
        double sum = 0.0;
        for (int k = 0; k < 3; ++k) {
            const DVec3& a = u[k];
            const DVec3& b = u[(k + 1) % 3];
            const double beta = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
            sum += beta * glm::dot(DVec3(n), glm::normalize(glm::cross(a, b)));
        }
        e += 0.5 * std::abs(sum) * DVec3(m.emission);
    }
    return Color(e);
}

/// Total emitted power of the one-sided Lambertian emitters: sum of pi L A.
double area_light_power(const Scene& scene) {
    double power = 0.0;
    for (uint32_t i = 0; i < scene.triangles.size(); ++i) {
        const Material& m = scene.materials[scene.triangle_materials[i]];
        if (m.is_emissive()) power += kPi * average(m.emission) * scene.triangle_area(i);
    }
    return power;
}

// ---------------------------------------------------------------------------------------------
// Shapes

TEST(Shapes, IcosphereIsClosedOutwardAndSmooth) {
    for (int level : {0, 1, 3, 5}) {
        const Vec3 center(1.0f, -2.0f, 0.5f);
        const float radius = 2.0f;
        const MeshData s = make_icosphere(center, radius, level);
        const size_t four_n = size_t{1} << (2 * level);
        EXPECT_EQ(s.positions.size(), 10 * four_n + 2) << "level " << level;
        EXPECT_EQ(s.triangles.size(), 20 * four_n);
        EXPECT_EQ(s.normals.size(), s.positions.size());
        EXPECT_EQ(s.uvs.size(), s.positions.size());
        EXPECT_TRUE(is_watertight(s.triangles)) << "level " << level;
        for (size_t i = 0; i < s.positions.size(); ++i) {
            ASSERT_NEAR(glm::length(s.positions[i] - center), radius, 1e-5f);
            ASSERT_NEAR(glm::length(s.normals[i]), 1.0f, 1e-5f);
            ASSERT_GT(glm::dot(s.normals[i], s.positions[i] - center), 0.0f);
        }
        // Volume about the origin is translation-invariant for a closed mesh.
        const double volume = signed_volume(s.positions, s.triangles);
        const double sphere_volume = 4.0 / 3.0 * kPi * radius * radius * radius;
        EXPECT_GT(volume, 0.0);
        if (level >= 3) {
            EXPECT_NEAR(volume / sphere_volume, 1.0, 0.01) << "level " << level;
        }
        if (level >= 1) {
            EXPECT_GT(min_normal_agreement(s.positions, s.normals, s.triangles), 0.9f);
        }
    }
}

TEST(Shapes, FlipTurnsTheSphereInsideOut) {
    MeshData s = make_icosphere(Vec3(0.0f), 1.0f, 3);
    flip_orientation(s);
    EXPECT_TRUE(is_watertight(s.triangles));
    EXPECT_LT(signed_volume(s.positions, s.triangles), 0.0);
    EXPECT_GT(min_normal_agreement(s.positions, s.normals, s.triangles), 0.9f);
    for (size_t i = 0; i < s.positions.size(); ++i) {
        ASSERT_LT(glm::dot(s.normals[i], s.positions[i]), 0.0f);
    }
}

TEST(Shapes, WatertightDetectsHolesAndFlippedFaces) {
    MeshData s = make_icosphere(Vec3(0.0f), 1.0f, 2);
    ASSERT_TRUE(is_watertight(s.triangles));
    std::vector<glm::uvec3> holed(s.triangles.begin() + 1, s.triangles.end());
    EXPECT_FALSE(is_watertight(holed));
    std::vector<glm::uvec3> flipped = s.triangles;
    std::swap(flipped[7].y, flipped[7].z);
    EXPECT_FALSE(is_watertight(flipped));
    EXPECT_FALSE(is_watertight({}));
}

TEST(Shapes, QuadFacesTheChosenSide) {
    const Vec3 corner(1.0f, 2.0f, 3.0f), eu(2.0f, 0.0f, 0.0f), ev(0.0f, 0.0f, 3.0f);
    // cross(eu, ev) = -y.
    const MeshData plain = make_quad(corner, eu, ev);
    ASSERT_EQ(plain.triangles.size(), 2u);
    for (const glm::uvec3& t : plain.triangles) {
        EXPECT_GT(glm::dot(geometric_normal(plain.positions, t), Vec3(0, -1, 0)), 0.999f);
    }
    for (const Vec3& facing : {Vec3(0, 1, 0), Vec3(0.3f, -1, 0.2f)}) {
        const MeshData q = make_quad(corner, eu, ev, facing);
        for (const glm::uvec3& t : q.triangles) {
            EXPECT_GT(glm::dot(geometric_normal(q.positions, t), facing), 0.0f);
        }
        EXPECT_GT(min_normal_agreement(q.positions, q.normals, q.triangles), 0.999f);
        // Area of the parallelogram.
        float area = 0.0f;
        for (const glm::uvec3& t : q.triangles) {
            area += 0.5f * glm::length(glm::cross(q.positions[t.y] - q.positions[t.x],
                                                  q.positions[t.z] - q.positions[t.x]));
        }
        EXPECT_NEAR(area, 6.0f, 1e-5f);
    }
    const std::array<Vec3, 4> corners = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0),
                                         Vec3(0, 1, 0)};
    for (const Vec3& facing : {Vec3(0, 0, 1), Vec3(0, 0, -1)}) {
        const MeshData q = make_quad(corners, facing);
        for (const glm::uvec3& t : q.triangles) {
            EXPECT_GT(glm::dot(geometric_normal(q.positions, t), facing), 0.999f);
        }
        EXPECT_GT(min_normal_agreement(q.positions, q.normals, q.triangles), 0.999f);
    }
}

void expect_outward_box(const MeshData& box, double expected_volume) {
    ASSERT_EQ(box.positions.size(), 24u);
    ASSERT_EQ(box.triangles.size(), 12u);
    Vec3 center(0.0f);
    for (const Vec3& p : box.positions) center += p;
    center /= static_cast<float>(box.positions.size());
    for (const glm::uvec3& t : box.triangles) {
        EXPECT_GT(glm::dot(geometric_normal(box.positions, t), centroid(box.positions, t) - center),
                  0.0f);
    }
    EXPECT_GT(min_normal_agreement(box.positions, box.normals, box.triangles), 0.999f);
    // Closed geometrically (although each face has its own vertices): the divergence theorem
    // gives the box's volume.
    EXPECT_NEAR(signed_volume(box.positions, box.triangles), expected_volume,
                1e-4 * expected_volume);
}

TEST(Shapes, BoxesFaceOutward) {
    expect_outward_box(make_box(Vec3(-1.0f, 0.0f, 2.0f), Vec3(2.0f, 0.5f, 4.0f)), 3.0);
    // A rotated box from 8 corners, once in a right-handed and once in a mirrored labelling.
    const float c = std::cos(0.3f), s = std::sin(0.3f);
    std::array<Vec3, 8> corners, mirrored;
    for (int i = 0; i < 8; ++i) {
        const Vec3 local((i & 1) ? 2.0f : 0.0f, (i & 2) ? 1.0f : 0.0f, (i & 4) ? 3.0f : 0.0f);
        corners[i] = Vec3(c * local.x - s * local.z, local.y, s * local.x + c * local.z);
    }
    for (int i = 0; i < 8; ++i) mirrored[i] = corners[i ^ 1];
    expect_outward_box(make_box(corners), 6.0);
    expect_outward_box(make_box(mirrored), 6.0);
}

// ---------------------------------------------------------------------------------------------
// Scenes

TEST(BuiltinScenes, NamesAreListedAndUnique) {
    const std::vector<std::string> names = builtin_scene_names();
    const std::set<std::string> unique(names.begin(), names.end());
    EXPECT_EQ(unique.size(), names.size());
    for (const char* expected : {"cornell-box", "cornell-box-diffuse", "caustic", "caustic-area",
                                 "furnace", "spheres-room", "sunlit-room", "large-city",
                                 "foggy-room", "glossy-objects"}) {
        EXPECT_TRUE(unique.contains(expected)) << expected;
    }
}

TEST(BuiltinScenes, EveryBuiltinBuildsValidatesAndHasOneCameraAndLight) {
    for (const std::string& name : builtin_scene_names()) {
        const auto start = std::chrono::steady_clock::now();
        Expected<Scene> scene = make_builtin_scene(name);
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        ASSERT_TRUE(scene.has_value()) << name << ": " << scene.error().message;
        EXPECT_EQ(scene->name, name);
        EXPECT_TRUE(scene->validate().is_ok()) << name;
        EXPECT_FALSE(scene->triangles.empty()) << name;
        EXPECT_FALSE(scene->bounds.empty()) << name;
        ASSERT_EQ(scene->cameras.size(), 1u) << name;
        EXPECT_EQ(scene->cameras[0].aspect, 0.0f) << name;
        EXPECT_GT(glm::length(scene->cameras[0].look_at - scene->cameras[0].position), 0.0f);
        EXPECT_TRUE(scene_emits_light(*scene)) << name << " has no light";
        for (size_t i = 0; i < scene->triangles.size(); ++i) {
            ASSERT_GT(scene->triangle_area(static_cast<uint32_t>(i)), 0.0f)
                << name << ": degenerate triangle " << i;
        }
        // The budget is 50 ms in Release (large-city: 400 ms for its 2M triangles); leave room
        // for sanitizers and loaded CI machines.
        EXPECT_LT(ms, name == "large-city" ? 5000.0 : 500.0) << name;
        std::printf("[ info ] %-20s %7zu triangles, built in %.1f ms\n", name.c_str(),
                    scene->triangles.size(), ms);
    }
}

TEST(BuiltinScenes, UnknownNameErrorListsTheKnownNames) {
    const Expected<Scene> scene = make_builtin_scene("cornell-boxx");
    ASSERT_FALSE(scene.has_value());
    const std::string& message = scene.error().message;
    EXPECT_NE(message.find("cornell-boxx"), std::string::npos) << message;
    for (const std::string& name : builtin_scene_names()) {
        EXPECT_NE(message.find(name), std::string::npos) << message;
    }
}

void expect_closed_outward_sphere(const Scene& scene, const std::string& material) {
    const std::vector<glm::uvec3> tris = triangles_of(scene, material_index(scene, material));
    ASSERT_FALSE(tris.empty());
    EXPECT_TRUE(is_watertight(tris)) << scene.name << " / " << material;
    EXPECT_GT(signed_volume(scene.positions, tris), 0.0) << scene.name << " / " << material;
    EXPECT_GT(min_normal_agreement(scene.positions, scene.normals, tris), 0.9f)
        << scene.name << " / " << material;
}

TEST(BuiltinScenes, SpheresAreClosedOutwardAndRestOnTheFloor) {
    const Scene cornell = build_or_die("cornell-box");
    expect_closed_outward_sphere(cornell, "glass");
    expect_closed_outward_sphere(cornell, "mirror");
    for (const char* name : {"caustic", "caustic-area"}) {
        const Scene caustic = build_or_die(name);
        expect_closed_outward_sphere(caustic, "glass");
        // Resting on the floor: lowest point at y = 0 (within float rounding).
        float lowest = 1e9f;
        for (const glm::uvec3& t : triangles_of(caustic, material_index(caustic, "glass"))) {
            for (uint32_t v : {t.x, t.y, t.z}) lowest = std::min(lowest, caustic.positions[v].y);
        }
        EXPECT_NEAR(lowest, 0.0f, 1e-5f) << name;
    }
}

TEST(BuiltinScenes, SceneMaterialsFollowTheGltfConventions) {
    const Scene cornell = build_or_die("cornell-box");
    const Material& glass = cornell.materials[material_index(cornell, "glass")];
    EXPECT_EQ(glass.transmission, 1.0f);
    EXPECT_EQ(glass.ior, 1.5f);
    EXPECT_EQ(glass.roughness, 0.0f);
    EXPECT_EQ(glass.metallic, 0.0f);
    const Material& mirror = cornell.materials[material_index(cornell, "mirror")];
    EXPECT_EQ(mirror.metallic, 1.0f);
    EXPECT_EQ(mirror.roughness, 0.0f);
    EXPECT_GE(min_component(mirror.base_color), 0.9f);
    for (const char* wall : {"white", "red", "blue"}) {
        const Material& m = cornell.materials[material_index(cornell, wall)];
        EXPECT_EQ(m.specular, 0.0f) << wall;
        EXPECT_EQ(m.metallic, 0.0f) << wall;
        EXPECT_EQ(m.roughness, 1.0f) << wall;
        EXPECT_FALSE(m.is_emissive()) << wall;
    }
    EXPECT_EQ(cornell.materials[material_index(cornell, "red")].base_color,
              Color(0.75f, 0.25f, 0.25f));
    const Scene diffuse = build_or_die("cornell-box-diffuse");
    for (const Material& m : diffuse.materials) {
        EXPECT_EQ(m.specular, 0.0f) << m.name;
        EXPECT_EQ(m.transmission, 0.0f) << m.name;
        EXPECT_EQ(m.metallic, 0.0f) << m.name;
    }
}

TEST(BuiltinScenes, FurnaceSphereFacesInwardWithTheAnalyticConstants) {
    EXPECT_FLOAT_EQ(kFurnaceRadiance, 2.0f);
    const Scene furnace = build_or_die("furnace");
    ASSERT_EQ(furnace.materials.size(), 1u);
    const Material& m = furnace.materials[0];
    EXPECT_EQ(m.base_color, Color(kFurnaceAlbedo));
    EXPECT_EQ(m.emission, Color(kFurnaceEmission));
    EXPECT_FALSE(m.double_sided);
    EXPECT_EQ(m.specular, 0.0f);
    EXPECT_EQ(m.metallic, 0.0f);
    EXPECT_EQ(m.transmission, 0.0f);
    EXPECT_TRUE(is_watertight(furnace.triangles));
    EXPECT_LT(signed_volume(furnace.positions, furnace.triangles), 0.0);
    EXPECT_GT(min_normal_agreement(furnace.positions, furnace.normals, furnace.triangles), 0.9f);
    for (const glm::uvec3& t : furnace.triangles) {
        const Vec3 c = centroid(furnace.positions, t);
        ASSERT_GT(glm::dot(geometric_normal(furnace.positions, t), -c), 0.9f * glm::length(c));
    }
    for (const Vec3& p : furnace.positions) ASSERT_NEAR(glm::length(p), 1.0f, 1e-5f);
    EXPECT_LT(glm::length(furnace.cameras[0].position), 1e-6f);
}

TEST(BuiltinScenes, CornellBoxWallsFaceTheInteriorAndTheLightFacesDown) {
    const Scene scene = build_or_die("cornell-box");
    const Vec3 interior(0.0f, 2.75f, 0.0f);
    const uint32_t light = material_index(scene, "light");
    int walls = 0;
    for (const char* name : {"white", "red", "blue", "light"}) {
        const uint32_t m = material_index(scene, name);
        for (const glm::uvec3& t : triangles_of(scene, m)) {
            const Vec3 n = geometric_normal(scene.positions, t);
            EXPECT_GT(glm::dot(n, interior - centroid(scene.positions, t)), 0.0f) << name;
            if (m == light) {
                EXPECT_LT(n.y, -0.999f);
                for (uint32_t v : {t.x, t.y, t.z}) {
                    EXPECT_LT(scene.positions[v].y, 5.5f);
                    EXPECT_GT(scene.positions[v].y, 5.45f);
                }
            }
            ++walls;
        }
    }
    EXPECT_EQ(walls, 12);  // floor, ceiling, back, left, right, light: two triangles each
    // Red is on the left and blue on the right as the camera sees them.
    const CameraDesc& cam = scene.cameras[0];
    const Vec3 right = glm::cross(glm::normalize(cam.look_at - cam.position), cam.up);
    const auto side = [&](const char* name) {
        const glm::uvec3 t = triangles_of(scene, material_index(scene, name))[0];
        return glm::dot(centroid(scene.positions, t) - cam.look_at, right);
    };
    EXPECT_LT(side("red"), 0.0f);
    EXPECT_GT(side("blue"), 0.0f);
}

TEST(BuiltinScenes, CornellBoxDiffuseMatchesThePublishedData) {
    const Scene scene = build_or_die("cornell-box-diffuse");
    // The light: 213..343 x 227..332 mm at y = 548.8 mm, scaled by 0.01, facing down.
    Bounds3 light;
    double area = 0.0;
    for (uint32_t i = 0; i < scene.triangles.size(); ++i) {
        if (!scene.materials[scene.triangle_materials[i]].is_emissive()) continue;
        const glm::uvec3& t = scene.triangles[i];
        for (uint32_t v : {t.x, t.y, t.z}) light.extend(scene.positions[v]);
        area += scene.triangle_area(i);
        EXPECT_LT(scene.triangle_normal(i).y, -0.9999f);
    }
    EXPECT_NEAR(light.lower.x, 2.13f, 1e-5f);
    EXPECT_NEAR(light.upper.x, 3.43f, 1e-5f);
    EXPECT_NEAR(light.lower.z, 2.27f, 1e-5f);
    EXPECT_NEAR(light.upper.z, 3.32f, 1e-5f);
    EXPECT_NEAR(light.lower.y, 5.488f, 1e-5f);
    EXPECT_NEAR(light.upper.y, 5.488f, 1e-5f);
    EXPECT_NEAR(area, 1.30 * 1.05, 1e-4);
    // The room: 0..556 x 0..548.8 x 0..559.2 mm.
    EXPECT_NEAR(scene.bounds.lower.x, 0.0f, 1e-5f);
    EXPECT_NEAR(scene.bounds.upper.x, 5.56f, 1e-5f);
    EXPECT_NEAR(scene.bounds.upper.y, 5.488f, 1e-5f);
    EXPECT_NEAR(scene.bounds.upper.z, 5.592f, 1e-5f);
    // The published camera.
    const CameraDesc& cam = scene.cameras[0];
    EXPECT_NEAR(cam.position.x, 2.78f, 1e-5f);
    EXPECT_NEAR(cam.position.y, 2.73f, 1e-5f);
    EXPECT_NEAR(cam.position.z, -8.0f, 1e-5f);
    EXPECT_NEAR(cam.vfov_deg, 39.3077f, 1e-3f);
    const Vec3 forward = glm::normalize(cam.look_at - cam.position);
    EXPECT_NEAR(forward.z, 1.0f, 1e-6f);

    // The blocks: closed boxes at their published corners, faces outward; walls face inward.
    struct Block {
        Vec2 lower, upper;  // footprint bounds (mm)
        float height;       // mm
        float footprint;    // mm^2, shoelace area of the published top face
    };
    const auto shoelace = [](std::initializer_list<Vec2> poly) {
        const std::vector<Vec2> p(poly);
        double a = 0.0;
        for (size_t i = 0; i < p.size(); ++i) {
            const Vec2& u = p[i];
            const Vec2& v = p[(i + 1) % p.size()];
            a += double(u.x) * v.y - double(v.x) * u.y;
        }
        return static_cast<float>(std::abs(a) / 2.0);
    };
    const Block blocks[2] = {
        {{82, 65}, {290, 272}, 165, shoelace({{130, 65}, {82, 225}, {240, 272}, {290, 114}})},
        {{265, 247}, {472, 456}, 330, shoelace({{423, 247}, {265, 296}, {314, 456}, {472, 406}})}};
    std::vector<bool> in_block(scene.triangles.size(), false);
    for (const Block& b : blocks) {
        std::vector<glm::uvec3> tris;
        for (size_t i = 0; i < scene.triangles.size(); ++i) {
            const glm::uvec3& t = scene.triangles[i];
            bool inside = true;
            for (uint32_t v : {t.x, t.y, t.z}) {
                const Vec3 p = scene.positions[v] * 100.0f;
                inside &= p.x > b.lower.x - 0.01f && p.x < b.upper.x + 0.01f &&
                          p.z > b.lower.y - 0.01f && p.z < b.upper.y + 0.01f &&
                          p.y < b.height + 0.01f;
            }
            if (inside) {
                tris.push_back(t);
                in_block[i] = true;
            }
        }
        ASSERT_EQ(tris.size(), 12u) << "block of height " << b.height;
        const double volume_mm3 = signed_volume(scene.positions, tris) * 1e6;
        EXPECT_NEAR(volume_mm3, double(b.footprint) * b.height, 1e-4 * b.footprint * b.height);
        Vec3 center(0.0f);
        for (const glm::uvec3& t : tris) center += centroid(scene.positions, t);
        center /= static_cast<float>(tris.size());
        for (const glm::uvec3& t : tris) {
            EXPECT_GT(glm::dot(geometric_normal(scene.positions, t),
                               centroid(scene.positions, t) - center),
                      0.0f);
        }
    }
    const Vec3 interior = 0.01f * Vec3(278.0f, 274.4f, 279.6f);
    int walls = 0;
    for (size_t i = 0; i < scene.triangles.size(); ++i) {
        if (in_block[i]) continue;
        const glm::uvec3& t = scene.triangles[i];
        EXPECT_GT(
            glm::dot(geometric_normal(scene.positions, t), interior - centroid(scene.positions, t)),
            0.0f);
        ++walls;
    }
    EXPECT_EQ(walls, 2 * (4 + 9));  // floor, back, left, right and the 3 x 3 ceiling cells
}

TEST(BuiltinScenes, CausticAreaLightHasThePointLightsPower) {
    const Scene point = build_or_die("caustic");
    const Scene area = build_or_die("caustic-area");
    ASSERT_EQ(point.lights.size(), 1u);
    EXPECT_TRUE(area.lights.empty());
    const PunctualLight& light = point.lights[0];
    EXPECT_EQ(light.type, PunctualLightType::Point);
    const double point_power = 4.0 * kPi * average(light.intensity);
    const double emitted = area_light_power(area);
    EXPECT_NEAR(emitted / point_power, 1.0, 1e-4);
    // Same place, the given size, facing the sphere.
    Bounds3 b;
    Vec3 normal(0.0f);
    double light_area = 0.0;
    for (uint32_t i = 0; i < area.triangles.size(); ++i) {
        if (!area.materials[area.triangle_materials[i]].is_emissive()) continue;
        const glm::uvec3& t = area.triangles[i];
        for (uint32_t v : {t.x, t.y, t.z}) b.extend(area.positions[v]);
        normal += area.triangle_normal(i);
        light_area += area.triangle_area(i);
    }
    EXPECT_NEAR(light_area, kCausticAreaLightSide * kCausticAreaLightSide, 1e-6);
    EXPECT_LT(glm::length(b.center() - light.position), 1e-5f);
    const Vec3 to_sphere = glm::normalize(Vec3(0.0f, 1.0f, 0.0f) - light.position);
    EXPECT_GT(glm::dot(glm::normalize(normal), to_sphere), 0.999f);
    EXPECT_FALSE(area.materials[material_index(area, "area-light")].double_sided);
}

TEST(BuiltinScenes, EmissionGivesAWellExposedFloor) {
    // Direct irradiance on the lit floor about pi, so that the floor's radiance is about its
    // albedo at exposure 0.
    const Vec3 up(0.0f, 1.0f, 0.0f);
    const Scene cornell = build_or_die("cornell-box");
    const float e_cornell = luminance(direct_irradiance(cornell, Vec3(0.0f), up));
    EXPECT_GT(e_cornell, 0.85f * kPi);
    EXPECT_LT(e_cornell, 1.15f * kPi);
    const Scene diffuse = build_or_die("cornell-box-diffuse");
    const float e_diffuse = luminance(direct_irradiance(diffuse, Vec3(2.78f, 0.0f, 2.796f), up));
    EXPECT_GT(e_diffuse, 0.85f * kPi);
    EXPECT_LT(e_diffuse, 1.15f * kPi);
    // Caustic: the floor beside the sphere, on the caustic's side.
    const Scene caustic = build_or_die("caustic");
    const Vec3 floor_point(1.0f, 0.0f, 0.7f);
    const Vec3 to_light = caustic.lights[0].position - floor_point;
    const float d2 = glm::dot(to_light, to_light);
    const float e_point =
        average(caustic.lights[0].intensity) * glm::dot(up, to_light) / std::sqrt(d2) / d2;
    EXPECT_GT(e_point, 0.75f * kPi);
    EXPECT_LT(e_point, 1.25f * kPi);
    std::printf(
        "[ info ] direct floor irradiance / pi: cornell-box %.3f, cornell-box-diffuse "
        "%.3f, caustic %.3f\n",
        e_cornell / kPi, e_diffuse / kPi, e_point / kPi);
}

TEST(BuiltinScenes, CamerasLookAtTheirScenes) {
    for (const std::string& name : {std::string("cornell-box"), std::string("cornell-box-diffuse"),
                                    std::string("caustic"), std::string("caustic-area")}) {
        const Scene scene = build_or_die(name);
        const CameraDesc& cam = scene.cameras[0];
        const Vec3 forward = glm::normalize(cam.look_at - cam.position);
        // Every floor-level object the scenes are about is inside the vertical field of view.
        const Vec3 target = name == "caustic" || name == "caustic-area"
                                ? Vec3(0.7f, 0.0f, 0.5f)  // the caustic
                                : scene.bounds.center();
        const Vec3 to_target = glm::normalize(target - cam.position);
        EXPECT_GT(glm::dot(forward, to_target), std::cos(glm::radians(0.5f * cam.vfov_deg)))
            << name;
    }
    const Scene caustic = build_or_die("caustic");
    const CameraDesc& cam = caustic.cameras[0];
    const Vec3 forward = glm::normalize(cam.look_at - cam.position);
    EXPECT_NEAR(std::asin(-forward.y), glm::radians(30.0f), 1e-3f);  // looking down at 30 deg
}

/// The scene's only light is a square of side `side` just below the ceiling at `height`, facing down.
void expect_one_ceiling_light(const Scene& scene, float height, float side) {
    double light_area = 0.0;
    for (uint32_t i = 0; i < scene.triangles.size(); ++i) {
        if (!scene.materials[scene.triangle_materials[i]].is_emissive()) continue;
        light_area += scene.triangle_area(i);
        EXPECT_LT(scene.triangle_normal(i).y, -0.9999f);
        for (uint32_t v : {scene.triangles[i].x, scene.triangles[i].y, scene.triangles[i].z}) {
            EXPECT_NEAR(scene.positions[v].y, height, 0.02f);
        }
    }
    EXPECT_NEAR(light_area, side * side, 1e-5);
}

TEST(BuiltinScenes, SpheresRoomIsLargeLambertianAndLitFromTheCeiling) {
    const Scene scene = build_or_die("spheres-room");
    // The benchmark's large scene: at least 100 000 triangles (20 spheres of 5120, 10 boxes of
    // 12 carrying spheres of 1280, and 12 for the walls and the light).
    EXPECT_GE(scene.triangles.size(), 100'000u);
    EXPECT_EQ(scene.triangles.size(), 20u * 5120u + 10u * (12u + 1280u) + 12u);
    EXPECT_TRUE(scene.lights.empty());
    // Lambertian only, so that a path-traced reference converges.
    for (const Material& m : scene.materials) {
        EXPECT_EQ(m.specular, 0.0f) << m.name;
        EXPECT_EQ(m.metallic, 0.0f) << m.name;
        EXPECT_EQ(m.transmission, 0.0f) << m.name;
        EXPECT_EQ(m.roughness, 1.0f) << m.name;
        EXPECT_LE(max_component(m.base_color), 0.8f) << m.name;
    }
    expect_one_ceiling_light(scene, kSpheresRoomHeight, kSpheresRoomLightSide);
    EXPECT_NEAR(area_light_power(scene),
                kPi * kSpheresRoomLightRadiance * kSpheresRoomLightSide * kSpheresRoomLightSide,
                1e-3);
    // Well exposed: direct irradiance about pi at the floor's centre (ignoring the objects).
    const float e = luminance(direct_irradiance(scene, Vec3(0.0f), Vec3(0.0f, 1.0f, 0.0f)));
    EXPECT_GT(e, 0.85f * kPi);
    EXPECT_LT(e, 1.15f * kPi);
    // Every object stands inside the room, on or above the floor.
    EXPECT_NEAR(scene.bounds.lower.y, 0.0f, 1e-5f);
    EXPECT_NEAR(scene.bounds.upper.y, kSpheresRoomHeight, 1e-5f);
    EXPECT_NEAR(scene.bounds.lower.x, -kSpheresRoomHalfWidth, 1e-5f);
    EXPECT_NEAR(scene.bounds.upper.z, kSpheresRoomHalfWidth, 1e-5f);
    // The spheres are closed and face outward, one mesh per colour.
    for (const char* colour : {"ivory", "terracotta", "teal", "ochre", "slate"}) {
        const std::vector<glm::uvec3> tris = triangles_of(scene, material_index(scene, colour));
        EXPECT_GT(tris.size(), 5000u) << colour;
        EXPECT_GT(signed_volume(scene.positions, tris), 0.0) << colour;
    }
}

TEST(BuiltinScenes, LargeCityHasTwoMillionTrianglesAndHundredsOfLightsOfVariedPower) {
    const Scene scene = build_or_die("large-city");
    EXPECT_GT(scene.triangles.size(), 1'800'000u);
    EXPECT_LT(scene.triangles.size(), 2'200'000u);
    EXPECT_EQ(scene.lights.size(), static_cast<size_t>(kLargeCityPointLights));
    // A lamp (two triangles) over every crossing, facing down.
    std::vector<float> powers;
    for (uint32_t i = 0; i < scene.triangles.size(); ++i) {
        const Material& m = scene.materials[scene.triangle_materials[i]];
        if (!m.is_emissive()) continue;
        EXPECT_LT(scene.triangle_normal(i).y, -0.9999f);
        powers.push_back(kPi * average(m.emission) * scene.triangle_area(i));
    }
    EXPECT_EQ(powers.size(), 2u * (kLargeCityBlocks + 1) * (kLargeCityBlocks + 1));
    for (const PunctualLight& l : scene.lights) powers.push_back(4.0f * kPi * average(l.intensity));
    // Varied: the strongest light carries over a hundred times the weakest's power.
    const auto [weakest, strongest] = std::minmax_element(powers.begin(), powers.end());
    EXPECT_GT(*strongest, 100.0f * *weakest);
    for (const Material& m : scene.materials) {
        EXPECT_EQ(m.metallic, 0.0f) << m.name;
        EXPECT_EQ(m.transmission, 0.0f) << m.name;
    }
    // Deterministic: built again, the same content.
    EXPECT_EQ(scene_content_hash(scene), scene_content_hash(build_or_die("large-city")));
    EXPECT_FALSE(scene.environment.has_value());
}

/// A small path render of a built-in scene from its camera: every pixel finite and
/// non-negative, the mean in a sane range, and the top and bottom rows not black (the camera
/// frames the room, not the void beyond it).
void expect_renders_and_fills_the_frame(const std::string& name, int size = 24, double min_mean = 0.02,
                                        double min_edge_share = 0.05) {
    auto device = EmbreeDevice::create();
    ASSERT_TRUE(device.has_value()) << device.error().message;
    auto scene = std::make_shared<const Scene>(build_or_die(name));
    auto render_scene = RenderScene::create(*device, scene);
    ASSERT_TRUE(render_scene.has_value()) << render_scene.error().message;
    const int kSize = size;
    auto camera = Camera::create(scene->cameras.at(0), kSize, kSize);
    ASSERT_TRUE(camera.has_value());
    PathIntegrator integrator(*render_scene);
    TileSettings settings;
    settings.tile_size = kSize / 2;
    settings.samples_per_pixel = 8;
    settings.seed = 7;
    const TileRenderResult r = render_tiles(integrator, *camera, settings);
    ASSERT_EQ(r.layers.beauty.width(), kSize);
    double total = 0.0;
    std::vector<double> row_sum(kSize, 0.0);
    for (int y = 0; y < kSize; ++y) {
        for (int x = 0; x < kSize; ++x) {
            const Color c = r.layers.beauty.pixels()[static_cast<size_t>(y) * kSize + x];
            ASSERT_TRUE(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z)) << name;
            ASSERT_GE(min_component(c), 0.0f) << name;
            row_sum[y] += average(c);
        }
        total += row_sum[y];
    }
    const double mean = total / (kSize * kSize);
    EXPECT_GT(mean, min_mean) << name;
    EXPECT_LT(mean, 5.0) << name;
    EXPECT_GT(row_sum.front() / kSize, min_edge_share * mean) << name;
    EXPECT_GT(row_sum.back() / kSize, min_edge_share * mean) << name;
}

TEST(BuiltinScenes, SpheresRoomRendersFiniteAndFillsTheFrame) {
    expect_renders_and_fills_the_frame("spheres-room", 32, 0.05, 0.1);
}

/// Lowest y of the triangles of one material.
float lowest_y(const Scene& scene, uint32_t material) {
    float lowest = std::numeric_limits<float>::infinity();
    for (const glm::uvec3& t : triangles_of(scene, material)) {
        for (uint32_t v : {t.x, t.y, t.z}) lowest = std::min(lowest, scene.positions[v].y);
    }
    return lowest;
}

TEST(BuiltinScenes, FoggyRoomIsClosedFoggyAndLitByASpotThroughTheWindow) {
    const Scene scene = build_or_die("foggy-room");
    // The fog is the scene's own (a job's atmosphere replaces it): it scatters forward, and its
    // optical depth across the room is between 0.3 and 1, so that the shafts show and the room
    // beyond them is not black.
    ASSERT_TRUE(scene.atmosphere.has_value());
    const HomogeneousMedium& fog = *scene.atmosphere;
    EXPECT_TRUE(fog.scatters());
    EXPECT_GE(fog.g, 0.3f);
    EXPECT_LE(fog.g, 0.5f);
    const float depth = max_component(fog.sigma_t()) * 2.0f * kFoggyRoomHalfWidth;
    EXPECT_GT(depth, 0.3f);
    EXPECT_LT(depth, 1.0f);
    EXPECT_FALSE(scene.environment.has_value());
    // One spot light; everything else Lambertian, nothing emits.
    ASSERT_EQ(scene.lights.size(), 1u);
    const PunctualLight& spot = scene.lights[0];
    EXPECT_EQ(spot.type, PunctualLightType::Spot);
    EXPECT_NEAR(glm::length(spot.direction), 1.0f, 1e-5f);
    EXPECT_LT(spot.direction.y, -0.5f);  // down across the room
    EXPECT_LT(spot.cos_outer, spot.cos_inner);
    for (const Material& m : scene.materials) {
        EXPECT_FALSE(m.is_emissive()) << m.name;
        EXPECT_EQ(m.specular, 0.0f) << m.name;
        EXPECT_EQ(m.metallic, 0.0f) << m.name;
        EXPECT_EQ(m.transmission, 0.0f) << m.name;
        EXPECT_EQ(m.roughness, 1.0f) << m.name;
    }
    for (const char* name :
         {"white", "floor", "red", "blue", "plaster", "stone", "wood", "ivory"}) {
        EXPECT_FALSE(triangles_of(scene, material_index(scene, name)).empty()) << name;
    }
    // The room's box is the scene's bounds, which the fog fills.
    EXPECT_NEAR(scene.bounds.lower.x, -kFoggyRoomHalfWidth, 1e-5f);
    EXPECT_NEAR(scene.bounds.upper.z, kFoggyRoomHalfWidth, 1e-5f);
    EXPECT_NEAR(scene.bounds.lower.y, 0.0f, 1e-5f);
    EXPECT_NEAR(scene.bounds.upper.y, kFoggyRoomHeight, 1e-5f);

    auto device = EmbreeDevice::create();
    ASSERT_TRUE(device.has_value()) << device.error().message;
    auto tracer = RayTracer::build(*device, scene);
    ASSERT_TRUE(tracer.has_value()) << tracer.error().message;
    // Closed: rays from the camera in every direction hit a wall facing them (no light leaves
    // the room, no ray sees the void).
    const Vec3 eye = scene.cameras[0].position;
    Rng rng(11, 0);
    for (int i = 0; i < 2000; ++i) {
        const Vec3 d = sample_uniform_sphere(rng.next_vec2());
        const std::optional<Hit> hit = (*tracer)->intersect(Ray{eye, d});
        ASSERT_TRUE(hit.has_value()) << "direction " << d.x << " " << d.y << " " << d.z;
        EXPECT_LT(glm::dot(scene.triangle_normal(hit->triangle), d), 0.0f);
    }
    // The light is in the chamber behind the partition, hidden from the camera.
    EXPECT_LT(spot.position.z, kFoggyRoomPartitionZ - kFoggyRoomPartitionThickness);
    EXPECT_TRUE((*tracer)->occluded(Ray{eye, spot.position - eye, 1e-4f, 0.999f}));
    // Its axis points at the window (at the cross of the mullions), each pane inside the inner
    // cone, and through each pane a shaft crosses the room in front of the partition.
    const float t_window = (kFoggyRoomPartitionZ - spot.position.z) / spot.direction.z;
    const Vec3 through = spot.position + t_window * spot.direction;
    EXPECT_GT(through.x, kFoggyRoomWindow[0]);
    EXPECT_LT(through.x, kFoggyRoomWindow[1]);
    EXPECT_GT(through.y, kFoggyRoomWindow[2]);
    EXPECT_LT(through.y, kFoggyRoomWindow[3]);
    const float mx = 0.5f * (kFoggyRoomWindow[0] + kFoggyRoomWindow[1]);
    const float my = 0.5f * (kFoggyRoomWindow[2] + kFoggyRoomWindow[3]);
    double e = 0.0;
    for (float x : {0.5f * (kFoggyRoomWindow[0] + mx), 0.5f * (mx + kFoggyRoomWindow[1])}) {
        for (float y : {0.5f * (kFoggyRoomWindow[2] + my), 0.5f * (my + kFoggyRoomWindow[3])}) {
            const Vec3 to_pane = glm::normalize(Vec3(x, y, kFoggyRoomPartitionZ) - spot.position);
            EXPECT_GT(glm::dot(to_pane, spot.direction), spot.cos_inner) << x << " " << y;
            const std::optional<Hit> hit = (*tracer)->intersect(Ray{spot.position, to_pane});
            ASSERT_TRUE(hit.has_value());
            EXPECT_GT((spot.position + hit->t * to_pane).z, kFoggyRoomPartitionZ) << x << " " << y;
            // The spot's irradiance through the fog where the shaft meets the floor's plane.
            const float d = -spot.position.y / to_pane.y;
            e += 0.25 * luminance(spot.intensity) * -to_pane.y / (d * d) *
                 luminance(fog.transmittance(d));
        }
    }
    // Well exposed: about 3 pi where the shafts land, since the rest of the room is lit only by
    // the light they bring (the image's mean is then about that of sunlit-room).
    EXPECT_GT(e, 2.5 * kPi);
    EXPECT_LT(e, 3.5 * kPi);
    std::printf(
        "[ info ] foggy-room: optical depth %.2f across the room, irradiance / pi %.3f "
        "where the shafts land\n",
        depth, e / kPi);
}

TEST(BuiltinScenes, GlossyObjectsAreGlossyMetalsAndPlasticsUnderACeilingLight) {
    const Scene scene = build_or_die("glossy-objects");
    EXPECT_TRUE(scene.lights.empty());
    EXPECT_FALSE(scene.environment.has_value());
    EXPECT_FALSE(scene.atmosphere.has_value());
    // Metals at four roughnesses, two plastics, a coated box and a torus: all glossy, no ideal
    // mirror and no glass.
    struct Object {
        const char* name;
        float metallic, roughness, clearcoat;
    };
    const Object objects[] = {
        {"gold", 1.0f, 0.1f, 0.0f},           {"copper", 1.0f, 0.2f, 0.0f},
        {"steel", 1.0f, 0.35f, 0.0f},         {"aluminium", 1.0f, 0.5f, 0.0f},
        {"brushed-gold", 1.0f, 0.3f, 0.0f},   {"red-plastic", 0.0f, 0.2f, 0.0f},
        {"green-plastic", 0.0f, 0.35f, 0.0f}, {"blue-coated", 0.0f, 0.6f, 1.0f}};
    for (const Object& o : objects) {
        const uint32_t index = material_index(scene, o.name);
        const Material& m = scene.materials[index];
        EXPECT_EQ(m.metallic, o.metallic) << o.name;
        EXPECT_EQ(m.roughness, o.roughness) << o.name;
        EXPECT_EQ(m.clearcoat, o.clearcoat) << o.name;
        EXPECT_GT(m.specular, 0.0f) << o.name;
        // Resting on the floor.
        EXPECT_NEAR(lowest_y(scene, index), 0.0f, 1e-4f) << o.name;
    }
    EXPECT_GT(scene.materials[material_index(scene, "blue-coated")].clearcoat_roughness,
              kDeltaRoughness);
    EXPECT_LT(scene.materials[material_index(scene, "blue-coated")].clearcoat_roughness,
              kGlossyRoughness);
    bool glossy = false, rough = false;
    for (const Material& m : scene.materials) {
        EXPECT_EQ(m.transmission, 0.0f) << m.name;
        EXPECT_GT(m.roughness, kDeltaRoughness) << m.name;
        if (m.specular > 0.0f) {
            glossy |= m.roughness < kGlossyRoughness;
            rough |= m.roughness >= kGlossyRoughness && m.metallic == 1.0f;
        }
    }
    // Both sides of the photon passes' line: lobes that count as glossy and a metal that counts
    // as diffuse.
    EXPECT_TRUE(glossy);
    EXPECT_TRUE(rough);
    // Coloured Lambertian walls.
    for (const char* wall : {"white", "floor", "orange", "teal"}) {
        const Material& m = scene.materials[material_index(scene, wall)];
        EXPECT_EQ(m.specular, 0.0f) << wall;
        EXPECT_EQ(m.metallic, 0.0f) << wall;
        EXPECT_EQ(m.roughness, 1.0f) << wall;
        EXPECT_FALSE(m.is_emissive()) << wall;
    }
    // Closed, outward-facing spheres and torus.
    for (const char* sphere :
         {"gold", "copper", "steel", "aluminium", "red-plastic", "green-plastic"}) {
        expect_closed_outward_sphere(scene, sphere);
    }
    const std::vector<glm::uvec3> torus =
        triangles_of(scene, material_index(scene, "brushed-gold"));
    EXPECT_TRUE(is_watertight(torus));
    EXPECT_GT(min_normal_agreement(scene.positions, scene.normals, torus), 0.9f);
    // 2 pi^2 R r^2 for the major radius 0.5 and the minor 0.16 (the tessellation is a little
    // smaller).
    EXPECT_NEAR(signed_volume(scene.positions, torus), 2.0 * kPi * kPi * 0.5 * 0.16 * 0.16, 0.01);
    expect_one_ceiling_light(scene, kGlossyObjectsHeight, kGlossyObjectsLightSide);
    // Well exposed: direct irradiance about pi at the floor's centre (ignoring the objects).
    const float e = luminance(direct_irradiance(scene, Vec3(0.0f), Vec3(0.0f, 1.0f, 0.0f)));
    EXPECT_GT(e, 0.85f * kPi);
    EXPECT_LT(e, 1.15f * kPi);
    EXPECT_NEAR(scene.bounds.upper.y, kGlossyObjectsHeight, 1e-5f);
    EXPECT_NEAR(scene.bounds.lower.x, -kGlossyObjectsHalfWidth, 1e-5f);
}


TEST(BuiltinScenes, FoggyRoomAndGlossyObjectsRenderFiniteAndFillTheFrame) {
    expect_renders_and_fills_the_frame("foggy-room");
    expect_renders_and_fills_the_frame("glossy-objects");
}

}  // namespace
}  // namespace photond
