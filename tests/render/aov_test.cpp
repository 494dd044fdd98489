// AOV layers: the radiance parts (emission, direct, indirect, caustic) sum to the beauty pass for
// every integrator, asking for AOVs leaves the beauty pass unchanged to the bit, and albedo,
// normal and depth match the Cornell box's walls as computed analytically from its geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/integrators/direct.h"
#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

constexpr int kWidth = 48, kHeight = 40;

struct Cornell {
    std::shared_ptr<const Scene> scene;
    std::shared_ptr<const RenderScene> render_scene;
    Camera camera;
};

const Cornell& cornell() {
    static const Cornell c = [] {
        auto scene = std::make_shared<const Scene>(make_builtin_scene("cornell-box").value());
        auto rs = RenderScene::create(EmbreeDevice::create().value(), scene).value();
        return Cornell{scene, rs, Camera::create(scene->cameras.at(0), kWidth, kHeight).value()};
    }();
    return c;
}

TileSettings settings_with(std::vector<Aov> aovs) {
    TileSettings s;
    s.tile_size = 16;
    s.samples_per_pixel = 4;
    s.seed = 7;
    s.threads = 2;
    s.aovs = std::move(aovs);
    return s;
}

const std::vector<Aov> kRadianceParts{Aov::Emission, Aov::Direct, Aov::Indirect, Aov::Caustic};

double mean_luminance(const Image& image) {
    double sum = 0.0;
    for (const Color& c : image.pixels()) sum += luminance(c);
    return sum / double(image.pixel_count());
}

// The four parts add up to the beauty pixel (to float rounding of the per-sample sums), each part
// is finite and non-negative, and the beauty pass is bit-identical to a render without AOVs.
void expect_parts_sum_to_beauty(const Integrator& integrator, const char* label) {
    const Cornell& c = cornell();
    const TileRenderResult plain = render_tiles(integrator, c.camera, settings_with({}));
    const TileRenderResult split = render_tiles(integrator, c.camera, settings_with(kRadianceParts));
    EXPECT_TRUE(plain.layers.aovs.empty());
    EXPECT_TRUE(split.layers.beauty == plain.layers.beauty) << label << ": AOVs changed the beauty pass";
    ASSERT_EQ(split.layers.aovs.size(), kRadianceParts.size());
    for (size_t a = 0; a < kRadianceParts.size(); ++a)
        EXPECT_EQ(split.layers.aovs[a].first, aov_name(kRadianceParts[a]));

    double worst = 0.0;
    for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) {
            Color sum(0.0f);
            for (const auto& [name, layer] : split.layers.aovs) {
                const Color part = layer.at(x, y);
                ASSERT_TRUE(is_finite(part)) << label << " " << name << " at " << x << "," << y;
                ASSERT_GE(min_component(part), 0.0f) << label << " " << name << " at " << x << "," << y;
                sum += part;
            }
            const Color beauty = split.layers.beauty.at(x, y);
            for (int ch = 0; ch < 3; ++ch)
                worst = std::max(worst, double(std::abs(sum[ch] - beauty[ch])) / std::max(1.0, double(beauty[ch])));
        }
    }
    EXPECT_LT(worst, 1e-5) << label << ": the parts do not sum to the beauty pass";
}

TEST(Aov, PathTracerPartsSumToTheBeautyPass) {
    PathIntegrator integrator(cornell().render_scene);
    expect_parts_sum_to_beauty(integrator, "path");
}

TEST(Aov, DirectLightingPartsSumToTheBeautyPass) {
    DirectIntegrator integrator(cornell().render_scene);
    expect_parts_sum_to_beauty(integrator, "direct");
}

