// Shared helpers of the numerical stability stress tests: a small in-process render of a Scene
// (the steps of server/render_pipeline.cpp, which tests do not link) and image statistics.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/camera/camera.h"
#include "core/image/image.h"
#include "core/image/image_metrics.h"
#include "core/integrators/direct.h"
#include "core/integrators/path.h"
#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"
#include "core/render/render_plan.h"
#include "core/shading/render_scene.h"
#include "core/render/tile_renderer.h"
#include "core/scene/scene.h"
#include "core/scene/shapes.h"

namespace photond::stress {

/// Small, fast settings: every stress render finishes in well under a second or two.
struct StressRenderSettings {
    std::string integrator = "photon-map";  // "photon-map", "path" or "direct"
    int width = 48;
    int height = 48;
    int spp = 4;
    uint64_t seed = 1;
    uint32_t global_photons = 20000;
    uint32_t caustic_photons = 10000;
    uint64_t photon_seed = 1;
    bool final_gather = true;
    uint32_t gather_rays = 64;
    bool irradiance_cache = true;
    float cache_accuracy = 0.25f;
    bool cache_gradients = true;
    int threads = 0;
    /// Use this camera instead of the scene's first one.
    std::optional<CameraDesc> camera;
};

struct StressRender {
    Image image;
    PhotonTracingStatistics photons;
    CacheBuildStatistics cache;
    RayCounters counters;
};

inline std::shared_ptr<EmbreeDevice> shared_device() {
    static std::shared_ptr<EmbreeDevice> device = EmbreeDevice::create().value();
    return device;
}

/// Renders `scene` through its first camera (or settings.camera) with the settings' integrator,
/// as photond render would: photon passes planned from the scene, irradiance cache prepass, tiles.
inline Expected<StressRender> render_scene(std::shared_ptr<const Scene> scene,
                                           const StressRenderSettings& s) {
    auto rs = RenderScene::create(shared_device(), scene);
    if (!rs) return rs.error();
    if (!s.camera && scene->cameras.empty()) return Error{"stress render: the scene has no camera"};
    auto camera = Camera::create(s.camera ? *s.camera : scene->cameras.front(), s.width, s.height);
    if (!camera) return camera.error();
    StressRender out;
    std::unique_ptr<Integrator> integrator;
    if (s.integrator == "path") {
        integrator = std::make_unique<PathIntegrator>(*rs);
    } else if (s.integrator == "direct") {
        integrator = std::make_unique<DirectIntegrator>(*rs);
    } else if (s.integrator == "photon-map") {
        const RenderPlan plan =
            plan_photon_passes(*scene, *(*rs)->lights, {s.global_photons, s.caustic_photons});
        PhotonTracingSettings tracing;
        tracing.global_photons = plan.global_map ? s.global_photons : 0;
        tracing.caustic_photons = plan.caustic_map ? s.caustic_photons : 0;
        tracing.seed = s.photon_seed;
        tracing.threads = s.threads;
        auto maps = std::make_shared<PhotonMaps>();
        if (tracing.global_photons > 0 || tracing.caustic_photons > 0) {
            auto traced = trace_photons(**rs, tracing);
            if (!traced) return traced.error();
            *maps = std::move(traced).value();
        }
        out.photons = maps->statistics;
        PhotonMapIntegratorSettings pm;
        pm.final_gather = s.final_gather;
        pm.gather.rays = s.gather_rays;
        pm.use_irradiance_cache = s.irradiance_cache;
        pm.irradiance_cache.accuracy = s.cache_accuracy;
        pm.irradiance_cache.gradients = s.cache_gradients;
        pm.irradiance_cache.seed = s.seed;
        pm.irradiance_cache.threads = s.threads;
        auto photon_map = std::make_unique<PhotonMapIntegrator>(*rs, maps, pm);
        photon_map->build_cache(*camera, &out.cache);
        integrator = std::move(photon_map);
    } else {
        return Error{"stress render: unknown integrator '" + s.integrator + "'"};
    }
    TileSettings tiles;
    tiles.tile_size = 16;
    tiles.samples_per_pixel = s.spp;
    tiles.seed = s.seed;
    tiles.threads = s.threads;
    TileRenderResult rendered = render_tiles(*integrator, *camera, tiles);
    out.image = std::move(rendered.layers.beauty);
    out.counters = rendered.counters;
    return out;
}

inline Expected<StressRender> render_scene(Scene scene, const StressRenderSettings& s) {
    return render_scene(std::make_shared<const Scene>(std::move(scene)), s);
}

/// The materials of make_room, for callers that add their own meshes.
struct RoomMaterials {
    uint32_t white = 0;
    uint32_t red = 0;
    uint32_t light = 0;
};

struct RoomOptions {
    Color light_radiance{8.0f};
    bool light = true;         // the ceiling light (else the room is dark unless `extra` lights it)
    bool inward_walls = true;  // walls facing the inside (false: their back faces are seen)
};

inline Material lambertian_material(std::string name, const Color& albedo) {
    Material m;
    m.name = std::move(name);
    m.base_color = albedo;
    m.metallic = 0.0f;
    m.roughness = 1.0f;
    m.specular = 0.0f;  // purely Lambertian
    return m;
}

/// A small closed test room seen from inside: white walls [-1, 1] x [0, 2] x [-1, 1], a red block
/// on the floor, a 0.6 x 0.6 light facing down just under the ceiling. `extra` may add meshes,
/// lights or cameras before the scene is built; the room's camera is added last.
inline Expected<Scene> make_room(
    const RoomOptions& options = {},
    const std::function<Status(SceneBuilder&, const RoomMaterials&)>& extra = {}) {
    SceneBuilder builder("stress-room");
    RoomMaterials m;
    m.white = builder.add_material(lambertian_material("white", Color(0.7f)));
    m.red = builder.add_material(lambertian_material("red", Color(0.7f, 0.15f, 0.1f)));
    Material light = lambertian_material("light", Color(0.0f));
    light.emission = options.light_radiance;
    m.light = builder.add_material(light);
    MeshData walls = make_box(Vec3(-1.0f, 0.0f, -1.0f), Vec3(1.0f, 2.0f, 1.0f));
    if (options.inward_walls) flip_orientation(walls);
    if (Status s = add_mesh(builder, walls, m.white); !s) return s.error();
    if (Status s =
            add_mesh(builder, make_box(Vec3(-0.6f, 0.0f, -0.5f), Vec3(-0.1f, 0.7f, 0.0f)), m.red);
        !s)
        return s.error();
    if (options.light) {
        const MeshData quad = make_quad(Vec3(-0.3f, 1.98f, -0.3f), Vec3(0.6f, 0.0f, 0.0f),
                                        Vec3(0.0f, 0.0f, 0.6f), Vec3(0.0f, -1.0f, 0.0f));
        if (Status s = add_mesh(builder, quad, m.light); !s) return s.error();
    }
    if (extra) {
        if (Status s = extra(builder, m); !s) return s.error();
    }
    CameraDesc camera;
    camera.name = "room";
    camera.position = Vec3(0.0f, 1.0f, 0.95f);
    camera.look_at = Vec3(0.0f, 0.7f, -1.0f);
    camera.vfov_deg = 70.0f;
    builder.add_camera(camera);
    return builder.build();
}

/// Relative MSE of `image` against `reference` (both must have the same size).
inline double relative_mse(const Image& image, const Image& reference) {
    auto e = compare_images(image, reference);
    return e ? e->relative_mse : std::numeric_limits<double>::infinity();
}

inline float median_luminance(const Image& image) {
    if (image.empty()) return 0.0f;
    std::vector<float> values;
    values.reserve(image.pixel_count());
    for (const Color& c : image.pixels()) values.push_back(luminance(c));
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
}

/// Relative MSE of two renders that may differ by noise only (other random directions, paths that
/// diverged): fireflies are clamped at 4 times the reference's median luminance and 4 x 4 pixel
/// blocks averaged first. Systematic differences (a shadow, a leak, a bias) still count fully.
inline double block_relative_mse(const Image& image, const Image& reference) {
    const float cap = 4.0f * median_luminance(reference);
    const auto clamp = [cap](Image im) {
        for (Color& c : im.pixels()) c = glm::min(c, Color(cap));
        return im;
    };
    auto e = compare_images(downsample(clamp(image), 4), downsample(clamp(reference), 4));
    return e ? e->relative_mse : std::numeric_limits<double>::infinity();
}

/// (mean(image) - mean(reference)) / mean(reference), over all channels.
inline double mean_bias(const Image& image, const Image& reference) {
    auto e = compare_images(image, reference);
    return e ? e->mean_bias : std::numeric_limits<double>::infinity();
}

/// Number of pixels with a NaN or infinite channel.
inline size_t non_finite_pixels(const Image& image) {
    return static_cast<size_t>(std::count_if(image.pixels().begin(), image.pixels().end(),
                                             [](const Color& c) { return !is_finite(c); }));
}

/// Number of pixels with a negative channel (radiance is never negative).
inline size_t negative_pixels(const Image& image) {
    return static_cast<size_t>(
        std::count_if(image.pixels().begin(), image.pixels().end(),
                      [](const Color& c) { return min_component(c) < 0.0f; }));
}

inline double mean_luminance(const Image& image, std::optional<PixelRect> region = std::nullopt) {
    const PixelRect r = region ? region->intersect(image.bounds()) : image.bounds();
    double sum = 0.0;
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) sum += luminance(image.at(x, y));
    return r.empty() ? 0.0 : sum / static_cast<double>(r.area());
}

