// Final gathering: irradiance against a brute-force hemisphere estimate, the rotation and
// translation gradients against finite differences of brute-force gathers, and gather rays'
// cones filtering the textures they meet.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/integrators/final_gather.h"
#include "core/scene/builtin_scenes.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

struct Fixture {
    std::shared_ptr<const RenderScene> scene;
    std::shared_ptr<const PhotonMaps> maps;
};

/// The scene ready to render, with a global map of `global_photons` (no caustic map).
Fixture with_global_map(Scene scene, uint32_t global_photons) {
    Fixture f;
    f.scene = test_support::make_render_scene(std::move(scene));
    PhotonTracingSettings settings;
    settings.global_photons = global_photons;
    settings.caustic_photons = 0;
    f.maps = std::make_shared<const PhotonMaps>(trace_photons(*f.scene, settings).value());
    return f;
}

const Fixture& cornell() {
    static const Fixture f = with_global_map(make_builtin_scene("cornell-box-diffuse").value(), 400000);
    return f;
}

GatherResult gather_at(const FinalGatherer& g, const Vec3& p, const Vec3& n, uint64_t seed, bool gradients) {
    Rng rng = Rng::for_stream(seed, 1);
    RayCounters counters;
    return g.gather(p, n, n, rng, counters, gradients);
}

TEST(FinalGather, GridFollowsWardsRatio) {
    const GatherGrid g = GatherGrid::for_rays(512);
    EXPECT_EQ(g.m, 13);
    EXPECT_EQ(g.n, 39);
    EXPECT_NEAR(static_cast<double>(g.n) / g.m, 3.14159, 0.2);
}

TEST(FinalGather, StratifiedEstimateAgreesWithIndependentSampling) {
    const Fixture& f = cornell();
    GatherSettings settings;
    settings.rays = 4096;
    const FinalGatherer gatherer(f.scene, f.maps, settings);
    // A point on the floor, normal up, in the open: (2.0, 0, 2.5) lay under the short block
    // (its footprint reaches z = 2.60 at x = 2.0), in the dark inside of a closed box.
    const Vec3 p(2.0f, 0.0f, 3.5f), n(0.0f, 1.0f, 0.0f);
    GatherResult stratified = gather_at(gatherer, p, n, 3, false);
    for (uint64_t seed = 4; seed < 7; ++seed) stratified.irradiance += gather_at(gatherer, p, n, seed, false).irradiance;
    stratified.irradiance /= 4.0f;
    // Brute force: independent cosine-weighted directions, E = pi * mean(L).
    Rng rng(11, 12);
    RayCounters counters;
    DVec3 sum(0.0);
    const int samples = 1 << 18;
    const Frame frame(n);
    for (int i = 0; i < samples; ++i) {
        const Vec3 d = frame.to_world(sample_cosine_hemisphere(rng.next_vec2()));
        float distance = 0.0f;
        sum += DVec3(gatherer.gather_ray_radiance(Ray{p + 1e-4f * n, d}, rng, counters, &distance));
    }
    const Color brute = Color(sum * (3.14159265358979 / samples));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(stratified.irradiance[c], brute[c], 0.02f * brute[c]) << c;
    EXPECT_GT(brute.x, 0.0f);
    const GatherGrid grid = GatherGrid::for_rays(4096);
    EXPECT_EQ(stratified.rays, static_cast<uint32_t>(grid.m * grid.n));
    EXPECT_GT(stratified.harmonic_mean_distance, 0.1f);
    EXPECT_LT(stratified.harmonic_mean_distance, 6.0f);
}

/// Central finite difference of brute-force gathers with common random numbers.
Color finite_difference(const FinalGatherer& g, const Vec3& p0, const Vec3& n0, const Vec3& p1, const Vec3& n1,
                        float step) {
    Color sum(0.0f);
    for (uint64_t seed = 0; seed < 4; ++seed) {
        sum += gather_at(g, p1, n1, 100 + seed, false).irradiance - gather_at(g, p0, n0, 100 + seed, false).irradiance;
    }
    return sum / (4.0f * step);
}

