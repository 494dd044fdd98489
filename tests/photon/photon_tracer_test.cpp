// The photon pass: energy bookkeeping, determinism across thread counts, the radiance estimate
// against an analytic irradiance, and scenes where photons cannot land.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "core/photon/photon_tracer.h"
#include "core/render/render_plan.h"
#include "core/scene/builtin_scenes.h"
#include "core/scene/shapes.h"

#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;

/// A closed 4 x 4 x 4 room (faces inward) of albedo rho with a point light inside.
Scene closed_room(float rho, const Vec3& light_position, const Color& intensity) {
    SceneBuilder builder("room");
    const uint32_t m = builder.add_material(lambertian(Color(rho)));
    MeshData room = make_box(Vec3(-2.0f), Vec3(2.0f));
    flip_orientation(room);
    EXPECT_TRUE(add_mesh(builder, room, m).is_ok());
    PunctualLight light;
    light.position = light_position;
    light.intensity = intensity;
    builder.add_light(light);
    return builder.build().value();
}

DVec3 summed_flux(const PhotonMap& map, uint8_t required_flags) {
    DVec3 sum(0.0);
    for (uint32_t i = 0; i < map.size(); ++i) {
        const Photon& p = map.tree().photon(i);
        if ((p.user_flags() & required_flags) == required_flags) sum += DVec3(p.flux());
    }
    return sum;
}

TEST(PhotonTracer, FirstHitsCarryTheLightsTotalPower) {
    const Color intensity(2.0f, 1.0f, 0.5f);
    auto rs = make_render_scene(closed_room(0.5f, Vec3(0.3f, 1.0f, -0.2f), intensity));
    PhotonTracingSettings settings;
    settings.global_photons = 100000;
    settings.caustic_photons = 0;
    const auto maps = trace_photons(*rs, settings);
    ASSERT_TRUE(maps.has_value()) << maps.error().message;
    ASSERT_TRUE(maps->global);
    EXPECT_FALSE(maps->caustic);
    // In a closed room every emitted photon's first hit is stored: their flux sums to the power.
    const DVec3 direct = summed_flux(*maps->global, photon_flags::kDirect);
    const Color power = 4.0f * kPi * intensity;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(direct[c], power[c], 0.01 * power[c]);
    // All photons: the power times the mean number of diffuse bounces 1 / (1 - rho) = 2.
    const DVec3 all = summed_flux(*maps->global, 0);
    EXPECT_NEAR(all.x / power.x, 2.0, 0.03);
    EXPECT_GE(maps->global->size(), 100000u);
    EXPECT_EQ(maps->statistics.stored_global, maps->global->size());
}

TEST(PhotonTracer, PhotonsKeepTheNormalOfTheSideTheyLandedOn) {
    // In the closed room every photon lies on a wall and arrived from the inside: its normal is
    // the wall's inward one, and the precomputed irradiance sites carry it too, with the radius
    // of their estimate.
    auto rs = make_render_scene(closed_room(0.5f, Vec3(0.3f, 1.0f, -0.2f), Color(1.0f)));
    PhotonTracingSettings settings;
    settings.global_photons = 20000;
    settings.caustic_photons = 0;
    const auto maps = trace_photons(*rs, settings);
    ASSERT_TRUE(maps.has_value()) << maps.error().message;
    ASSERT_TRUE(maps->irradiance);
    const auto inward_normal = [](const Vec3& p) {
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (std::abs(p[a]) > std::abs(p[axis])) axis = a;
        Vec3 n(0.0f);
        n[axis] = p[axis] > 0.0f ? -1.0f : 1.0f;
        return n;
    };
    for (const PhotonMap* map : {maps->global.get(), maps->irradiance.get()}) {
        for (const Photon& photon : map->tree().photons()) {
            ASSERT_TRUE(photon.has_normal());
            const Vec3 n = inward_normal(photon.position);
            ASSERT_GT(glm::dot(photon.normal(), n), 0.99999f)
                << photon.position.x << " " << photon.position.y << " " << photon.position.z;
            if (map == maps->global.get()) {
                // Arrived from the inside, up to the direction's 0.8 degree (0.014) bins.
                ASSERT_GT(glm::dot(-photon.direction(), n), -0.015f);
            } else {
                // A site keeps its estimate's radius: the k-th photon's, or the cap's where fewer
                // were within it.
                const float cap = kIrradianceRadiusShare * rs->scene->bounds.radius();
                float radius = 0.0f;
                maps->global->estimate_irradiance(photon.position, photon.normal(), settings.k_irradiance, cap, 0, &radius);
                if (radius == 0.0f) radius = cap;
                ASSERT_NEAR(photon.site_radius(), radius, 1e-3f * radius);
            }
        }
    }
}