inline double max_luminance(const Image& image) {
    double m = 0.0;
    for (const Color& c : image.pixels()) m = std::max(m, static_cast<double>(luminance(c)));
    return m;
}

/// Pixels where a bright, small feature is legitimate rather than a firefly, or where an edge meets
/// the void: the camera path through some point of the pixel (centre and four inner points)
/// reaches an emitter directly or through ideal specular bounces (a light, its reflection in a
/// mirror, its image through glass), or leaves the scene. Dilated by one pixel, since a
/// neighbouring pixel's samples may still catch the feature.
inline std::vector<uint8_t> legitimately_bright_pixels(const RenderScene& rs,
                                                       const Camera& camera) {
    const int w = camera.width(), h = camera.height();
    std::vector<uint8_t> hit(static_cast<size_t>(w) * h, 0);
    // Follows every delta lobe (at most 2 per bounce) up to a depth of 6.
    const std::function<bool(const Ray&, int)> reaches_light_or_void = [&](const Ray& ray,
                                                                           int depth) {
        const std::optional<Hit> found = rs.tracer->intersect(ray);
        if (!found) return true;
        const SurfaceInteraction si = make_interaction(*rs.scene, *found, ray.direction);
        const Vec3 wo = -ray.direction;
        if (!is_black(rs.lights->emitted_radiance(si, wo))) return true;
        const Bsdf bsdf = make_bsdf(rs, si, wo);
        if (!bsdf.has_delta() || depth >= 6) return false;
        std::array<BsdfSample, 2> lobes;
        const int count = bsdf.delta_lobes(wo, lobes);
        for (int i = 0; i < count; ++i) {
            if (!is_black(lobes[i].weight) &&
                reaches_light_or_void(spawn_ray(rs, si, lobes[i].wi), depth + 1))
                return true;
        }
        return false;
    };
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            for (const Vec2 offset :
                 {Vec2(0.5f), Vec2(0.1f), Vec2(0.9f, 0.1f), Vec2(0.1f, 0.9f), Vec2(0.9f)}) {
                const CameraRay ray = camera.generate_ray(static_cast<float>(x) + offset.x,
                                                          static_cast<float>(y) + offset.y);
                if (reaches_light_or_void(Ray{ray.origin, ray.direction}, 0)) {
                    hit[static_cast<size_t>(y) * w + x] = 1;
                    break;
                }
            }
        }
    }
    std::vector<uint8_t> dilated(hit.size(), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx >= 0 && ny >= 0 && nx < w && ny < h &&
                        hit[static_cast<size_t>(ny) * w + nx])
                        dilated[static_cast<size_t>(y) * w + x] = 1;
                }
    return dilated;
}

