// Shading with the rest of the glTF material against closed forms: a constant tilted normal map
// under a directional light gives rho / pi * E * cos(angle to the tilted normal); mirrored-UV
// halves of a normal-mapped quad shade alike; mip-mapping from the camera's ray cone removes the
// aliasing of a distant checkerboard.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/camera/camera.h"
#include "core/integrators/direct.h"
#include "core/integrators/photon_mapping.h"
#include "core/math/rng.h"
#include "core/render/tile_renderer.h"
#include "core/scene/gltf_loader.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;

PunctualLight sun(const Vec3& travel, float irradiance) {
    PunctualLight l;
    l.type = PunctualLightType::Directional;
    l.direction = glm::normalize(travel);
    l.intensity = Color(irradiance);
    return l;
}

Color radiance_straight_down(const std::shared_ptr<const RenderScene>& rs, const Vec3& from) {
    DirectIntegrator direct(rs);
    Rng rng(1, 1);
    RayCounters counters;
    SampleContext context{rng, counters};
    CameraRay ray;
    ray.origin = from;
    ray.direction = Vec3(0, 0, -1);
    return direct.radiance(ray, context);
}

/// A Lambertian quad z = 0 (albedo 0.5) whose normal texture tilts every normal by `tilt`
/// towards the tangent +x (none when normal_mapped is false), lit by `light`.
/// With `wall`, a white wall x = 1 (facing -x) stands on the quad, so that light reaches the quad
/// indirectly too, and the quad's albedo is 0.05 (little of what it reflects comes back).
std::shared_ptr<const RenderScene> tilted_quad(bool normal_mapped, float tilt,
                                               const PunctualLight& light, bool wall = false) {
    SceneBuilder builder("normal-map");
    Material m = lambertian(Color(wall ? 0.05f : 0.5f));
    if (normal_mapped) {
        Texture t;
        t.width = t.height = 1;
        const Vec3 n(std::sin(tilt), 0.0f, std::cos(tilt));
        t.texels = {0.5f * (n + Vec3(1.0f))};
        m.normal_texture.texture = static_cast<int>(builder.add_texture(std::move(t)));
    }
    const uint32_t material = builder.add_material(m);
    const MeshData q = make_quad(Vec3(-1, -1, 0), Vec3(2, 0, 0), Vec3(0, 2, 0));
    const std::vector<Vec4> tangents(q.positions.size(), Vec4(1, 0, 0, 1));
    SceneBuilder::MeshExtras extras;
    extras.tangents = tangents;
    EXPECT_TRUE(
        builder.add_mesh(q.positions, q.normals, q.uvs, q.triangles, material, Mat4(1.0f), extras)
            .is_ok());
    if (wall) {
        const uint32_t white = builder.add_material(lambertian(Color(0.9f)));
        const MeshData w = make_quad(Vec3(1, -1, 0), Vec3(0, 2, 0), Vec3(0, 0, 2), Vec3(-1, 0, 0));
        EXPECT_TRUE(builder.add_mesh(w.positions, w.normals, w.uvs, w.triangles, white).is_ok());
    }
    builder.add_light(light);
    return make_render_scene(builder.build().value());
}

TEST(NormalMap, ConstantTiltGivesTheCosineOfTheTiltedAngle) {
    const float tilt = 30.0f * kPi / 180.0f, e = 2.0f, rho_over_pi = 0.5f * kInvPi;
    // Light from straight above: the tilted normal sees it at 30 degrees.
    const PunctualLight overhead = sun(Vec3(0, 0, -1), e);
    EXPECT_NEAR(radiance_straight_down(tilted_quad(false, tilt, overhead), Vec3(0, 0, 2)).x,
                rho_over_pi * e, 1e-4f);
    EXPECT_NEAR(radiance_straight_down(tilted_quad(true, tilt, overhead), Vec3(0, 0, 2)).x,
                rho_over_pi * e * std::cos(tilt), 1e-4f);
    // Light along the tilted normal: full irradiance on the mapped quad, cos 30 on the flat one.
    const PunctualLight along = sun(-Vec3(std::sin(tilt), 0.0f, std::cos(tilt)), e);
    EXPECT_NEAR(radiance_straight_down(tilted_quad(true, tilt, along), Vec3(0, 0, 2)).x,
                rho_over_pi * e, 1e-4f);
    EXPECT_NEAR(radiance_straight_down(tilted_quad(false, tilt, along), Vec3(0, 0, 2)).x,
                rho_over_pi * e * std::cos(tilt), 1e-4f);
}