TEST(PhotonTracer, MapsAreBitIdenticalForAnyThreadCount) {
    auto rs = make_render_scene(make_builtin_scene("cornell-box").value());
    PhotonTracingSettings settings;
    settings.global_photons = 30000;
    settings.caustic_photons = 20000;
    settings.seed = 5;
    settings.threads = 1;
    const auto one = trace_photons(*rs, settings);
    settings.threads = 2;
    const auto two = trace_photons(*rs, settings);
    settings.threads = 5;
    const auto five = trace_photons(*rs, settings);
    ASSERT_TRUE(one && two && five);
    for (const auto* other : {&two, &five}) {
        // The precomputed irradiance too: its estimates pass radius hints on (photon_tracer.cpp).
        ASSERT_TRUE(one->irradiance && one->caustic_irradiance);
        for (const auto& [a, b] : {std::pair{(*one).global, (**other).global}, std::pair{(*one).caustic, (**other).caustic},
                                   std::pair{(*one).irradiance, (**other).irradiance},
                                   std::pair{(*one).caustic_irradiance, (**other).caustic_irradiance}}) {
            ASSERT_EQ(a->size(), b->size());
            ASSERT_EQ(a->emitted(), b->emitted());
            ASSERT_EQ(0, std::memcmp(&a->tree().photon(0), &b->tree().photon(0), a->size() * sizeof(Photon)));
        }
    }
    // Another seed gives other photons: the comparison can fail.
    settings.seed = 6;
    const auto other_seed = trace_photons(*rs, settings);
    EXPECT_NE(0, std::memcmp(&one->global->tree().photon(0), &other_seed->global->tree().photon(0),
                             std::min(one->global->size(), other_seed->global->size()) * sizeof(Photon)));
}

TEST(PhotonTracer, IrradianceEstimateOnAPlaneMatchesInverseSquareLaw) {
    SceneBuilder builder("plane");
    // Nothing else in the scene: reflected photons leave it, so every stored photon is a first hit.
    const uint32_t m = builder.add_material(lambertian(Color(0.5f)));
    const MeshData plane = make_quad(Vec3(-10, 0, 10), Vec3(20, 0, 0), Vec3(0, 0, -20));
    ASSERT_TRUE(add_mesh(builder, plane, m).is_ok());
    PunctualLight light;
    light.position = Vec3(0, 2, 0);
    light.intensity = Color(10.0f);
    builder.add_light(light);
    auto rs = make_render_scene(builder.build().value());
    ASSERT_GT(rs->scene->triangle_normal(0).y, 0.99f);
    PhotonTracingSettings settings;
    settings.global_photons = 1000000;
    settings.caustic_photons = 0;
    const auto maps = trace_photons(*rs, settings);
    ASSERT_TRUE(maps.has_value()) << maps.error().message;
    for (const float x : {0.0f, 0.7f, 1.5f, 2.5f}) {
        const Vec3 p(x, 0.0f, 0.3f);
        const Vec3 d = light.position - p;
        const float dist2 = glm::dot(d, d);
        const float expected = 10.0f * d.y / std::sqrt(dist2) / dist2;
        const Color e = maps->global->estimate_irradiance(p, Vec3(0, 1, 0), 1000, 0.0f);
        std::printf("x=%.1f estimate %.4f exact %.4f\n", x, e.x, expected);
        EXPECT_NEAR(e.x, expected, 0.05f * expected) << "x=" << x;
    }
}

TEST(PhotonTracer, LightsFacingAwayEndWithAMessageInsteadOfLooping) {
    SceneBuilder builder("away");
    const uint32_t m = builder.add_material(lambertian(Color(0.8f)));
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-1, 0, 1), Vec3(2, 0, 0), Vec3(0, 0, -2)), m).is_ok());
    PunctualLight spot;
    spot.type = PunctualLightType::Spot;
    spot.position = Vec3(0, 1, 0);
    spot.direction = Vec3(0, 1, 0);  // up, away from the floor
    spot.cos_inner = std::cos(0.2f);
    spot.cos_outer = std::cos(0.4f);
    builder.add_light(spot);
    auto rs = make_render_scene(builder.build().value());
    PhotonTracingSettings settings;
    settings.global_photons = 1000;
    settings.caustic_photons = 0;
    const auto maps = trace_photons(*rs, settings);
    ASSERT_FALSE(maps.has_value());
    EXPECT_NE(maps.error().message.find("no photon"), std::string::npos) << maps.error().message;
    EXPECT_NE(maps.error().message.find("global"), std::string::npos) << maps.error().message;
}