TEST(Aov, PhotonMapPartsSumToTheBeautyPassAndEachPartHoldsLight) {
    const Cornell& c = cornell();
    PhotonTracingSettings photons;
    photons.global_photons = 20000;
    photons.caustic_photons = 20000;
    auto maps = std::make_shared<const PhotonMaps>(trace_photons(*c.render_scene, photons).value());
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = 64;
    PhotonMapIntegrator integrator(c.render_scene, maps, settings);
    integrator.build_cache(c.camera, nullptr);
    expect_parts_sum_to_beauty(integrator, "photon-map");

    // The Cornell box has all four: the light seen from the camera, direct light on the walls,
    // colour bleeding, and the glass sphere's caustic on the floor.
    const TileRenderResult split = render_tiles(integrator, c.camera, settings_with(kRadianceParts));
    for (const auto& [name, layer] : split.layers.aovs) {
        std::printf("photon-map %s: mean luminance %.4f of %.4f\n", name.c_str(), mean_luminance(layer),
                    mean_luminance(split.layers.beauty));
        EXPECT_GT(mean_luminance(layer), 1e-3 * mean_luminance(split.layers.beauty)) << name;
    }
}

// The Cornell box's walls (core/scene/builtin_scenes.cpp): planes of the box
// [-2.75, 2.75] x [0, 5.5] x [-2.75, 2.75] with the front (z = +2.75) open, and two unit spheres
// resting on the floor at (-1.4, -1.2) and (1.3, 0.9).
struct Wall {
    int axis;      // the coordinate that is constant on it
    float value;   // that coordinate
    Vec3 normal;   // towards the interior
    Color albedo;  // its base colour
};
const Wall kWalls[] = {
    {1, 0.0f, {0, 1, 0}, Color(0.75f)},                      // floor
    {1, 5.5f, {0, -1, 0}, Color(0.75f)},                     // ceiling (the light hangs below it)
    {2, -2.75f, {0, 0, 1}, Color(0.75f)},                    // back
    {0, -2.75f, {1, 0, 0}, Color(0.75f, 0.25f, 0.25f)},      // left, red
    {0, 2.75f, {-1, 0, 0}, Color(0.25f, 0.25f, 0.75f)},      // right, blue
};

// The wall a ray meets first and the distance to it, or -1 when it leaves the box.
int wall_hit(const Vec3& origin, const Vec3& direction, float* distance) {
    int best = -1;
    float nearest = INFINITY;
    for (int w = 0; w < 5; ++w) {
        const Wall& wall = kWalls[w];
        if (direction[wall.axis] == 0.0f) continue;
        const float t = (wall.value - origin[wall.axis]) / direction[wall.axis];
        if (!(t > 0.0f) || t >= nearest) continue;
        const Vec3 p = origin + t * direction;
        const bool inside = p.x >= -2.7501f && p.x <= 2.7501f && p.y >= -1e-4f && p.y <= 5.5001f &&
                            p.z >= -2.7501f && p.z <= 2.7501f;
        if (inside) {
            nearest = t;
            best = w;
        }
    }
    *distance = nearest;
    return best;
}

// Whether the ray passes within `margin` of a sphere or the light (the analytic walls do not
// describe what it meets there).
bool near_an_object(const Vec3& origin, const Vec3& direction) {
    const Vec3 centres[] = {{-1.4f, 1.0f, -1.2f}, {1.3f, 1.0f, 0.9f}};
    for (const Vec3& centre : centres) {
        const Vec3 to = centre - origin;
        const float along = glm::dot(to, direction);
        if (glm::length(to - along * direction) < 1.3f) return true;
    }
    float t = 0.0f;
    if (wall_hit(origin, direction, &t) == 1) return true;  // the ceiling holds the light
    return false;
}