TEST(FinalGather, TranslationGradientMatchesFiniteDifferences) {
    const Fixture& f = cornell();
    GatherSettings settings;
    settings.rays = 16384;
    const FinalGatherer gatherer(f.scene, f.maps, settings);
    // On the floor near the red wall (x = 5.56 in the scaled data): irradiance changes fast in x.
    const Vec3 p(4.6f, 0.0f, 1.2f), n(0.0f, 1.0f, 0.0f);
    std::array<Vec3, 3> gradient{};
    for (uint64_t seed = 0; seed < 4; ++seed) {
        const GatherResult r = gather_at(gatherer, p, n, 200 + seed, true);
        for (int c = 0; c < 3; ++c) gradient[c] += r.translation_gradient[c] / 4.0f;
    }
    const float h = 0.15f;
    for (const Vec3 axis : {Vec3(1, 0, 0), Vec3(0, 0, 1)}) {
        const Color fd = finite_difference(gatherer, p - h * axis, n, p + h * axis, n, 2.0f * h);
        const float along_red = glm::dot(gradient[0], axis);
        std::printf("translation along (%g, %g, %g): gradient %.4f, finite difference %.4f\n", axis.x, axis.y,
                    axis.z, along_red, fd.x);
        EXPECT_NEAR(along_red, fd.x, 0.25f * std::abs(fd.x) + 0.02f);
    }
    // The red wall is at +x: moving towards it raises the red irradiance there.
    EXPECT_GT(glm::dot(gradient[0], Vec3(1, 0, 0)), 0.0f);
}

TEST(FinalGather, RotationGradientMatchesFiniteDifferences) {
    const Fixture& f = cornell();
    GatherSettings settings;
    settings.rays = 16384;
    const FinalGatherer gatherer(f.scene, f.maps, settings);
    const Vec3 p(4.6f, 0.0f, 1.2f), n(0.0f, 1.0f, 0.0f);
    std::array<Vec3, 3> gradient{};
    for (uint64_t seed = 0; seed < 4; ++seed) {
        const GatherResult r = gather_at(gatherer, p, n, 300 + seed, true);
        for (int c = 0; c < 3; ++c) gradient[c] += r.rotation_gradient[c] / 4.0f;
    }
    const float angle = 0.1f;
    for (const Vec3 axis : {Vec3(0, 0, 1), Vec3(1, 0, 0)}) {
        // Rotating n by +-angle about `axis`: n x n' = angle * axis to first order.
        const Vec3 tangent = glm::cross(axis, n);
        const Vec3 plus = glm::normalize(n * std::cos(angle) + tangent * std::sin(angle));
        const Vec3 minus = glm::normalize(n * std::cos(angle) - tangent * std::sin(angle));
        const Color fd = finite_difference(gatherer, p, minus, p, plus, 2.0f * angle);
        const float predicted = glm::dot(axis, gradient[0]);
        std::printf("rotation about (%g, %g, %g): gradient %.4f, finite difference %.4f\n", axis.x, axis.y, axis.z,
                    predicted, fd.x);
        EXPECT_NEAR(predicted, fd.x, 0.25f * std::abs(fd.x) + 0.02f);
    }
}

/// A 4 x 4 floor at z = 0 of a checkerboard albedo (0 and 1) in checks of 1/32, under a sun
/// straight down of irradiance pi (radiance = albedo), with its photon maps.
const Fixture& checkered_floor() {
    static Fixture f = [] {
        SceneBuilder builder("checkered floor");
        // Checks of 4 x 4 texels: bilinear lookups blend neighbouring checks only near their edges.
        Texture t;
        t.width = t.height = 32;
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) t.texels.push_back(Color(float((x / 4 + y / 4) % 2)));
        Material m = test_support::lambertian(Color(1.0f));
        m.base_color_texture.texture = static_cast<int>(builder.add_texture(std::move(t)));
        m.base_color_texture.transformed = true;  // uv * 16: 128 checks across
        m.base_color_texture.m0 = Vec2(16.0f, 0.0f);
        m.base_color_texture.m1 = Vec2(0.0f, 16.0f);
        const uint32_t material = builder.add_material(m);
        const MeshData q = make_quad(Vec3(-2, -2, 0), Vec3(4, 0, 0), Vec3(0, 4, 0));
        EXPECT_TRUE(builder.add_mesh(q.positions, q.normals, q.uvs, q.triangles, material).is_ok());
        PunctualLight sun;
        sun.type = PunctualLightType::Directional;
        sun.direction = Vec3(0, 0, -1);
        sun.intensity = Color(kPi);
        builder.add_light(sun);
        return with_global_map(builder.build().value(), 200000);
    }();
    return f;
}

