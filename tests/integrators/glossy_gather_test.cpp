// Glossy surfaces seen in glossy surfaces: the photon-map integrator's glossy rays land on another
// glossy surface, where final gathering follows the glossy lobe by sampling (a light sample and
// a lobe sample, power heuristic) instead of reading the photons with the sharp lobe, whose rare
// photons along its peak are fireflies. Both against `path`, pixel by pixel. Rough glass is
// followed as glossy lobes are, and where the rays stop it is read from both sides' precomputed
// irradiance. Where a
// glossy ray lands next to where it left (a sphere's base reflecting the floor it stands on), the
// hit traces a bounce instead of reading the photons (Jensen's short-ray rule).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "core/image/image_metrics.h"
#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"
#include "core/render/render_plan.h"
#include "core/render/tile_renderer.h"
#include "core/scene/shapes.h"

#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;

/// Two glossy metal spheres (roughness 0.1) side by side on a Lambertian floor under a square
/// area light: the camera sees each sphere in the other.
std::shared_ptr<const RenderScene> glossy_spheres() {
    SceneBuilder builder("glossy spheres");
    const uint32_t floor = builder.add_material(lambertian(Color(0.6f, 0.5f, 0.4f)));
    Material metal;
    metal.base_color = Color(0.9f, 0.85f, 0.8f);
    metal.metallic = 1.0f;
    metal.roughness = 0.1f;
    const uint32_t glossy = builder.add_material(metal);
    Material lamp = lambertian(Color(0.0f));
    lamp.emission = Color(6.0f);
    const uint32_t emitter = builder.add_material(lamp);
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-4, 0, -4), Vec3(8, 0, 0), Vec3(0, 0, 8), Vec3(0, 1, 0)), floor).is_ok());
    EXPECT_TRUE(add_mesh(builder, make_icosphere(Vec3(-0.55f, 0.5f, 0.0f), 0.5f, 4), glossy).is_ok());
    EXPECT_TRUE(add_mesh(builder, make_icosphere(Vec3(0.55f, 0.5f, 0.0f), 0.5f, 4), glossy).is_ok());
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-1, 3, -1), Vec3(2, 0, 0), Vec3(0, 0, 2), Vec3(0, -1, 0)), emitter).is_ok());
    CameraDesc view;
    view.position = Vec3(0.0f, 0.9f, 2.4f);
    view.look_at = Vec3(0.0f, 0.45f, 0.0f);
    view.vfov_deg = 40.0f;
    builder.add_camera(view);
    return make_render_scene(builder.build().value());
}

/// glossy_spheres() through its camera at 48x32, the view the per-pixel comparisons use.
Camera glossy_spheres_camera(const std::shared_ptr<const RenderScene>& rs) {
    return Camera::create(rs->scene->cameras.at(0), 48, 32).value();
}

/// `path` at `spp` (1024 unless told): the per-pixel reference of a view.
Image path_reference(const std::shared_ptr<const RenderScene>& rs, const Camera& camera, int spp = 1024) {
    TileSettings tiles;
    tiles.samples_per_pixel = spp;
    return render_tiles(PathIntegrator(rs), camera, tiles).layers.beauty;
}

/// The scene `builder` holds, seen from `position` towards `look_at` (40 degrees), under a uniform
/// sky of radiance 1.
std::shared_ptr<const RenderScene> under_uniform_sky(SceneBuilder& builder, const Vec3& position, const Vec3& look_at,
                                                     float vfov_deg = 40.0f) {
    CameraDesc view;
    view.position = position;
    view.look_at = look_at;
    view.vfov_deg = vfov_deg;
    builder.add_camera(view);
    Scene scene = builder.build().value();
    scene.environment = Environment{};  // uniform, radiance 1
    return make_render_scene(std::move(scene));
}

/// The photon maps of 100k global and `caustic` caustic photons (empty maps, after a failed
/// expectation, when tracing fails).
std::shared_ptr<const PhotonMaps> trace_maps(const std::shared_ptr<const RenderScene>& rs, uint32_t caustic) {
    PhotonTracingSettings tracing;
    tracing.global_photons = 100000;
    tracing.caustic_photons = caustic;
    auto traced = trace_photons(*rs, tracing);
    EXPECT_TRUE(traced) << traced.error().message;
    return traced ? std::make_shared<const PhotonMaps>(std::move(traced).value()) : std::make_shared<const PhotonMaps>();
}