TEST(NormalMap, PhotonEstimatesLieOnTheSurfaceAndWeightPhotonsByTheBentNormal) {
    // The photon map's share of the radiance (photon-map without final gathering minus direct
    // light) on a flat and on a normal-mapped quad. Photons lie on the surface, so the
    // estimate's disc must lie there too, not tilt with the normal map (a tilted disc finds a
    // third of them); and each photon counts cos(bent normal, wi) / cos(surface normal, wi),
    // which turns their density on the flat surface into the bent facet's irradiance. The
    // indirect light comes from the sunlit wall x = 1, of uniform radiance but for the little
    // the dark quad sends back: the two shares must be in the ratio of the wall's view from
    // the point, integrated with either cosine.
    const float tilt = 30.0f * kPi / 180.0f;
    const PunctualLight overhead = sun(Vec3(0.5f, 0, -1), 2.0f);
    const Vec3 point(0.1f, 0.2f, 0.0f);
    const auto photon_share = [&](bool normal_mapped) {
        auto rs = tilted_quad(normal_mapped, tilt, overhead, true);
        PhotonTracingSettings tracing;
        tracing.global_photons = 400000;
        tracing.caustic_photons = 0;
        tracing.irradiance_stride = 0;
        auto maps = std::make_shared<const PhotonMaps>(trace_photons(*rs, tracing).value());
        PhotonMapIntegratorSettings settings;
        settings.final_gather = false;
        settings.use_irradiance_cache = false;
        settings.k_global = 400;
        PhotonMapIntegrator photon_map(rs, maps, settings);
        Rng rng(1, 1);
        RayCounters counters;
        SampleContext context{rng, counters};
        CameraRay ray;
        ray.origin = point + Vec3(0.0f, 0.0f, 2.0f);
        ray.direction = Vec3(0, 0, -1);
        return photon_map.radiance(ray, context).x - radiance_straight_down(rs, ray.origin).x;
    };
    // The wall x = 1, y in [-1, 1], z in [0, 2], facing -x, seen from the point: sum of
    // cos_wall cos_n / r^2 over its area for the surface normal +z and the bent one.
    const Vec3 bent(std::sin(tilt), 0.0f, std::cos(tilt));
    double flat_view = 0.0, bent_view = 0.0;
    constexpr int kCells = 400;
    for (int i = 0; i < kCells; ++i) {
        for (int j = 0; j < kCells; ++j) {
            const Vec3 q(1.0f, -1.0f + 2.0f * (i + 0.5f) / kCells, 2.0f * (j + 0.5f) / kCells);
            const Vec3 d = q - point;
            const double r2 = glm::dot(d, d);
            const Vec3 w = d / std::sqrt(static_cast<float>(r2));
            flat_view += w.x * w.z / r2;
            bent_view += w.x * std::max(glm::dot(bent, w), 0.0f) / r2;
        }
    }
    const double expected_ratio = bent_view / flat_view;
    const float flat = photon_share(false), mapped = photon_share(true);
    std::printf("photon share of the radiance: flat %.5f, normal-mapped %.5f (ratio %.3f, the wall's view %.3f)\n",
                flat, mapped, mapped / flat, expected_ratio);
    ASSERT_GT(flat, 0.001f);
    EXPECT_NEAR(mapped / flat, expected_ratio, 0.03 * expected_ratio);
}

TEST(NormalMap, MirroredUvHalvesShadeLikeTheUnmirroredHalf) {
    // tests/data/gltf/alpha_normal.gltf: at z = 5, x in [0, 1] with u = x and x in [1, 2] with
    // u = 2 - x, one normal texel tilted up the image (+y); tangents generated by the loader.
    Expected<Scene> loaded =
        load_gltf_file(std::filesystem::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "alpha_normal.gltf");
    ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
    Scene scene = std::move(loaded).value();
    // Light from +y and +x above: a wrongly handed tangent frame on the mirrored half would turn
    // its normal towards -y and shade it differently.
    scene.lights.push_back(sun(Vec3(-0.3f, -0.5f, -1.0f), 1.0f));
    auto rs = make_render_scene(std::move(scene));
    const Color left = radiance_straight_down(rs, Vec3(0.5f, 0.5f, 8.0f));
    const Color right = radiance_straight_down(rs, Vec3(1.5f, 0.5f, 8.0f));
    // The same up to the tangent-direction (x) part of the tilt, which is mirrored: texel R 128
    // tilts by 0.002 only, and the light's x component is small.
    ASSERT_GT(left.x, 0.0f);
    EXPECT_NEAR(right.x / left.x, 1.0f, 0.01f);
}