/// Mean and relative standard deviation of the first channel.
struct Spread {
    double mean = 0.0;
    double relative_deviation = 0.0;
};
Spread spread_of(const std::vector<double>& values) {
    double sum = 0.0, sum2 = 0.0;
    for (double v : values) {
        sum += v;
        sum2 += v * v;
    }
    const double n = static_cast<double>(values.size());
    const double mean = sum / n;
    return {mean, std::sqrt(std::max(sum2 / n - mean * mean, 0.0)) / mean};
}

TEST(FinalGather, PhotonsAreStoredOnTheBlackChecksToo) {
    // A photon that lands on a black check is absorbed, but stored first: the estimates at the
    // white checks beside it, whose discs span several checks, count the photons of all of them
    // against the disc's area. Stored on the white checks alone, the floor read 0.69 of its
    // irradiance.
    const Fixture& f = checkered_floor();
    size_t parity[2] = {0, 0};
    for (const Photon& photon : f.maps->global->tree().photons()) {
        const int i = static_cast<int>(std::floor((photon.position.x + 2.0f) * 32.0f));
        const int j = static_cast<int>(std::floor((photon.position.y + 2.0f) * 32.0f));
        ++parity[(i + j) & 1];
    }
    const double share = static_cast<double>(parity[0]) / static_cast<double>(parity[0] + parity[1]);
    std::printf("photons on the checks of either colour: %zu and %zu\n", parity[0], parity[1]);
    EXPECT_NEAR(share, 0.5, 0.02);
}

TEST(FinalGather, GatherRayConesFilterTheTexturesTheyMeet) {
    const Fixture& f = checkered_floor();
    const FinalGatherer gatherer(f.scene, f.maps, GatherSettings{});
    // Rays from 1 above the floor to points of its middle: at level 0 each sees a check's albedo,
    // 0 or 1 (bilinear between them at their edges); a cone of spread 0.1 is some three checks
    // wide there and reads their mean, 1/2, whatever check it lands in. The photons' estimates
    // vary from point to point as well (about 1/sqrt(k)), alike for both.
    const Vec3 p(0.0f, 0.0f, 1.0f);
    std::vector<double> sharp, filtered;
    Rng points(5, 6);
    for (int i = 0; i < 2000; ++i) {
        const Vec2 u = points.next_vec2();
        const Vec3 target(2.0f * u.x - 1.0f, 2.0f * u.y - 1.0f, 0.0f);
        const Ray ray{p, glm::normalize(target - p)};
        float distance = 0.0f;
        Rng rng(7, static_cast<uint64_t>(i));
        RayCounters counters;
        sharp.push_back(gatherer.gather_ray_radiance(ray, rng, counters, &distance).x);
        filtered.push_back(gatherer.gather_ray_radiance(ray, rng, counters, &distance, nullptr, RayFootprint{0.0f, 0.1f, 1.0f}).x);
    }
    const Spread at_level_zero = spread_of(sharp), over_cones = spread_of(filtered);
    std::printf("gather rays onto the checks: mean %.4f, relative deviation %.3f at level 0; mean %.4f, %.3f over cones\n",
                at_level_zero.mean, at_level_zero.relative_deviation, over_cones.mean, over_cones.relative_deviation);
    EXPECT_GT(at_level_zero.relative_deviation, 0.6);
    EXPECT_LT(over_cones.relative_deviation, 0.3);
    // Filtering moves no light: the checks' mean either way, and their mean albedo times E / pi
    // = 1/2 (PhotonsAreStoredOnTheBlackChecksToo: else 0.35).
    EXPECT_NEAR(over_cones.mean, at_level_zero.mean, 0.08 * at_level_zero.mean);
    EXPECT_NEAR(at_level_zero.mean, 0.5, 0.04);

    // A gather's rays each stand for their cell: the irradiance the floor sends up to a point
    // above it varies from gather to gather by the photons' noise alone, not by which checks its
    // 256 rays happened to land on (3.7 % at level 0).
    std::vector<double> gathers;
    for (uint64_t seed = 0; seed < 12; ++seed)
        gathers.push_back(gather_at(gatherer, p, Vec3(0.0f, 0.0f, -1.0f), 200 + seed, false).irradiance.x);
    const Spread of_gathers = spread_of(gathers);
    std::printf("gathers: mean irradiance %.4f, relative deviation %.4f\n", of_gathers.mean, of_gathers.relative_deviation);
    EXPECT_LT(of_gathers.relative_deviation, 0.02);
    // And its mean is what the rays' radiance makes of the floor's view factor from p: for a
    // square of half-side x = 2 at height 1, (2 / pi) (2 x / sqrt(1 + x^2)) atan(x / sqrt(1 + x^2)).
    const double x = 2.0, view_factor = 4.0 / std::numbers::pi * x / std::sqrt(1.0 + x * x) * std::atan(x / std::sqrt(1.0 + x * x));
    EXPECT_NEAR(of_gathers.mean, over_cones.mean * std::numbers::pi * view_factor, 0.03 * of_gathers.mean);
}