/// `photon-map` without the irradiance cache: `global` photons (no caustic map), `rays` gather
/// rays, `spp` samples per pixel.
Image render_photon_map(const std::shared_ptr<const RenderScene>& rs, const Camera& camera, uint32_t global,
                        uint32_t rays, int spp) {
    PhotonTracingSettings tracing;
    tracing.global_photons = global;
    tracing.caustic_photons = 0;
    auto traced = trace_photons(*rs, tracing);
    EXPECT_TRUE(traced) << traced.error().message;
    if (!traced) return Image(camera.width(), camera.height());
    EXPECT_TRUE(traced->irradiance) << "gather hits on diffuse-reading surfaces read the precomputed irradiance";
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = rays;
    settings.use_irradiance_cache = false;
    const PhotonMapIntegrator photon_map(rs, std::make_shared<const PhotonMaps>(std::move(traced).value()), settings);
    TileSettings tiles;
    tiles.samples_per_pixel = spp;
    return render_tiles(photon_map, camera, tiles).layers.beauty;
}

TEST(GlossyGather, GlossyLobesFollowedBySamplingAgreeWithPathPerPixel) {
    const auto rs = glossy_spheres();
    const Camera camera = glossy_spheres_camera(rs);
    const Image reference = path_reference(rs, camera);
    const auto maps = trace_maps(rs, 0);
    ASSERT_TRUE(maps->global);
    const auto render = [&](int max_glossy_bounces) {
        PhotonMapIntegratorSettings settings;
        settings.gather.rays = 128;
        settings.gather.max_glossy_bounces = max_glossy_bounces;
        settings.use_irradiance_cache = false;
        const PhotonMapIntegrator photon_map(rs, maps, settings);
        TileSettings tiles;
        tiles.samples_per_pixel = 32;
        const Image image = render_tiles(photon_map, camera, tiles).layers.beauty;
        for (const Color& c : image.pixels()) EXPECT_TRUE(is_finite(c));
        return compare_images(image, reference).value();
    };
    const ImageError followed = render(2), read = render(0);
    std::printf("glossy spheres 48x32 vs path: lobes followed relMSE %.5f (mean %+.2f %%), read from photons "
                "%.5f (%+.2f %%)\n",
                followed.relative_mse, 100.0 * followed.mean_bias, read.relative_mse, 100.0 * read.mean_bias);
    // Measured: followed 0.0078 (+0.5 %), read 0.0163 (+0.0 %); an emitter counted both by a
    // glossy sample's continuation and as the gather ray's first hit made the mean +4 % at 256 spp.
    EXPECT_NEAR(followed.mean_bias, 0.0, 0.015);
    EXPECT_LT(followed.relative_mse, 0.85 * read.relative_mse);
}

TEST(GlossyGather, SharpGlossyCausticsComeFromTheCausticMap) {
    // The spheres (roughness 0.1, under kSharpGlossyRoughness) focus the lamp onto the floor
    // as a mirror would, a little blurred: the plan runs the caustic map for them, its photons
    // are flagged photon_flags::kGlossyCaustic, and the image keeps path's mean (the gather
    // leaves those paths to the caustic map, counting none twice). The back wall of
    // builtin:glossy-objects shows what reading them through the irradiance cache cost
    // (PhotondRender.GlossyCausticsLeaveNoBlotchesOnTheWallTheyLight).
    const auto rs = glossy_spheres();
    const RenderPlan plan = plan_photon_passes(*rs->scene, *rs->lights, {100000, 20000});
    ASSERT_TRUE(plan.caustic_map) << "sharply glossy spheres focus light onto the floor";
    EXPECT_NE(plan.find("caustic_map")->reason.find("sharply glossy"), std::string::npos)
        << plan.find("caustic_map")->reason;
    const Camera camera = glossy_spheres_camera(rs);
    const Image reference = path_reference(rs, camera);
    const auto maps = trace_maps(rs, 20000);
    ASSERT_TRUE(maps->caustic);
    size_t glossy_caustics = 0;
    for (const Photon& photon : maps->caustic->tree().photons()) {
        if (photon.user_flags() & photon_flags::kGlossyCaustic) ++glossy_caustics;
    }
    EXPECT_GT(glossy_caustics, 10000u) << "the caustic map holds the spheres' glossy caustic";
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = 64;
    const PhotonMapIntegrator photon_map(rs, maps, settings);
    TileSettings tiles;
    tiles.samples_per_pixel = 16;
    const Image image = render_tiles(photon_map, camera, tiles).layers.beauty;
    for (const Color& c : image.pixels()) EXPECT_TRUE(is_finite(c));
    const ImageError error = compare_images(image, reference).value();
    std::printf("glossy spheres 48x32 with a glossy caustic map (%zu photons) vs path: relMSE %.5f (mean %+.2f %%)\n",
                glossy_caustics, error.relative_mse, 100.0 * error.mean_bias);
    // Measured: relMSE 0.0160 (mean +0.44 %), as without the caustic map (0.0173, +0.74 %, before
    // the short-ray rule).
    EXPECT_NEAR(error.mean_bias, 0.0, 0.015);
}

