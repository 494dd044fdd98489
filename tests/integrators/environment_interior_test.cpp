// Environment light through the photon-map integrator's split (the diffuse sky to final
// gathering, also through specular surfaces; its peaks and other lights to light sampling and
// the caustic map) against the path tracer: "sunlit-room", a textured room lit only by a sky
// image and its sun through a window, the same room with an alpha-masked lattice across the
// window and a normal-mapped floor, and a glass sphere on a floor under a uniform sky (no
// caustic map needed) and under a sky with a sun (a caustic map of the sun alone).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string_view>
#include <vector>

#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"
#include "core/render/render_plan.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"
#include "core/scene/shapes.h"

#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::make_render_scene;

/// The mean of each of the image's left and right halves, and of the whole.
std::array<double, 3> half_means(const Image& image) {
    double left = 0.0, right = 0.0;
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            EXPECT_TRUE(is_finite(image.at(x, y)));
            (x < image.width() / 2 ? left : right) += luminance(image.at(x, y));
        }
    }
    const double half = 0.5 * image.width() * image.height();
    return {left / half, right / half, 0.5 * (left + right) / half};
}

/// The photon-map integrator as the pipeline sets it up: planned passes, final photon counts.
Image render_photon_map(const std::shared_ptr<const RenderScene>& rs, const Camera& camera, RenderPlan* plan) {
    *plan = plan_photon_passes(*rs->scene, *rs->lights, {200000, 50000}, rs->lights_with_sky_peaks.get());
    PhotonTracingSettings tracing;
    tracing.global_photons = plan->global_map ? 200000 : 0;
    tracing.caustic_photons = plan->caustic_map ? 50000 : 0;
    auto maps = trace_photons(*rs, tracing);
    EXPECT_TRUE(maps) << maps.error().message;
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = 256;
    settings.irradiance_cache.accuracy = 0.3f;
    PhotonMapIntegrator photon_map(rs, std::make_shared<const PhotonMaps>(std::move(maps).value()), settings);
    photon_map.build_cache(camera, nullptr);
    TileSettings tiles;
    tiles.samples_per_pixel = 16;
    return render_tiles(photon_map, camera, tiles).layers.beauty;
}

/// A path render at `samples_per_pixel`.
Image render_path(const std::shared_ptr<const RenderScene>& rs, const Camera& camera, int samples_per_pixel) {
    TileSettings tiles;
    tiles.samples_per_pixel = samples_per_pixel;
    return render_tiles(PathIntegrator(rs), camera, tiles).layers.beauty;
}

/// The image means of a converged path render (1024 spp).
std::array<double, 3> path_means(const std::shared_ptr<const RenderScene>& rs, const Camera& camera) {
    return half_means(render_path(rs, camera, 1024));
}

/// The lattice screen's cells: kLatticeCell x kLatticeCell texels, the outermost ring of each
/// opaque (bars two texels wide between cells), the rest holes; kLatticeOpen of it is holes.
constexpr int kLatticeCell = 8;
constexpr double kLatticeOpen = (kLatticeCell - 2.0) * (kLatticeCell - 2.0) / (kLatticeCell * kLatticeCell);
/// The floor's bumps: normals (-s cos a sin b, -s sin a cos b, 1) for s = kBumpSlope, tilted up
/// to 56 degrees.
constexpr float kBumpSlope = 1.5f;

/// Appends a mesh to a built scene (a SceneBuilder starts empty), with zero tangents (no normal
/// map) where the scene has tangents; the caller derives the triangle data again.
void add_to_scene(Scene& scene, const MeshData& mesh, uint32_t material) {
    const auto base = static_cast<uint32_t>(scene.positions.size());
    scene.positions.insert(scene.positions.end(), mesh.positions.begin(), mesh.positions.end());
    scene.normals.insert(scene.normals.end(), mesh.normals.begin(), mesh.normals.end());
    scene.uvs.insert(scene.uvs.end(), mesh.uvs.begin(), mesh.uvs.end());
    if (!scene.tangents.empty()) scene.tangents.resize(scene.positions.size(), Vec4(0.0f));
    for (const glm::uvec3& t : mesh.triangles) {
        scene.triangles.push_back(t + base);
        scene.triangle_materials.push_back(material);
    }
    for (const Vec3& p : mesh.positions) scene.bounds.extend(p);
}