TEST(MipMaps, ReduceTheErrorOfADistantCheckerboard) {
    // A 200 x 200 floor with an 8 x 8 checkerboard repeated 100 times, seen at a slant from a
    // height of 1: far pixels cover many checks. Reference: 16 x 16 samples per pixel.
    auto scene_with = [](bool mipmapped) {
        SceneBuilder builder("checkerboard");
        Texture t;
        t.width = t.height = 8;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) t.texels.push_back(Color(float((x + y) % 2)));
        Material m = lambertian(Color(1.0f));
        m.base_color_texture.texture = static_cast<int>(builder.add_texture(std::move(t)));
        m.base_color_texture.transformed = true;  // uv * 100
        m.base_color_texture.m0 = Vec2(100.0f, 0.0f);
        m.base_color_texture.m1 = Vec2(0.0f, 100.0f);
        const uint32_t material = builder.add_material(m);
        const MeshData q = make_quad(Vec3(-100, -100, 0), Vec3(200, 0, 0), Vec3(0, 200, 0));
        EXPECT_TRUE(builder.add_mesh(q.positions, q.normals, q.uvs, q.triangles, material).is_ok());
        builder.add_light(sun(Vec3(0, 0, -1), kPi));
        Scene s = builder.build().value();
        if (!mipmapped) {
            Texture level_zero_only = *s.textures[0];
            level_zero_only.mip_levels.clear();
            s.textures[0] = std::make_shared<const Texture>(std::move(level_zero_only));
        }
        return make_render_scene(std::move(s));
    };
    const auto mip = scene_with(true), flat = scene_with(false);
    CameraDesc desc;
    desc.position = Vec3(0, -10, 1);
    desc.look_at = Vec3(0, 10, 0);
    desc.vfov_deg = 30.0f;
    const int size = 48;
    const Camera camera = Camera::create(desc, size, size).value();
    DirectIntegrator with_mips(mip), without_mips(flat);
    Rng rng(1, 1);
    RayCounters counters;
    SampleContext context{rng, counters};
    double error_mip = 0.0, error_flat = 0.0;
    for (int y = 0; y < size / 2; ++y) {  // the upper half: the distant floor (and the sky)
        for (int x = 0; x < size; ++x) {
            double reference = 0.0;
            for (int s = 0; s < 256; ++s) {
                const CameraRay r =
                    camera.generate_ray(x + (s % 16 + 0.5f) / 16.0f, y + (s / 16 + 0.5f) / 16.0f);
                reference += without_mips.radiance(r, context).x;
            }
            reference /= 256.0;
            const CameraRay centre = camera.generate_ray(x + 0.5f, y + 0.5f);
            error_mip += sqr(float(with_mips.radiance(centre, context).x - reference));
            error_flat += sqr(float(without_mips.radiance(centre, context).x - reference));
        }
    }
    std::printf(
        "distant checkerboard, 1 spp against 256: squared error %.3f with mip-maps, %.3f without\n",
        error_mip, error_flat);
    EXPECT_LT(error_mip, 0.25 * error_flat) << error_mip << " vs " << error_flat;
}

TEST(MipMaps, ManySamplesPerPixelKeepTexturesSharp) {
    // Stripes one pixel wide, each 4 texels of a 64 x 64 emissive texture, seen straight on by a
    // distant camera (a narrow perspective one: its ray cones pick the level): the box-filtered
    // truth is 1 and 0 in alternate columns. A pixel's 64
    // samples average it themselves; were each to filter a whole pixel's footprint too (mip level
    // 2, the stripes' own size, bilinear), the columns would blur to 0.75 and 0.25.
    SceneBuilder builder("stripes");
    Texture t;
    t.width = 64;
    t.height = 64;
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) t.texels.push_back(Color(float((x / 4) % 2)));
    t.wrap_s = t.wrap_t = TextureWrap::ClampToEdge;
    Material m = lambertian(Color(0.0f));
    m.emission = Color(1.0f);
    m.emissive_texture.texture = static_cast<int>(builder.add_texture(std::move(t)));
    const uint32_t material = builder.add_material(m);
    const MeshData q = make_quad(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0));
    ASSERT_TRUE(builder.add_mesh(q.positions, q.normals, q.uvs, q.triangles, material).is_ok());
    const auto rs = make_render_scene(builder.build().value());
    CameraDesc desc;
    desc.position = Vec3(0.5f, 0.5f, 50.0f);
    desc.look_at = Vec3(0.5f, 0.5f, 0.0f);
    desc.vfov_deg = static_cast<float>(2.0 * std::atan(0.5 / 50.0) * 180.0 / 3.14159265358979323846);
    const int size = 16;
    const Camera camera = Camera::create(desc, size, size).value();
    const DirectIntegrator integrator(rs);
    TileSettings settings;
    settings.samples_per_pixel = 64;
    settings.tile_size = size;
    const TileRenderResult result = render_tiles(integrator, camera, settings);
    float worst = 0.0f;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            worst = std::max(worst, std::abs(result.layers.beauty.at(x, y).x - float(x % 2)));
    std::printf("one-pixel stripes at 64 spp: largest error against the box filter %.3f\n", worst);
    EXPECT_LT(worst, 0.1f);
}

}  // namespace
}  // namespace photond