TEST(GlossyGather, RoughMetalUnderAUniformSkyIsAsSmoothAsPath) {
    // The glTF default material (metal, roughness 1) on a plane under a uniform sky: light
    // sampling leaves the diffuse sky to the gather, so its rough lobe saw the sky through one
    // BSDF ray per sample alone (relMSE 25 times path's at 16 spp). The sky is light-sampled
    // there too, with MIS, from the pixel's stratified dimensions.
    SceneBuilder builder("rough metal plane");
    Material metal;
    metal.base_color = Color(1.0f);
    metal.metallic = 1.0f;
    metal.roughness = 1.0f;
    const uint32_t m = builder.add_material(metal);
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-1, 0, -1), Vec3(2, 0, 0), Vec3(0, 0, 2), Vec3(0, 1, 0)), m).is_ok());
    const auto rs = under_uniform_sky(builder, Vec3(0.0f, 1.5f, 1.5f), Vec3(0.0f));
    ASSERT_TRUE(rs->diffuse_sky) << "a uniform sky is all diffuse sky";
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 32, 32).value();
    const Image reference = path_reference(rs, camera, 4096);
    TileSettings tiles;
    tiles.samples_per_pixel = 16;
    const Image path16 = render_tiles(PathIntegrator(rs), camera, tiles).layers.beauty;
    const Image image = render_photon_map(rs, camera, 20000, 64, tiles.samples_per_pixel);
    const ImageError ours = compare_images(image, reference).value();
    const ImageError theirs = compare_images(path16, reference).value();
    std::printf("rough metal plane under a uniform sky, 16 spp: photon-map relMSE %.6f, path %.6f\n",
                ours.relative_mse, theirs.relative_mse);
    EXPECT_NEAR(ours.mean_bias, 0.0, 0.01);
    EXPECT_LT(ours.relative_mse, 3.0 * theirs.relative_mse);
}

TEST(GlossyGather, FloorUnderARoughGlassRoofAgreesWithPath) {
    // A floor under a roof of rough glass (roughness 0.6: as rough as diffuse) and a uniform sky:
    // what lights the floor beneath the roof comes through the glass, which shadow rays do not
    // cross. The gather rays that meet the roof follow it (a light sample and a lobe sample) and,
    // where they stop, read it from both sides, the sky's irradiance above it carried through by
    // a lobe sample and the floor's below; the side the other way round would leave the floor a
    // fraction as bright.
    SceneBuilder builder("rough glass roof");
    const uint32_t floor = builder.add_material(lambertian(Color(0.5f)));
    Material frosted;
    frosted.base_color = Color(1.0f);
    frosted.roughness = 0.6f;
    frosted.transmission = 1.0f;
    frosted.double_sided = true;
    const uint32_t glass = builder.add_material(frosted);
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-5, 0, -5), Vec3(10, 0, 0), Vec3(0, 0, 10), Vec3(0, 1, 0)), floor).is_ok());
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-2, 1, -2), Vec3(4, 0, 0), Vec3(0, 0, 4), Vec3(0, 1, 0)), glass).is_ok());
    const auto rs = under_uniform_sky(builder, Vec3(0.0f, 0.8f, 0.8f), Vec3(0.0f, 0.0f, -0.2f), 50.0f);
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 24, 24).value();
    const Image reference = path_reference(rs, camera);
    const Image image = render_photon_map(rs, camera, 100000, 128, 16);
    const ImageError error = compare_images(image, reference).value();
    std::printf("floor under a rough glass roof, 24x24 vs path: mean %.4f against %.4f (%+.2f %%), relMSE %.5f\n",
                error.mean, error.reference_mean, 100.0 * error.mean_bias, error.relative_mse);
    EXPECT_NEAR(error.mean_bias, 0.0, 0.03);
}

