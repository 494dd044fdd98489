#include "core/render/tile_renderer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <mutex>

#include "core/render/aov_sample.h"

namespace photond {

namespace {
// Distinguishes the pixel sample pattern's hash from the samples' random streams.
constexpr uint64_t kPatternStream = 0x7061747465726e00ull;
}  // namespace

std::vector<PixelRect> make_tiles(const PixelRect& area, int tile_size) {
    std::vector<PixelRect> tiles;
    const int size = std::max(tile_size, 1);
    for (int y = area.y0; y < area.y1; y += size) {
        for (int x = area.x0; x < area.x1; x += size) {
            tiles.push_back({x, y, std::min(x + size, area.x1), std::min(y + size, area.y1)});
        }
    }
    return tiles;
}

TileRenderResult render_tiles(const Integrator& integrator, const Camera& camera,
                              const TileSettings& settings, const RenderCallbacks& callbacks) {
    const int width = camera.width(), height = camera.height();
    const PixelRect frame{0, 0, width, height};
    const PixelRect area = settings.region ? settings.region->intersect(frame) : frame;
    const std::vector<PixelRect> tiles = make_tiles(area, settings.tile_size);
    const int spp = std::max(settings.samples_per_pixel, 1);
    const float texture_scale = texture_footprint_scale(spp);

    TileRenderResult result;
    ImageLayers& layers = result.layers;
    layers.beauty = Image(width, height);
    for (Aov aov : settings.aovs) layers.aovs.emplace_back(std::string(aov_name(aov)), Image(width, height));
    const bool first_surface_wanted =
        std::any_of(settings.aovs.begin(), settings.aovs.end(), [](Aov aov) { return needs_first_surface(aov); });
    const size_t aov_count = settings.aovs.size();
    result.tiles_total = tiles.size();
    std::atomic<size_t> tiles_done{0};
    std::atomic<size_t> tiles_restored{0};
    std::atomic<bool> cancelled{false};
    tbb::enumerable_thread_specific<RayCounters> counters;

    auto render_tile = [&](const PixelRect& tile) {
        enable_flush_denormals();
        RayCounters& local = counters.local();
        std::vector<DVec3> aov_sums(aov_count);
        for (int y = tile.y0; y < tile.y1; ++y) {
            for (int x = tile.x0; x < tile.x1; ++x) {
                const uint64_t pixel = static_cast<uint64_t>(y) * static_cast<uint64_t>(width) + x;
                DVec3 sum(0.0);
                std::fill(aov_sums.begin(), aov_sums.end(), DVec3(0.0));
                // The pixel's sample pattern (never 0, which means "none").
                const uint64_t pattern_seed = hash_indices(settings.seed, pixel, kPatternStream) | 1u;
                for (int s = 0; s < spp; ++s) {
                    Rng rng = Rng::for_stream(settings.seed, pixel, static_cast<uint64_t>(s));
                    SampleContext context{rng, local, pattern_seed, static_cast<uint32_t>(s), static_cast<uint32_t>(spp)};
                    const Vec2 jitter = context.next_2d();
                    CameraRay ray = camera.generate_ray(static_cast<float>(x) + jitter.x,
                                                        static_cast<float>(y) + jitter.y);
                    ray.texture_footprint_scale = texture_scale;
                    const RadianceParts parts = integrator.radiance_parts(ray, context);
                    const Color& L = parts.total;
                    // A non-finite sample (a numerical failure) is dropped rather than poisoning
                    // the pixel; every pixel of the output stays finite.
                    if (!is_finite(L)) continue;
                    sum += DVec3(L);
                    if (aov_count == 0) continue;
                    // After the sample's own draws: the beauty pass is the same with or without AOVs.
                    const FirstSurface surface =
                        first_surface_wanted ? first_surface(integrator.scene(), ray, local) : FirstSurface{};
                    for (size_t a = 0; a < aov_count; ++a) {
                        const Color value = aov_value(settings.aovs[a], parts, surface);
                        if (is_finite(value)) aov_sums[a] += DVec3(value);
                    }
                }
                layers.beauty.at(x, y) = Color(sum / static_cast<double>(spp));
                for (size_t a = 0; a < aov_count; ++a)
                    layers.aovs[a].second.at(x, y) = Color(aov_sums[a] / static_cast<double>(spp));
            }
        }
    };

    WorkLog::Phase* phase = nullptr;
    if (settings.work_log) {
        settings.work_log->phases.push_back({"tiles", std::vector<double>(tiles.size(), 0.0), 0.0});
        phase = &settings.work_log->phases.back();
    }
    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, tiles.size(), 1),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t i = range.begin(); i != range.end(); ++i) {
                    if ((callbacks.cancel && callbacks.cancel->load(std::memory_order_relaxed)) ||
                        cancelled.load(std::memory_order_relaxed)) {
                        cancelled = true;
                        return;
                    }
                    const bool restored = callbacks.restore_tile && callbacks.restore_tile(tiles[i], layers);
                    if (restored)
                        tiles_restored.fetch_add(1);
                    else if (phase) {
                        const auto start = std::chrono::steady_clock::now();
                        render_tile(tiles[i]);
                        phase->item_seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                    } else {
                        render_tile(tiles[i]);
                    }
                    const size_t done = tiles_done.fetch_add(1) + 1;
                    if (callbacks.on_tile) callbacks.on_tile({tiles[i], done, tiles.size(), restored}, layers);
                }
            },
            tbb::simple_partitioner());
    });
    for (const RayCounters& c : counters) result.counters += c;
    result.tiles_done = tiles_done.load();
    result.tiles_restored = tiles_restored.load();
    result.cancelled = cancelled.load();
    return result;
}

}  // namespace photond