/// The index of the material called `name`.
uint32_t material_named(const Scene& scene, std::string_view name) {
    const auto it = std::find_if(scene.materials.begin(), scene.materials.end(),
                                 [&](const Material& m) { return m.name == name; });
    EXPECT_NE(it, scene.materials.end()) << name;
    return static_cast<uint32_t>(it - scene.materials.begin());
}

/// "sunlit-room" with, optionally, an alpha-MASKed lattice across the window (sun and sky come
/// in through its holes only) and a normal map of egg-crate bumps on the sunlit floor.
Scene sunlit_room_variant(bool lattice, bool bumps) {
    Scene scene = make_builtin_scene("sunlit-room").value();
    if (lattice) {
        Texture t;
        t.width = t.height = kLatticeCell;
        t.texels.assign(kLatticeCell * kLatticeCell, Color(1.0f));
        t.alpha.resize(t.texels.size());
        for (int y = 0; y < kLatticeCell; ++y) {
            for (int x = 0; x < kLatticeCell; ++x) {
                const bool bar = x == 0 || y == 0 || x == kLatticeCell - 1 || y == kLatticeCell - 1;
                t.alpha[static_cast<size_t>(y * kLatticeCell + x)] = bar ? 1.0f : 0.0f;
            }
        }
        t.nearest = true;  // crisp bars: bilinear alpha would round their ends
        t.build_mip_levels();
        scene.textures.push_back(std::make_shared<const Texture>(std::move(t)));
        Material screen = test_support::lambertian(Color(0.5f));
        screen.name = "lattice";
        screen.alpha_mode = AlphaMode::Mask;
        screen.base_color_texture.texture = static_cast<int>(scene.textures.size() - 1);
        // 3 x 2 cells of 0.6 m over the 1.8 x 1.2 m opening: holes of 0.45 m, wider than the
        // sun's penumbra on the floor (0.06 rad across, 2 to 4 m below the window: 0.1 to
        // 0.25 m), so the sunlit floor shows the lattice.
        screen.base_color_texture.transformed = true;
        screen.base_color_texture.m0 = Vec2(3.0f, 0.0f);
        screen.base_color_texture.m1 = Vec2(0.0f, 2.0f);
        scene.materials.push_back(screen);
        // In the plane of the wall, exactly filling the opening: no light passes beside it.
        const float y0 = kSunlitRoomWindow[0], y1 = kSunlitRoomWindow[1];
        const float z0 = kSunlitRoomWindow[2], z1 = kSunlitRoomWindow[3];
        add_to_scene(scene,
                     make_quad(Vec3(kSunlitRoomHalfWidth, y0, z0), Vec3(0.0f, 0.0f, z1 - z0),
                               Vec3(0.0f, y1 - y0, 0.0f), Vec3(-1.0f, 0.0f, 0.0f)),
                     static_cast<uint32_t>(scene.materials.size() - 1));
    }
    if (bumps) {
        // One period of h = sin(a) sin(b) in 32 x 32 texels, repeated every metre of the 4 x 6 m
        // floor (several pixels per bump at 48 x 48, so mip-mapping keeps most of the tilt).
        constexpr int kBumpTexels = 32;
        Texture t;
        t.width = t.height = kBumpTexels;
        t.texels.resize(kBumpTexels * kBumpTexels);
        for (int y = 0; y < kBumpTexels; ++y) {
            for (int x = 0; x < kBumpTexels; ++x) {
                const float a = 2.0f * kPi * (x + 0.5f) / kBumpTexels;
                const float b = 2.0f * kPi * (y + 0.5f) / kBumpTexels;
                const Vec3 n = glm::normalize(Vec3(-kBumpSlope * std::cos(a) * std::sin(b),
                                                   -kBumpSlope * std::sin(a) * std::cos(b), 1.0f));
                t.texels[static_cast<size_t>(y * kBumpTexels + x)] = 0.5f * (n + Vec3(1.0f));
            }
        }
        t.build_mip_levels();
        scene.textures.push_back(std::make_shared<const Texture>(std::move(t)));
        const uint32_t floor = material_named(scene, "floor");
        Material& m = scene.materials.at(floor);
        m.normal_texture.texture = static_cast<int>(scene.textures.size() - 1);
        m.normal_texture.transformed = true;
        m.normal_texture.m0 = Vec2(2.0f * kSunlitRoomHalfWidth, 0.0f);
        m.normal_texture.m1 = Vec2(0.0f, 2.0f * kSunlitRoomHalfDepth);
        // The floor's u runs along +x and v along +z (make_quad from the corner (-x, -z)): T = +x,
        // and the normal map's +y is -dp/dv = -z = cross(N, T) for N = +y, so w = +1 (as the
        // glTF loader's generate_tangents would make them).
        scene.tangents.assign(scene.positions.size(), Vec4(0.0f));
        for (size_t i = 0; i < scene.triangles.size(); ++i) {
            if (scene.triangle_materials[i] != floor) continue;
            for (int k = 0; k < 3; ++k) scene.tangents[scene.triangles[i][k]] = Vec4(1.0f, 0.0f, 0.0f, 1.0f);
        }
    }
    scene.derive_triangle_data();
    EXPECT_TRUE(scene.validate().is_ok());
    return scene;
}