TEST(Aov, AlbedoNormalAndDepthMatchTheWallsTheCameraSees) {
    const Cornell& c = cornell();
    PathIntegrator integrator(c.render_scene);
    TileSettings settings = settings_with({Aov::Albedo, Aov::Normal, Aov::Depth});
    settings.samples_per_pixel = 64;  // the depth of a pixel is a mean over its area
    const TileRenderResult r = render_tiles(integrator, c.camera, settings);
    ASSERT_EQ(r.layers.aovs.size(), 3u);
    const Image& albedo = r.layers.aovs[0].second;
    const Image& normal = r.layers.aovs[1].second;
    const Image& depth = r.layers.aovs[2].second;

    int checked[5] = {0, 0, 0, 0, 0};
    double worst_depth = 0.0;
    int outside = 0;
    for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) {
            // A pixel is checked when rays through an 8 x 8 grid over it all meet the same wall,
            // away from the spheres and the light; its expected depth is their mean (the depth
            // varies across a pixel on the floor seen at a grazing angle).
            int wall = -2;
            double expected_depth = 0.0;
            bool uniform = true;
            constexpr int kGrid = 8;
            for (int i = 0; i < kGrid * kGrid; ++i) {
                const float u = (float(i % kGrid) + 0.5f) / kGrid, v = (float(i / kGrid) + 0.5f) / kGrid;
                const CameraRay ray = c.camera.generate_ray(float(x) + u, float(y) + v);
                float t = 0.0f;
                const int w = wall_hit(ray.origin, ray.direction, &t);
                if (near_an_object(ray.origin, ray.direction) || (wall != -2 && w != wall)) uniform = false;
                wall = w;
                expected_depth += t / double(kGrid * kGrid);
            }
            if (!uniform) continue;
            if (wall < 0) {
                // Out through the open front: nothing is met.
                EXPECT_EQ(albedo.at(x, y), Color(0.0f)) << x << "," << y;
                EXPECT_EQ(depth.at(x, y), Color(0.0f)) << x << "," << y;
                ++outside;
                continue;
            }
            ++checked[wall];
            const Wall& w = kWalls[wall];
            for (int ch = 0; ch < 3; ++ch) {
                EXPECT_NEAR(albedo.at(x, y)[ch], w.albedo[ch], 1e-6f) << "wall " << wall << " at " << x << "," << y;
                EXPECT_NEAR(normal.at(x, y)[ch], w.normal[ch], 1e-5f) << "wall " << wall << " at " << x << "," << y;
            }
            // Depth is repeated in R, G and B; within a pixel it is not linear, hence the bound.
            EXPECT_EQ(depth.at(x, y)[0], depth.at(x, y)[1]);
            worst_depth = std::max(worst_depth, std::abs(depth.at(x, y)[0] - expected_depth) / expected_depth);
            EXPECT_NEAR(depth.at(x, y)[0], expected_depth, 5e-4 * expected_depth)
                << "wall " << wall << " at " << x << "," << y;
        }
    }
    std::printf("worst relative depth error %.2e; pixels checked: floor %d, back %d, left %d, right %d, outside %d\n",
                worst_depth, checked[0], checked[2], checked[3], checked[4], outside);
    // The floor, the back wall and both coloured walls are seen in many pixels.
    EXPECT_GT(checked[0], 20);
    EXPECT_GT(checked[2], 100);
    EXPECT_GT(checked[3], 20);
    EXPECT_GT(checked[4], 20);
}

TEST(Aov, LayersAreTheSameForAnyThreadCount) {
    PathIntegrator integrator(cornell().render_scene);
    std::vector<Aov> all(kAllAovs.begin(), kAllAovs.end());
    TileSettings one = settings_with(all);
    one.threads = 1;
    TileSettings three = settings_with(all);
    three.threads = 3;
    const TileRenderResult a = render_tiles(integrator, cornell().camera, one);
    const TileRenderResult b = render_tiles(integrator, cornell().camera, three);
    ASSERT_EQ(a.layers.aovs.size(), kAllAovs.size());
    for (size_t i = 0; i < kAllAovs.size(); ++i) {
        EXPECT_EQ(a.layers.aovs[i].first, b.layers.aovs[i].first);
        EXPECT_TRUE(a.layers.aovs[i].second == b.layers.aovs[i].second) << a.layers.aovs[i].first;
    }
}

TEST(Aov, EveryNameMapsToItsAov) {
    for (Aov aov : kAllAovs) {
        ASSERT_TRUE(aov_from_name(aov_name(aov)).has_value()) << aov_name(aov);
        EXPECT_EQ(*aov_from_name(aov_name(aov)), aov);
    }
    EXPECT_FALSE(aov_from_name("beauty").has_value());
    EXPECT_FALSE(aov_from_name("").has_value());
}

}  // namespace
}  // namespace photond