TEST(FinalGather, AGlossyRaysConeGoesOnFromThePathsWidthOverItsSamplesSolidAngle) {
    // A camera path's cone 0.01 wide at its origin, spreading 0.002 a unit, at distance 5 (width
    // 0.02), with textures filtered over a quarter of it (16 samples a pixel): a lobe sample of
    // pdf 4 among 2 rays stands for a solid angle of 1/8.
    const RayFootprint path{0.01f, 0.002f, 0.25f};
    BsdfSample sample;
    sample.kind = LobeKind::Glossy;
    sample.pdf = 4.0f;
    const RayFootprint cone = glossy_ray_cone(path, 5.0f, sample, 2.0f);
    EXPECT_FLOAT_EQ(cone.width, 0.02f);
    EXPECT_FLOAT_EQ(cone.spread, std::sqrt(0.125f));
    EXPECT_FLOAT_EQ(cone.texture_scale, 0.25f);
    EXPECT_FLOAT_EQ(cone.texture_at(2.0f), 0.25f * (0.02f + 2.0f * std::sqrt(0.125f)));
    // An ideal specular sample's pdf is its lobe's choice: its cone goes on unspread.
    sample.kind = LobeKind::Delta;
    EXPECT_FLOAT_EQ(glossy_ray_cone(path, 5.0f, sample, 2.0f).spread, 0.0f);
}