/// The pixels whose centre sees a triangle of `material` first.
std::vector<uint8_t> pixels_showing(const RenderScene& rs, const Camera& camera, uint32_t material) {
    std::vector<uint8_t> mask(static_cast<size_t>(camera.width() * camera.height()), 0);
    for (int y = 0; y < camera.height(); ++y) {
        for (int x = 0; x < camera.width(); ++x) {
            const CameraRay c = camera.generate_ray(x + 0.5f, y + 0.5f);
            Ray ray{c.origin, c.direction};
            ray.from_viewpoint = true;
            const std::optional<Hit> hit = rs.tracer->intersect(ray);
            mask[static_cast<size_t>(y * camera.width() + x)] =
                hit && rs.scene->triangle_materials[hit->triangle] == material;
        }
    }
    return mask;
}

/// Mean luminance over the masked pixels.
double masked_mean(const Image& image, const std::vector<uint8_t>& mask) {
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            if (!mask[static_cast<size_t>(y * image.width() + x)]) continue;
            sum += luminance(image.at(x, y));
            ++n;
        }
    }
    return n > 0 ? sum / n : 0.0;
}

TEST(EnvironmentInterior, PhotonMapAgreesWithPathInTheSunlitRoom) {
    auto rs = make_render_scene(make_builtin_scene("sunlit-room").value());
    ASSERT_TRUE(rs->lights_with_sky_peaks) << "the room's sky must split into its sun and the rest";
    ASSERT_TRUE(rs->sky_peaks && rs->diffuse_sky);
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 48, 48).value();

    const std::array<double, 3> reference = path_means(rs, camera);
    RenderPlan plan;
    const std::array<double, 3> estimate = half_means(render_photon_map(rs, camera, &plan));
    EXPECT_FALSE(plan.caustic_map);  // nothing in the room is specular

    std::printf("sunlit-room 48x48: path means %.4f %.4f %.4f, photon-map %.4f %.4f %.4f\n", reference[0],
                reference[1], reference[2], estimate[0], estimate[1], estimate[2]);
    EXPECT_NEAR(estimate[2] / reference[2], 1.0, 0.02);      // the whole image
    for (int h = 0; h < 2; ++h) EXPECT_NEAR(estimate[h] / reference[h], 1.0, 0.04) << "half " << h;
}

