#include "core/render/preview_renderer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/render/aov_sample.h"

namespace photond {
namespace {

// Distinguishes the preview's random streams from the final render's (seed, pixel, sample).
constexpr uint64_t kPreviewStream = 0x70726576696577ull;

int blocks(int length, int stride) { return (length + stride - 1) / stride; }

/// Where pixel centre `x` lies between the block centres of one axis: the lower block's index
/// and the weight of the next one (clamped at the area's edges).
struct Lerp {
    int i0 = 0;
    int i1 = 0;
    float t = 0.0f;
};

Lerp lerp_at(int pixel, int origin, int stride, int count) {
    const float u = (static_cast<float>(pixel - origin) + 0.5f) / static_cast<float>(stride) - 0.5f;
    const float clamped = std::clamp(u, 0.0f, static_cast<float>(count - 1));
    Lerp l;
    l.i0 = std::min(static_cast<int>(clamped), count - 1);
    l.i1 = std::min(l.i0 + 1, count - 1);
    l.t = clamped - static_cast<float>(l.i0);
    return l;
}

}  // namespace

int preview_stride(const PixelRect& area, int64_t max_samples) {
    int stride = kMinPreviewStride;
    const int64_t cap = std::max<int64_t>(max_samples, 1);
    while (stride < std::max(area.width(), area.height()) &&
           int64_t(blocks(area.width(), stride)) * blocks(area.height(), stride) > cap)
        ++stride;
    return stride;
}

PreviewResult render_preview(const Integrator& integrator, const Camera& camera, const PreviewSettings& settings,
                             const RenderCallbacks& callbacks) {
    const int width = camera.width(), height = camera.height();
    const PixelRect frame{0, 0, width, height};
    const PixelRect area = settings.region ? settings.region->intersect(frame) : frame;
    PreviewResult result;
    result.layers.beauty = Image(width, height);
    for (Aov aov : settings.aovs) result.layers.aovs.emplace_back(std::string(aov_name(aov)), Image(width, height));
    if (area.empty()) return result;

    const int stride = preview_stride(area, settings.max_samples);
    const int nx = blocks(area.width(), stride), ny = blocks(area.height(), stride);
    const size_t layer_count = 1 + settings.aovs.size();
    const bool first_surface_wanted =
        std::any_of(settings.aovs.begin(), settings.aovs.end(), [](Aov aov) { return needs_first_surface(aov); });
    // The samples of every layer, block by block: samples[(j * nx + i) * layer_count + layer].
    std::vector<Color> samples(size_t(nx) * size_t(ny) * layer_count, Color(0.0f));
    tbb::enumerable_thread_specific<RayCounters> counters;
    std::atomic<bool> cancelled{false};
    const auto is_cancelled = [&] {
        return cancelled.load(std::memory_order_relaxed) ||
               (callbacks.cancel && callbacks.cancel->load(std::memory_order_relaxed));
    };

    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, ny, 1), [&](const tbb::blocked_range<int>& rows) {
            enable_flush_denormals();
            RayCounters& local = counters.local();
            for (int j = rows.begin(); j != rows.end(); ++j) {
                if (is_cancelled()) {
                    cancelled = true;
                    return;
                }
                for (int i = 0; i < nx; ++i) {
                    const float x = static_cast<float>(area.x0) + (static_cast<float>(i) + 0.5f) * stride;
                    const float y = static_cast<float>(area.y0) + (static_cast<float>(j) + 0.5f) * stride;
                    const uint64_t block = static_cast<uint64_t>(j) * static_cast<uint64_t>(nx) + i;
                    Rng rng = Rng::for_stream(settings.seed, kPreviewStream, block);
                    SampleContext context{rng, local};
                    const CameraRay ray = camera.generate_ray(x, y);
                    const RadianceParts parts = integrator.radiance_parts(ray, context);
                    Color* out = &samples[block * layer_count];
                    // A non-finite sample (a numerical failure) is black rather than a hole.
                    out[0] = is_finite(parts.total) ? parts.total : Color(0.0f);
                    if (layer_count == 1) continue;
                    const FirstSurface surface =
                        first_surface_wanted ? first_surface(integrator.scene(), ray, local) : FirstSurface{};
                    for (size_t a = 0; a < settings.aovs.size(); ++a) {
                        const Color value = aov_value(settings.aovs[a], parts, surface);
                        out[1 + a] = is_finite(value) ? value : Color(0.0f);
                    }
                }
            }
        });
    });
    for (const RayCounters& c : counters) result.counters += c;
    result.stride = stride;
    result.samples = size_t(nx) * size_t(ny);
    if (cancelled.load() || is_cancelled()) {
        result.cancelled = true;
        return result;
    }

    // Bilinear between the four block centres around each pixel centre.
    std::vector<Lerp> columns(static_cast<size_t>(area.width()));
    for (int x = area.x0; x < area.x1; ++x) columns[size_t(x - area.x0)] = lerp_at(x, area.x0, stride, nx);
    for (int y = area.y0; y < area.y1; ++y) {
        const Lerp row = lerp_at(y, area.y0, stride, ny);
        for (int x = area.x0; x < area.x1; ++x) {
            const Lerp& col = columns[size_t(x - area.x0)];
            const size_t s00 = (size_t(row.i0) * nx + col.i0) * layer_count;
            const size_t s10 = (size_t(row.i0) * nx + col.i1) * layer_count;
            const size_t s01 = (size_t(row.i1) * nx + col.i0) * layer_count;
            const size_t s11 = (size_t(row.i1) * nx + col.i1) * layer_count;
            for (size_t layer = 0; layer < layer_count; ++layer) {
                // a + (b - a) t: exact where the samples agree.
                const Color top = samples[s00 + layer] + (samples[s10 + layer] - samples[s00 + layer]) * col.t;
                const Color bottom = samples[s01 + layer] + (samples[s11 + layer] - samples[s01 + layer]) * col.t;
                const Color value = top + (bottom - top) * row.t;
                Image& image = layer == 0 ? result.layers.beauty : result.layers.aovs[layer - 1].second;
                image.at(x, y) = value;
            }
        }
    }

    const std::vector<PixelRect> tiles = make_tiles(area, settings.tile_size);
    for (size_t t = 0; t < tiles.size(); ++t) {
        if (callbacks.cancel && callbacks.cancel->load(std::memory_order_relaxed)) {
            result.cancelled = true;
            break;
        }
        TileEvent event;
        event.rect = tiles[t];
        event.tiles_done = t + 1;
        event.tiles_total = tiles.size();
        event.preview = true;
        if (callbacks.on_tile) callbacks.on_tile(event, result.layers);
        ++result.tiles;
    }
    return result;
}

}  // namespace photond