/// The closed room lit by a point light of intensity 1 at (0, 1, 0), over a square ideal mirror
/// of side `side` and reflectance `reflectance` (at normal incidence) facing it at y = -1: the
/// mirror's caustic carries the light's flux times the mirror's solid angle over 4 pi (times the
/// reflectance), onto the diffuse walls.
Scene room_with_a_mirror(float side, float reflectance = 1.0f) {
    Scene scene = closed_room(0.8f, Vec3(0.0f, 1.0f, 0.0f), Color(1.0f));
    SceneBuilder builder("mirror room");
    for (const Material& m : scene.materials) builder.add_material(m);
    Material mirror;
    mirror.metallic = 1.0f;
    mirror.roughness = 0.0f;
    mirror.base_color = Color(reflectance);
    const uint32_t mirror_material = builder.add_material(mirror);
    MeshData room = make_box(Vec3(-2.0f), Vec3(2.0f));
    flip_orientation(room);
    EXPECT_TRUE(add_mesh(builder, room, 0).is_ok());
    const float h = 0.5f * side;
    EXPECT_TRUE(
        add_mesh(builder,
                 make_quad(Vec3(-h, -1.0f, -h), Vec3(side, 0, 0), Vec3(0, 0, side), Vec3(0, 1, 0)),
                 mirror_material)
            .is_ok());
    builder.add_light(scene.lights.at(0));
    return builder.build().value();
}

TEST(PhotonTracer, CausticMapCarryingNegligibleLightStopsEarlyAndStaysUnbiased) {
    PhotonTracingSettings settings;
    settings.global_photons = 20000;
    settings.caustic_photons = 20000;
    // A 0.1 x 0.1 mirror 2 below the light: 1 photon in 5,000 reaches it, and its caustic is
    // about 4e-5 of what the walls receive in all: the map stops long before its cap (20 M).
    // (Photons for the caustic map alone are aimed at the mirror, so most of them reach it.)
    const auto small = trace_photons(*make_render_scene(room_with_a_mirror(0.1f)), settings);
    ASSERT_TRUE(small) << small.error().message;
    const PhotonTracingStatistics& s = small->statistics;
    EXPECT_FALSE(s.caustic_complete);
    EXPECT_GE(s.stored_caustic, kCausticShareMinPhotons);
    EXPECT_LT(s.emitted_caustic, 4'000'000u) << "stopped at the cap, not by the share";
    const double share = caustic_flux_share(*small);
    EXPECT_GT(share, 0.0);
    EXPECT_LT(share, kNegligibleCausticShare);
    // What was traced is kept, divided by the photons emitted for it: the caustic's flux is the
    // light's intensity times the mirror's solid angle (a rectangle a x b at distance d:
    // 4 asin(ab / sqrt((a^2 + 4 d^2)(b^2 + 4 d^2)))), within the noise of ~200 photons (there
    // are many more).
    const double solid_angle = 4.0 * std::asin(0.01 / std::sqrt((0.01 + 16.0) * (0.01 + 16.0)));
    const double caustic_flux = summed_flux(*small->caustic, 0).x;
    EXPECT_NEAR(caustic_flux / solid_angle, 1.0, 0.25) << s.stored_caustic << " photons";
    std::printf(
        "small mirror: %llu caustic photons of %llu emitted, share %.3g, flux / expected %.3f\n",
        static_cast<unsigned long long>(s.stored_caustic),
        static_cast<unsigned long long>(s.emitted_caustic), share, caustic_flux / solid_angle);

    // A mirror a hundred times larger casts a caustic worth tracing: the map fills.
    settings.caustic_photons = 5000;
    const auto large = trace_photons(*make_render_scene(room_with_a_mirror(1.0f)), settings);
    ASSERT_TRUE(large) << large.error().message;
    EXPECT_TRUE(large->statistics.caustic_complete);
    EXPECT_EQ(large->statistics.stored_caustic, 5000u);
    EXPECT_GT(caustic_flux_share(*large), kNegligibleCausticShare);
}