/// A ball of rough glass (`roughness`, red) on a grey floor under a uniform sky, seen from
/// close enough that it fills most of a 24x24 view.
std::shared_ptr<const RenderScene> rough_glass_ball(float roughness, float transmission = 1.0f) {
    SceneBuilder builder("rough glass ball");
    const uint32_t floor = builder.add_material(lambertian(Color(0.5f)));
    Material frosted;
    frosted.base_color = Color(0.95f, 0.2f, 0.1f);
    frosted.roughness = roughness;
    frosted.transmission = transmission;
    const uint32_t glass = builder.add_material(frosted);
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-5, 0, -5), Vec3(10, 0, 0), Vec3(0, 0, 10), Vec3(0, 1, 0)), floor).is_ok());
    EXPECT_TRUE(add_mesh(builder, make_icosphere(Vec3(0.0f, 0.5f, 0.0f), 0.5f, 5), glass).is_ok());
    return under_uniform_sky(builder, Vec3(0.0f, 0.9f, 1.6f), Vec3(0.0f, 0.45f, 0.0f));
}

TEST(GlossyGather, ARoughGlassBallAgreesWithPath) {
    // All the light inside a ball of rough glass came in through its surface. Read at once where
    // a gather ray meets the inside, the surface gives the irradiance of the few photons that
    // reached its inner side; followed as glossy lobes are, the rays leave the ball and read the
    // photons outside. As rough as diffuse (1.0) and glossy (0.3, 0.15). Where the rays stop
    // following, at glossy glass, the photons are read through one lobe sample from the
    // irradiance on the side it picks: read through the lobe itself, the rare photons that line
    // up with a sharp lobe made fireflies (roughness 0.15: one pixel 5.5 times its reference,
    // relative squared error 20). Half transmissive (also a Lambertian lobe and a rough layer,
    // read apart from the followed lobes): each lobe once.
    struct Ball {
        float roughness, transmission;
    };
    for (const Ball ball : {Ball{1.0f, 1.0f}, Ball{0.3f, 1.0f}, Ball{0.15f, 1.0f}, Ball{1.0f, 0.5f}}) {
        const float roughness = ball.roughness;
        const auto rs = rough_glass_ball(roughness, ball.transmission);
        const Camera camera = Camera::create(rs->scene->cameras.at(0), 24, 24).value();
        const Image reference = path_reference(rs, camera);
        const Image image = render_photon_map(rs, camera, 100000, 128, 16);
        const ImageError error = compare_images(image, reference, std::nullopt, 0.01, 1).value();
        std::printf("rough glass ball (roughness %.2f, transmission %.1f), 24x24 vs path: mean %.4f against %.4f "
                    "(%+.2f %%), relMSE %.5f, worst pixel %.3f\n", roughness, ball.transmission, error.mean,
                    error.reference_mean, 100.0 * error.mean_bias, error.relative_mse,
                    error.worst.at(0).relative_squared_error);
        EXPECT_NEAR(error.mean_bias, 0.0, 0.02) << "roughness " << roughness << ", transmission " << ball.transmission;
        EXPECT_LT(error.worst.at(0).relative_squared_error, 1.0)
            << "roughness " << roughness << ", transmission " << ball.transmission;
    }
}

/// A metal sphere of `roughness` resting on a floor under an area light, and a low camera
/// (48x32) that sees the sphere's base.
std::shared_ptr<const RenderScene> sphere_on_a_floor(float roughness, const Vec3& centre, float radius) {
    SceneBuilder builder("glossy sphere on a floor");
    const uint32_t floor = builder.add_material(lambertian(Color(0.6f)));
    Material metal;
    metal.base_color = Color(1.0f, 0.8f, 0.4f);
    metal.metallic = 1.0f;
    metal.roughness = roughness;
    const uint32_t glossy = builder.add_material(metal);
    Material lamp = lambertian(Color(0.0f));
    lamp.emission = Color(6.0f);
    const uint32_t emitter = builder.add_material(lamp);
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-4, 0, -4), Vec3(8, 0, 0), Vec3(0, 0, 8), Vec3(0, 1, 0)), floor).is_ok());
    EXPECT_TRUE(add_mesh(builder, make_icosphere(centre, radius, 5), glossy).is_ok());
    EXPECT_TRUE(add_mesh(builder, make_quad(Vec3(-1, 3, -1), Vec3(2, 0, 0), Vec3(0, 0, 2), Vec3(0, -1, 0)), emitter).is_ok());
    CameraDesc view;
    view.position = Vec3(0.0f, 0.35f, 1.8f);
    view.look_at = Vec3(0.0f, 0.2f, 0.0f);
    view.vfov_deg = 30.0f;
    builder.add_camera(view);
    return make_render_scene(builder.build().value());
}