TEST(EnvironmentInterior, PhotonMapAgreesWithPathThroughALatticeOntoANormalMappedFloor) {
    auto rs = make_render_scene(sunlit_room_variant(true, true));
    ASSERT_TRUE(rs->lights_with_sky_peaks && rs->sky_peaks && rs->diffuse_sky);
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 48, 48).value();

    const Image path = render_path(rs, camera, 1024);
    const std::array<double, 3> reference = half_means(path);
    RenderPlan plan;
    const std::array<double, 3> estimate = half_means(render_photon_map(rs, camera, &plan));
    EXPECT_FALSE(plan.caustic_map);  // nothing in the room is specular
    std::printf("sunlit-room, lattice and bumps 48x48: path means %.4f %.4f %.4f, photon-map %.4f %.4f %.4f\n",
                reference[0], reference[1], reference[2], estimate[0], estimate[1], estimate[2]);
    EXPECT_NEAR(estimate[2] / reference[2], 1.0, 0.02);      // the whole image
    for (int h = 0; h < 2; ++h) EXPECT_NEAR(estimate[h] / reference[h], 1.0, 0.04) << "half " << h;

    // The lattice lets in only its holes' share of the sun and sky (kLatticeOpen), and its bars'
    // inner faces send some of the room's light back in: against the room without it, the
    // image keeps a little more than kLatticeOpen of its mean (an opaque screen would keep 0, a
    // mask that covers nothing 1).
    const auto unscreened_room = make_render_scene(sunlit_room_variant(false, true));
    const double unscreened = half_means(render_path(unscreened_room, camera, 256))[2];
    const double let_in = reference[2] / unscreened;
    // The bumps: the floor's pixels, normal-mapped against flat under the same lattice.
    const std::vector<uint8_t> floor = pixels_showing(*rs, camera, material_named(*rs->scene, "floor"));
    const Image flat = render_path(make_render_scene(sunlit_room_variant(true, false)), camera, 256);
    half_means(flat);  // every pixel finite
    const double bumpy_floor = masked_mean(path, floor), flat_floor = masked_mean(flat, floor);
    std::printf("lattice lets in %.4f of the unscreened room's mean %.4f (holes: %.4f); floor pixels bumpy %.4f, "
                "flat %.4f\n",
                let_in, unscreened, kLatticeOpen, bumpy_floor, flat_floor);
    EXPECT_GT(let_in, kLatticeOpen - 0.02);
    EXPECT_LT(let_in, kLatticeOpen + 0.1);
    // Tilted normals see the sun at 30 degrees elevation less on average, and what their cosine
    // lobes send under the floor is lost (geometry_agrees in core/material/bsdf.h): the bumpy
    // floor is clearly darker than the flat one (a normal map that did nothing would give 1).
    EXPECT_LT(bumpy_floor / flat_floor, 0.85);
}

TEST(EnvironmentTransport, GlassOnAFloorUnderUniformAndSunnySkiesAgreesWithPath) {
    for (const bool sunny : {false, true}) {
        Scene scene = make_builtin_scene("caustic").value();
        scene.lights.clear();  // the sky alone
        Environment sky;
        if (sunny) {
            // A small, bright sun above and behind the sphere, so that its caustic lies in view.
            sky.name = "sunny";
            sky.width = 64;
            sky.height = 32;
            sky.texels.assign(64 * 32, Color(0.3f, 0.4f, 0.6f));
            sky.texels[6 * 64 + 16] = Color(2000.0f, 1900.0f, 1700.0f);
        }
        scene.environment = sky;
        auto rs = make_render_scene(std::move(scene));
        const Camera camera = Camera::create(rs->scene->cameras.at(0), 48, 36).value();
        RenderPlan plan;
        const Image image = render_photon_map(rs, camera, &plan);
        const PassDecision* caustic = plan.find("caustic_map");
        ASSERT_TRUE(caustic);
        EXPECT_EQ(caustic->enabled, sunny) << caustic->reason;

        const std::array<double, 3> reference = path_means(rs, camera);
        const std::array<double, 3> estimate = half_means(image);
        std::printf("glass under a %s sky 48x36: path %.4f, photon-map %.4f\n", sunny ? "sunny" : "uniform",
                    reference[2], estimate[2]);
        EXPECT_NEAR(estimate[2] / reference[2], 1.0, 0.02) << (sunny ? "sunny" : "uniform");
    }
}

}  // namespace
}  // namespace photond