/// Isolated outliers ("fireflies"): pixels whose luminance exceeds `k` times the median of their
/// 3x3 neighbourhood (the pixel included) and an absolute floor `min_luminance`. Pixels flagged
/// in `exclude` (e.g. legitimately_bright_pixels) are not counted. Border pixels use the
/// neighbours inside the image.
struct OutlierStatistics {
    size_t outliers = 0;
    size_t pixels = 0;         // pixels examined (not excluded)
    double worst_ratio = 0.0;  // largest luminance / neighbourhood median among examined pixels
    double fraction() const {
        return pixels ? static_cast<double>(outliers) / static_cast<double>(pixels) : 0.0;
    }
};

inline OutlierStatistics isolated_outliers(const Image& image,
                                           const std::vector<uint8_t>& exclude = {},
                                           double k = 10.0, double min_luminance = 1e-3) {
    OutlierStatistics stats;
    std::vector<double> window;
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            if (!exclude.empty() && exclude[static_cast<size_t>(y) * image.width() + x]) continue;
            window.clear();
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx >= 0 && ny >= 0 && nx < image.width() && ny < image.height())
                        window.push_back(luminance(image.at(nx, ny)));
                }
            std::nth_element(window.begin(), window.begin() + window.size() / 2, window.end());
            const double median = window[window.size() / 2];
            const double value = luminance(image.at(x, y));
            ++stats.pixels;
            if (median > 0.0) stats.worst_ratio = std::max(stats.worst_ratio, value / median);
            if (value > min_luminance && value > k * median) ++stats.outliers;
        }
    }
    return stats;
}

/// The settings of a small stress render with `integrator` (path, photon-map or direct).
inline StressRenderSettings settings_for(const std::string& integrator) {
    StressRenderSettings s;
    s.integrator = integrator;
    return s;
}

/// Renders a scene that must build and render, expecting every pixel finite and non-negative.
inline Image render_ok(Expected<Scene> scene, const StressRenderSettings& settings) {
    EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().message);
    if (!scene) return {};
    auto rendered = render_scene(std::move(scene).value(), settings);
    EXPECT_TRUE(rendered.has_value()) << (rendered ? "" : rendered.error().message);
    if (!rendered) return {};
    EXPECT_EQ(non_finite_pixels(rendered->image), 0u);
    EXPECT_EQ(negative_pixels(rendered->image), 0u);
    return rendered->image;
}

}  // namespace photond::stress