TEST(PhotonTracer, CausticMapWhoseLightWouldNotShowIsDropped) {
    PhotonTracingSettings settings;
    settings.global_photons = 20000;
    settings.caustic_photons = 20000;
    // The large mirror reflecting everything: on the ceiling its caustic (the light's image 5
    // away, 1 / 25 of the direct irradiance of the light 1 away, more towards the walls) is
    // several percent of the light there: kept, and its irradiance precomputed.
    const auto bright = trace_photons(*make_render_scene(room_with_a_mirror(1.0f)), settings);
    ASSERT_TRUE(bright) << bright.error().message;
    const PhotonTracingStatistics& b = bright->statistics;
    EXPECT_TRUE(b.caustic_tested);
    EXPECT_FALSE(b.caustic_dropped);
    EXPECT_GT(b.caustic_peak_ratio, kInvisibleCausticRatio);
    ASSERT_TRUE(bright->caustic);
    ASSERT_TRUE(bright->caustic_irradiance);
    EXPECT_EQ(bright->caustic_irradiance->size(), (bright->caustic->size() + 3) / 4);  // every 4th

    // A mirror twice as wide reflecting 1 % (Schlick's Fresnel: more at grazing angles): its
    // caustic is a few tenths of a percent of the light where it lands, though its share of all
    // light (above 1e-4) keeps the negligible-share rule from stopping it. Tested once the global
    // map is full, it is dropped: tracing for it stops there, and the global map is the one a
    // job without caustics gets.
    const auto dim = trace_photons(*make_render_scene(room_with_a_mirror(2.0f, 0.01f)), settings);
    ASSERT_TRUE(dim) << dim.error().message;
    const PhotonTracingStatistics& d = dim->statistics;
    std::printf("caustic peak ratio: bright mirror %.4f, dim mirror %.6f (%llu of %u photons when dropped)\n",
                b.caustic_peak_ratio, d.caustic_peak_ratio, static_cast<unsigned long long>(d.stored_caustic),
                settings.caustic_photons);
    EXPECT_TRUE(d.caustic_tested);
    EXPECT_TRUE(d.caustic_dropped);
    EXPECT_GT(d.caustic_peak_ratio, 0.0);
    EXPECT_LT(d.caustic_peak_ratio, kInvisibleCausticRatio);
    EXPECT_FALSE(dim->caustic);
    EXPECT_FALSE(dim->caustic_irradiance);
    EXPECT_LT(d.stored_caustic, settings.caustic_photons);
    // The first batch (16,384 photons, photon_tracer.cpp) filled the global map along whole
    // paths; the caustic map then started again with photons aimed at the mirror alone, and
    // tracing stopped when it was dropped.
    EXPECT_EQ(d.emitted, 16384u + d.emitted_caustic);

    settings.caustic_photons = 0;
    const auto none = trace_photons(*make_render_scene(room_with_a_mirror(2.0f, 0.01f)), settings);
    ASSERT_TRUE(none) << none.error().message;
    ASSERT_EQ(none->global->size(), dim->global->size());
    EXPECT_EQ(std::memcmp(none->global->tree().photons().data(), dim->global->tree().photons().data(),
                          none->global->size() * sizeof(Photon)),
              0);
}

TEST(PhotonTracer, SceneWithoutLightsIsRefused) {
    SceneBuilder builder("dark");
    const uint32_t m = builder.add_material(lambertian(Color(0.8f)));
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-1, 0, 1), Vec3(2, 0, 0), Vec3(0, 0, -2)), m).is_ok());
    auto rs = make_render_scene(builder.build().value());
    const auto maps = trace_photons(*rs, PhotonTracingSettings{});
    ASSERT_FALSE(maps.has_value());
    EXPECT_NE(maps.error().message.find("no light"), std::string::npos) << maps.error().message;
}

TEST(RenderPlan, SkipsTheCausticMapWithoutSpecularSurfaces) {
    auto diffuse = make_render_scene(make_builtin_scene("cornell-box-diffuse").value());
    const RenderPlan plan = plan_photon_passes(*diffuse->scene, *diffuse->lights, {200000, 100000});
    EXPECT_FALSE(plan.caustic_map);
    EXPECT_TRUE(plan.global_map);
    ASSERT_NE(plan.find("caustic_map"), nullptr);
    EXPECT_NE(plan.find("caustic_map")->reason.find("specular"), std::string::npos);

    auto jensen = make_render_scene(make_builtin_scene("cornell-box").value());
    const RenderPlan full = plan_photon_passes(*jensen->scene, *jensen->lights, {200000, 100000});
    EXPECT_TRUE(full.caustic_map);
    EXPECT_TRUE(full.global_map);
}

TEST(RenderPlan, SkipsTheGlobalMapWhenNothingReflectsDiffusely) {
    // A glossy metal floor and a glass sphere: caustics are possible, indirect diffuse light is not.
    SceneBuilder builder("glossy");
    Material metal;
    metal.metallic = 1.0f;
    metal.roughness = 0.3f;
    const uint32_t black = builder.add_material(metal);
    Material glass;
    glass.transmission = 1.0f;
    glass.roughness = 0.0f;
    const uint32_t g = builder.add_material(glass);
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-5, 0, 5), Vec3(10, 0, 0), Vec3(0, 0, -10)), black).is_ok());
    ASSERT_TRUE(add_mesh(builder, make_icosphere(Vec3(0, 1, 0), 1.0f, 2), g).is_ok());
    PunctualLight light;
    light.position = Vec3(0, 4, 0);
    builder.add_light(light);
    auto rs = make_render_scene(builder.build().value());
    const RenderPlan plan = plan_photon_passes(*rs->scene, *rs->lights, {1000, 1000});
    EXPECT_TRUE(plan.caustic_map);
    EXPECT_FALSE(plan.global_map);
    EXPECT_NE(plan.find("global_map")->reason.find("diffuse"), std::string::npos);
}

}  // namespace
}  // namespace photond