TEST(FinalGather, WideConesFilterAlbedoAtOneLevelButNotEmissionAndStayWithinTheTriangle) {
    // A 4 x 4 quad whose base colour and emission are the same checks (4 x 4 texels each, 128
    // across), seen through a cone 0.5 wide at the hit: far coarser than the checks.
    SceneBuilder builder("checks that glow");
    Texture t;
    t.width = t.height = 32;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) t.texels.push_back(Color(float((x / 4 + y / 4) % 2)));
    const int texture = static_cast<int>(builder.add_texture(std::move(t)));
    Material m = test_support::lambertian(Color(1.0f));
    m.emission = Color(1.0f);
    for (TextureRef* ref : {&m.base_color_texture, &m.emissive_texture}) {
        ref->texture = texture;
        ref->transformed = true;
        ref->m0 = Vec2(16.0f, 0.0f);
        ref->m1 = Vec2(0.0f, 16.0f);
    }
    const uint32_t material = builder.add_material(m);
    const MeshData q = make_quad(Vec3(-2, -2, 0), Vec3(4, 0, 0), Vec3(0, 4, 0));
    ASSERT_TRUE(builder.add_mesh(q.positions, q.normals, q.uvs, q.triangles, material).is_ok());
    const Scene scene = builder.build().value();
    // A hit inside a check, where level 0 reads 0 or 1 (not a blend at a check's edge).
    Hit hit{1.0f, 0, 0.0f, 0.0f};
    float level_zero = 0.5f;
    for (int i = 1; i < 64 && std::abs(level_zero - 0.5f) < 0.49f; ++i) {
        hit.u = 0.013f * static_cast<float>(i);
        hit.v = 0.007f * static_cast<float>(i);
        level_zero = scene.emission_at(material, make_interaction(scene, hit, Vec3(0, 0, -1)).tex).x;
    }
    ASSERT_GT(std::abs(level_zero - 0.5f), 0.49f);
    const SurfaceInteraction wide = make_interaction(scene, hit, Vec3(0, 0, -1), 0.5f, ConeKind::Wide);
    const SurfaceInteraction pixel = make_interaction(scene, hit, Vec3(0, 0, -1), 0.5f, ConeKind::Pixel);
    // The albedo is the checks' mean either way; the emission a wide cone reads is level 0's, as
    // light sampling reads it, where a pixel's cone averages it too.
    EXPECT_NEAR(scene.material_point(material, wide.tex).base_color.x, 0.5f, 0.01f);
    EXPECT_NEAR(scene.material_point(material, pixel.tex).base_color.x, 0.5f, 0.01f);
    EXPECT_EQ(scene.emission_at(material, wide.tex).x, level_zero);
    EXPECT_NEAR(scene.emission_at(material, pixel.tex).x, 0.5f, 0.01f);

    // Between two levels a wide cone reads the nearer alone: at a check's centre level 2 (a texel
    // a check) reads the check's value, level 3 (a texel four checks) 1/2, a blend of them
    // neither. Level 2.4 is a footprint of 2^2.4 level-0 texels, 2^2.4 / 512 in uv, 0.0103 in
    // uv units of the quad's 0.25 per world unit: a cone 0.0413 wide.
    TexturePoint centre = wide.tex;
    centre.uv = Vec2(6.0f, 2.0f) / 512.0f;  // the centre of the second check along u, level 2
    centre.footprint = std::exp2(2.4f) / 512.0f;
    const float one_level = scene.material_point(material, centre).base_color.x;
    centre.wide_cone = false;
    const float blended = scene.material_point(material, centre).base_color.x;
    EXPECT_TRUE(one_level == 0.0f || one_level == 1.0f) << one_level;
    EXPECT_NEAR(blended, 0.6f * one_level + 0.4f * 0.5f, 0.02f);

    // On a triangle a hundredth as wide in texture space, the cone's footprint stops at the
    // triangle's extent there (square root of its uv parallelogram's area); a pixel's does not.
    SceneBuilder small_builder("small triangles in texture space");
    small_builder.add_texture(Texture(*scene.textures[0]));
    const uint32_t small_material = small_builder.add_material(m);
    std::vector<Vec2> small_uvs = q.uvs;
    for (Vec2& uv : small_uvs) uv *= 0.01f;
    ASSERT_TRUE(small_builder.add_mesh(q.positions, q.normals, small_uvs, q.triangles, small_material).is_ok());
    const Scene small = small_builder.build().value();
    const float extent = 0.01f;  // sqrt of the parallelogram (0.01 x 0.01) of each half of the quad
    EXPECT_NEAR(make_interaction(small, hit, Vec3(0, 0, -1), 8.0f, ConeKind::Wide).tex.footprint, extent, 1e-5f);
    EXPECT_NEAR(make_interaction(small, hit, Vec3(0, 0, -1), 8.0f, ConeKind::Pixel).tex.footprint, 8.0f * 0.01f / 4.0f,
                1e-5f);
}

}  // namespace
}  // namespace photond
