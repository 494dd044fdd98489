// Photons for the caustic map aimed at its casters (core/light/emission_focus.h): the same flux
// reaches the focus spheres as when they leave by the light's own distribution, and the cover of
// the casters holds every caster and keeps separate objects apart.
#include <gtest/gtest.h>

#include "core/light/emission_focus.h"
#include "core/light/light_set.h"
#include "core/math/rng.h"
#include "core/scene/shapes.h"

namespace photond {
namespace {

/// A scene of `lights` and, with `triangle_radiance` > 0, the emissive triangle (0,0,1), (2,0,1),
/// (0,1,1) facing +z (one- or two-sided); the triangle gives the scene its bounds either way.
Scene scene_with(const std::vector<PunctualLight>& lights, float triangle_radiance, bool double_sided) {
    SceneBuilder builder("focus");
    Material m;
    m.base_color = Color(0.0f);
    m.emission = Color(triangle_radiance);
    m.double_sided = double_sided;
    const uint32_t material = builder.add_material(m);
    const Vec3 positions[3] = {{0, 0, 1}, {2, 0, 1}, {0, 1, 1}};
    const glm::uvec3 triangle[1] = {{0, 1, 2}};
    EXPECT_TRUE(builder.add_mesh(positions, {}, {}, triangle, material).is_ok());
    for (const PunctualLight& l : lights) builder.add_light(l);
    return builder.build().value();
}

/// Whether the ray (origin, unit direction) meets the sphere, or starts inside it.
bool meets(const Vec3& origin, const Vec3& direction, const FocusSphere& sphere) {
    const Vec3 to_center = sphere.center - origin;
    const float d2 = glm::dot(to_center, to_center), r2 = sphere.radius * sphere.radius;
    if (d2 <= r2) return true;
    const float along = glm::dot(to_center, direction);
    return along > 0.0f && d2 - along * along <= r2;
}

/// Emits kSamples photons from the scene's one light, aimed at `focus` (or at `aim` when given)
/// or not, and returns the mean flux per photon of those that meet one of the spheres of `focus`;
/// `meeting` counts them and `largest` (when given) is the largest flux one of them carries.
DVec3 flux_into(const Scene& scene, const EmissionFocus& focus, bool aimed, int* meeting, double* largest = nullptr,
                const EmissionFocus* aim = nullptr) {
    constexpr int kSamples = 1000000;
    const LightSet lights(scene);
    Rng rng(31, 32);
    DVec3 flux(0.0);
    *meeting = 0;
    for (int i = 0; i < kSamples; ++i) {
        const float u_select = rng.next_float();
        const Vec2 u_position = rng.next_vec2(), u_direction = rng.next_vec2();
        const float u_focus = rng.next_float();
        const auto e = lights.sample_emission(u_select, u_position, u_direction, aimed ? (aim ? aim : &focus) : nullptr, u_focus);
        if (!e || is_black(e->flux_weight)) continue;
        EXPECT_NEAR(glm::length(e->direction), 1.0f, 1e-4f);
        bool hit = false;
        for (const FocusSphere& s : focus.spheres) hit = hit || meets(e->origin, e->direction, s);
        if (!hit) continue;
        flux += DVec3(e->flux_weight);
        if (largest) *largest = std::max(*largest, double(max_component(e->flux_weight)));
        ++*meeting;
    }
    return flux / static_cast<double>(kSamples);
}

/// Two spheres, one of them partly behind the triangle's plane z = 1.
EmissionFocus two_spheres() {
    EmissionFocus focus;
    focus.spheres = {{Vec3(0.6f, 0.3f, 2.5f), 0.3f}, {Vec3(2.6f, -1.0f, 1.1f), 0.4f}};
    focus.center = Vec3(1.6f, -0.35f, 1.8f);
    focus.radius = 2.0f;
    return focus;
}

/// The same mean flux into the spheres aimed or not, and no aimed photon heavier than the
/// heaviest unaimed one (emission_focus.h); with `gains`, aiming sends far more photons there.
void expect_same_flux(const Scene& scene, const EmissionFocus& focus, const char* what, bool gains = true) {
    int plain_meeting = 0, aimed_meeting = 0;
    double plain_largest = 0.0, aimed_largest = 0.0;
    const DVec3 plain = flux_into(scene, focus, false, &plain_meeting, &plain_largest);
    const DVec3 aimed = flux_into(scene, focus, true, &aimed_meeting, &aimed_largest);
    ASSERT_GT(plain_meeting, 1000) << what;
    EXPECT_LE(aimed_largest, plain_largest * 1.0001) << what;
    if (gains) {
        EXPECT_GT(aimed_meeting, 500000) << what << ": aimed, most photons meet a sphere";
        EXPECT_GT(aimed_meeting, 5 * plain_meeting) << what;
    }
    // The plain estimate's own error dominates: about 1 / sqrt(plain_meeting).
    const double tolerance = 4.0 / std::sqrt(static_cast<double>(plain_meeting));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(aimed[c] / plain[c], 1.0, tolerance) << what << " channel " << c;
}

TEST(EmissionFocus, PointLightSendsTheSameFluxIntoTheSpheres) {
    PunctualLight light;
    light.position = Vec3(0.5f, 0.2f, 0.0f);
    light.intensity = Color(3.0f, 2.0f, 1.0f);
    expect_same_flux(scene_with({light}, 0.0f, false), two_spheres(), "point");
}

TEST(EmissionFocus, PointLightInsideASphereSendsItEverything) {
    PunctualLight light;
    light.position = Vec3(0.5f, 0.2f, 0.0f);
    light.intensity = Color(3.0f);
    EmissionFocus focus = two_spheres();
    focus.spheres.push_back({Vec3(0.6f, 0.25f, 0.1f), 0.3f});
    const Scene scene = scene_with({light}, 0.0f, false);
    int meeting = 0;
    const DVec3 flux = flux_into(scene, focus, true, &meeting);
    EXPECT_EQ(meeting, 1000000);
    EXPECT_NEAR(flux.x, 4.0 * kPi * 3.0, 0.01 * 4.0 * kPi * 3.0);
}

TEST(EmissionFocus, SpotLightSendsTheSameFluxIntoTheSpheres) {
    PunctualLight light;
    light.type = PunctualLightType::Spot;
    light.position = Vec3(0.5f, 0.2f, 0.0f);
    light.direction = glm::normalize(Vec3(0.2f, 0.0f, 1.0f));
    light.intensity = Color(5.0f);
    light.cos_inner = std::cos(0.1f);
    light.cos_outer = std::cos(0.35f);
    expect_same_flux(scene_with({light}, 0.0f, false), two_spheres(), "spot");
}

TEST(EmissionFocus, OneSidedTriangleSendsTheSameFluxIntoTheSpheres) {
    expect_same_flux(scene_with({}, 2.0f, false), two_spheres(), "one-sided triangle");
}

TEST(EmissionFocus, TwoSidedTriangleSendsTheSameFluxIntoTheSpheres) {
    EmissionFocus focus = two_spheres();
    focus.spheres.push_back({Vec3(0.5f, 0.5f, -0.5f), 0.35f});  // behind the triangle
    expect_same_flux(scene_with({}, 2.0f, true), focus, "two-sided triangle");
}

TEST(EmissionFocus, TwoSidedTriangleBetweenLargeSpheresKeepsItsPhotonsLight) {
    // Large spheres on both sides of the triangle's middle: from there they fill more than the
    // emitter's two cosine lobes can weigh, and it emits as usual; from its far corner it aims.
    EmissionFocus focus;
    focus.spheres = {{Vec3(0.667f, 0.333f, 2.0f), 0.95f}, {Vec3(0.667f, 0.333f, 0.0f), 0.95f}};
    focus.center = Vec3(0.667f, 0.333f, 1.0f);
    focus.radius = 2.0f;
    expect_same_flux(scene_with({}, 2.0f, true), focus, "two-sided triangle between large spheres", false);
}

/// scene_with's triangle in bounds of radius about 8, where the spheres of two_spheres() are small.
Scene wide_scene_with(const std::vector<PunctualLight>& lights) {
    Scene scene = scene_with(lights, 0.0f, false);
    scene.bounds.extend(Vec3(-4.0f, -4.0f, -4.0f));
    scene.bounds.extend(Vec3(6.0f, 5.0f, 6.0f));
    return scene;
}

/// Parallel photons (a sun, the sky) start on the discs of the focus spheres across their
/// direction: the same flux into the spheres as from the scene's disc, and more of them meet a
/// sphere than from the disc of the spheres' bounding sphere.
void expect_parallel_photons_aimed_at_the_spheres(const Scene& scene, const char* what) {
    expect_same_flux(scene, two_spheres(), what);
    EmissionFocus bounding = two_spheres();
    bounding.spheres.clear();
    int from_bounding = 0, from_spheres = 0;
    const DVec3 flux_bounding = flux_into(scene, two_spheres(), true, &from_bounding, nullptr, &bounding);
    const DVec3 flux_spheres = flux_into(scene, two_spheres(), true, &from_spheres, nullptr);
    // The discs' areas 0.25 (pi dropped) against the bounding disc's 4: a sixteenth of the
    // bounding disc's photons pass through a sphere, nearly all of the spheres'.
    EXPECT_GT(from_spheres, 950000) << what;
    EXPECT_LT(from_bounding, 100000) << what;
    const double tolerance = 4.0 / std::sqrt(static_cast<double>(from_bounding));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(flux_spheres[c] / flux_bounding[c], 1.0, tolerance) << what;
}

TEST(EmissionFocus, ASunsPhotonsLeaveFromTheSpheresDiscs) {
    PunctualLight sun;
    sun.type = PunctualLightType::Directional;
    sun.direction = glm::normalize(Vec3(0.3f, 0.2f, -1.0f));
    sun.intensity = Color(4.0f, 3.0f, 2.0f);
    sun.angular_radius = 0.05f;
    expect_parallel_photons_aimed_at_the_spheres(wide_scene_with({sun}), "sun");
}

TEST(EmissionFocus, TheSkysPhotonsLeaveFromTheSpheresDiscs) {
    Scene scene = wide_scene_with({});
    Environment sky;
    sky.color = Color(1.0f, 2.0f, 4.0f);
    scene.environment = sky;
    expect_parallel_photons_aimed_at_the_spheres(scene, "sky");
}

TEST(EmissionFocus, OverlappingDiscsCountEachPointOnce) {
    // Two spheres, one inside the other's shadow for some directions: where discs overlap the
    // density adds up, and the flux into the spheres stays that of the scene's disc.
    Scene scene = wide_scene_with({});
    Environment sky;
    sky.color = Color(1.0f);
    scene.environment = sky;
    EmissionFocus focus;
    focus.spheres = {{Vec3(0.5f, 0.5f, 2.0f), 0.5f}, {Vec3(0.9f, 0.6f, 2.3f), 0.4f}};
    focus.center = Vec3(0.7f, 0.55f, 2.15f);
    focus.radius = 1.5f;
    expect_same_flux(scene, focus, "overlapping spheres under a sky");
}

TEST(EmissionFocus, SpheresWiderTogetherThanTheirBoundLeaveParallelPhotonsOnItsDisc) {
    // Two large spheres whose discs add up to more than their bounding sphere's: the sky's
    // photons start on the bounding disc, with the same flux into the spheres.
    Scene scene = wide_scene_with({});
    Environment sky;
    sky.color = Color(1.0f, 0.5f, 0.25f);
    scene.environment = sky;
    EmissionFocus focus;
    focus.spheres = {{Vec3(0.3f, 0.3f, 2.0f), 1.0f}, {Vec3(0.8f, 0.3f, 2.0f), 1.0f}};
    focus.center = Vec3(0.55f, 0.3f, 2.0f);
    focus.radius = 1.3f;
    expect_same_flux(scene, focus, "large spheres under a sky", false);
}

TEST(EmissionFocus, NothingToAimAtCarriesNoFlux) {
    // A one-sided triangle facing +z and one sphere wholly behind it.
    EmissionFocus focus;
    focus.spheres = {{Vec3(0.5f, 0.5f, -1.0f), 0.3f}};
    const Scene scene = scene_with({}, 2.0f, false);
    const LightSet lights(scene);
    Rng rng(3, 4);
    for (int i = 0; i < 1000; ++i) {
        const auto e = lights.sample_emission(rng.next_float(), rng.next_vec2(), rng.next_vec2(), &focus, rng.next_float());
        ASSERT_TRUE(e.has_value());
        EXPECT_TRUE(is_black(e->flux_weight));
    }
}

/// A scene of the given meshes (material 0), to cover their triangles.
Scene scene_of(const std::vector<MeshData>& meshes) {
    SceneBuilder builder("casters");
    const uint32_t material = builder.add_material(Material{});
    for (const MeshData& mesh : meshes) EXPECT_TRUE(add_mesh(builder, mesh, material).is_ok());
    return builder.build().value();
}

std::vector<uint32_t> all_triangles(const Scene& scene) {
    std::vector<uint32_t> triangles(scene.triangles.size());
    for (uint32_t t = 0; t < triangles.size(); ++t) triangles[t] = t;
    return triangles;
}

void expect_covered(const Scene& scene, const EmissionFocus& focus) {
    for (const Vec3& p : scene.positions) {
        EXPECT_LE(glm::length(p - focus.center), focus.radius);
        bool inside = false;
        for (const FocusSphere& s : focus.spheres) inside = inside || glm::length(p - s.center) <= s.radius;
        EXPECT_TRUE(inside) << p.x << " " << p.y << " " << p.z;
    }
}

TEST(EmissionFocus, OneRoundObjectStaysOneSphere) {
    const Scene scene = scene_of({make_icosphere(Vec3(1.0f, 2.0f, 3.0f), 0.5f, 3)});
    const EmissionFocus focus = focus_on_triangles(scene, all_triangles(scene));
    expect_covered(scene, focus);
    ASSERT_EQ(focus.spheres.size(), 1u);
    EXPECT_NEAR(focus.spheres[0].radius, 0.5f, 0.01f);
}

TEST(EmissionFocus, SeparateObjectsGetTheirOwnSpheres) {
    // Eight small spheres in a row, far apart: the cover holds each alone, not the row.
    std::vector<MeshData> meshes;
    for (int i = 0; i < 8; ++i) meshes.push_back(make_icosphere(Vec3(3.0f * i, 0.0f, 0.0f), 0.25f, 2));
    const Scene scene = scene_of(meshes);
    const EmissionFocus focus = focus_on_triangles(scene, all_triangles(scene));
    expect_covered(scene, focus);
    EXPECT_GT(focus.radius, 10.0f);
    ASSERT_EQ(focus.spheres.size(), 8u);
    for (const FocusSphere& s : focus.spheres) EXPECT_NEAR(s.radius, 0.25f, 0.01f);
}

TEST(EmissionFocus, ObjectsOfUnequalDetailAreNotCutInHalf) {
    // A finely tessellated sphere between two coarse ones, all three in a row: a split of the
    // row's triangles, by their median or at the middle of their extent, cuts the fine one in
    // two, each half wider than it. Split between objects, each gets a sphere of its own.
    const Scene scene = scene_of({make_icosphere(Vec3(0.0f, 0.0f, 0.0f), 0.25f, 1),
                                  make_icosphere(Vec3(1.0f, 0.0f, 0.0f), 0.25f, 4),
                                  make_icosphere(Vec3(2.0f, 0.0f, 0.0f), 0.25f, 1)});
    const EmissionFocus focus = focus_on_triangles(scene, all_triangles(scene));
    expect_covered(scene, focus);
    ASSERT_EQ(focus.spheres.size(), 3u);
    for (const FocusSphere& s : focus.spheres) EXPECT_NEAR(s.radius, 0.25f, 0.01f);
}

TEST(EmissionFocus, ASphereWithASeamIsOneObject) {
    // The triangles of one half of a sphere on vertices of their own at the same positions (a UV
    // seam): still one object, one sphere, not two halves each wider than the ball.
    MeshData ball = make_icosphere(Vec3(0.0f), 0.5f, 3);
    const size_t first_copy = ball.positions.size();
    for (size_t v = 0; v < first_copy; ++v) {
        ball.positions.push_back(ball.positions[v]);
        ball.normals.push_back(ball.normals[v]);
        ball.uvs.push_back(ball.uvs[v]);
    }
    for (size_t t = 0; t < ball.triangles.size(); ++t)
        if (t % 2 == 0) ball.triangles[t] += glm::uvec3(static_cast<uint32_t>(first_copy));
    const Scene scene = scene_of({ball});
    const EmissionFocus focus = focus_on_triangles(scene, all_triangles(scene));
    expect_covered(scene, focus);
    ASSERT_EQ(focus.spheres.size(), 1u);
    EXPECT_NEAR(focus.spheres[0].radius, 0.5f, 0.01f);
}

TEST(EmissionFocus, AnObjectInsideAnotherSharesItsSphere) {
    // A liquid inside its glass: two objects, but a sphere for the inner one would only add to
    // the cover's discs.
    const Scene scene = scene_of({make_icosphere(Vec3(0.0f), 0.5f, 3), make_icosphere(Vec3(0.05f, 0.0f, 0.0f), 0.3f, 3)});
    const EmissionFocus focus = focus_on_triangles(scene, all_triangles(scene));
    expect_covered(scene, focus);
    ASSERT_EQ(focus.spheres.size(), 1u);
    EXPECT_NEAR(focus.spheres[0].radius, 0.5f, 0.01f);
}

TEST(EmissionFocus, ALongObjectIsSplitAlongItsLength) {
    // A rod of twenty boxes end to end, one mesh.
    MeshData rod;
    for (int i = 0; i < 20; ++i) append_mesh(rod, make_box(Vec3(0.5f * i, 0.0f, 0.0f), Vec3(0.5f * (i + 1), 0.2f, 0.2f)));
    const Scene scene = scene_of({rod});
    const EmissionFocus focus = focus_on_triangles(scene, all_triangles(scene));
    expect_covered(scene, focus);
    EXPECT_GT(focus.spheres.size(), 1u);
    EXPECT_LE(focus.spheres.size(), kMaxFocusSpheres);
    for (const FocusSphere& s : focus.spheres) EXPECT_LT(s.radius, focus.radius);
}

}  // namespace
}  // namespace photond