TEST(GlossyGather, AGlossySphereReflectsTheShadowItStandsInAsPathDoes) {
    // A metal sphere resting on a floor under an area light. Its base reflects the floor beneath
    // it, in the sphere's own shadow: its glossy rays land there a few centimetres away. The
    // photon estimate at such a hit (the nearest precomputed site, or k photons) spreads over a
    // disc that reaches past the shadow into lit floor, and the base shone as a bright band
    // (builtin:glossy-objects' gold torus: +81 % against path). The short-ray rule
    // (GatherSettings::short_ray_radii) traces those hits a bounce on instead. Roughness 0.38
    // (glossy, not sharp: kSharpGlossyRoughness) has no caustic map (the bounce's ray is weighted
    // against its light sample by MIS); at 0.2 the sphere is sharply glossy and casts a caustic
    // map (the bounce reads it, and its ray counts no emitter behind the sphere).
    const Vec3 centre(0.0f, 0.5f, 0.0f);
    const float radius = 0.5f;
    for (const float roughness : {0.38f, 0.2f}) {
        SCOPED_TRACE("roughness " + std::to_string(roughness));
        const auto rs = sphere_on_a_floor(roughness, centre, radius);
        const Camera camera = Camera::create(rs->scene->cameras.at(0), 48, 32).value();
        // The sphere's base: pixels whose centre's ray meets the sphere below y = 0.15.
        std::vector<std::pair<int, int>> base;
        for (int y = 0; y < camera.height(); ++y) {
            for (int x = 0; x < camera.width(); ++x) {
                const CameraRay ray = camera.generate_ray(x + 0.5f, y + 0.5f);
                const Vec3 to_centre = ray.origin - centre;
                const float b = glm::dot(to_centre, ray.direction);
                const float discriminant = b * b - (glm::dot(to_centre, to_centre) - radius * radius);
                if (discriminant <= 0.0f) continue;
                const Vec3 hit = ray.origin + (-b - std::sqrt(discriminant)) * ray.direction;
                if (hit.y < 0.15f) base.emplace_back(x, y);
            }
        }
        ASSERT_GT(base.size(), 40u);
        const auto base_mean = [&](const Image& image) {
            double sum = 0.0;
            for (const auto& [x, y] : base) sum += luminance(image.at(x, y));
            return sum / static_cast<double>(base.size());
        };

        const double reference = base_mean(path_reference(rs, camera));
        const bool sharp = roughness < kSharpGlossyRoughness;
        const auto maps = trace_maps(rs, sharp ? 20000 : 0);
        ASSERT_TRUE(maps->global && maps->irradiance);
        ASSERT_EQ(maps->caustic != nullptr, sharp);
        const auto render = [&](float short_ray_radii) {
            PhotonMapIntegratorSettings settings;
            settings.gather.rays = 64;
            settings.gather.short_ray_radii = short_ray_radii;
            settings.use_irradiance_cache = false;
            const PhotonMapIntegrator photon_map(rs, maps, settings);
            TileSettings tiles;
            tiles.samples_per_pixel = 64;
            const TileRenderResult result = render_tiles(photon_map, camera, tiles);
            for (const Color& c : result.layers.beauty.pixels()) EXPECT_TRUE(is_finite(c));
            EXPECT_EQ(result.counters.short_ray_bounces > 0, short_ray_radii > 0.0f);
            return base_mean(result.layers.beauty) / reference - 1.0;
        };
        const double traced = render(GatherSettings{}.short_ray_radii), read = render(0.0f);
        // Measured at 64 spp: roughness 0.38 traced -0.8 %, read +48.1 %; 0.2 traced +7.9 %, read
        // +37.1 %. With 0.3 in place of 0.38 (before it was sharp), at 128 spp +3.7 % and +5.9 %
        // (the gap's bounces are noisy). What the rule leaves is the estimate's blur at hits a few
        // radii away: with 4 radii instead of 2, +1.2 % and +3.3 % then, for more bounces everywhere.
        std::printf("roughness %.2f: the sphere's base (%zu pixels) vs path: short rays traced %+.2f %%, read from the "
                    "photons %+.2f %%\n",
                    roughness, base.size(), 100.0 * traced, 100.0 * read);
        EXPECT_NEAR(traced, 0.0, 0.15);
    }
}

}  // namespace
}  // namespace photond
