// The tile renderer: splits the frame (or a region of it) into tiles, renders them in parallel on
// a oneTBB arena, and reports each finished tile. Every pixel sample draws its random numbers from
// a stream derived from (seed, pixel, sample), so the image is bit-identical for any thread count
// and any tile order.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "core/camera/camera.h"
#include "core/image/image.h"
#include "core/integrators/integrator.h"
#include "core/util/work_log.h"
#include "core/render/aov.h"

namespace photond {

struct TileSettings {
    int tile_size = 32;
    int samples_per_pixel = 4;
    uint64_t seed = 1;
    int threads = 0;                     // 0 = every core
    std::optional<PixelRect> region;     // render only this part of the frame (others stay black)
    std::vector<Aov> aovs;               // layers beside the beauty pass, in this order
    WorkLog* work_log = nullptr;         // set: each tile's duration, one phase (bench/schedule_simulation.cpp)
};

/// The tiles covering `area`, row by row.
std::vector<PixelRect> make_tiles(const PixelRect& area, int tile_size);

struct TileEvent {
    PixelRect rect;
    size_t tiles_done = 0;
    size_t tiles_total = 0;
    bool restored = false;  // filled by RenderCallbacks::restore_tile, not rendered
    /// A tile of the progressive preview (core/render/preview_renderer.h), which the final tile
    /// of the same rectangle replaces later; tiles_done and tiles_total count preview tiles then.
    bool preview = false;
};

struct RenderCallbacks {
    /// Called after each tile, from the worker thread that finished it (calls may overlap);
    /// `frame` holds the finished tile's pixels in every layer (and other tiles' in any state).
    std::function<void(const TileEvent&, const ImageLayers& frame)> on_tile;
    /// Called before each tile renders, from the worker thread that would render it (calls may
    /// overlap): when it fills `rect` of `frame` (every layer) with the tile's pixels from an
    /// earlier, interrupted run of the same render and returns true, the tile is not rendered again.
    std::function<bool(const PixelRect& rect, ImageLayers& frame)> restore_tile;
    /// Checked before each tile starts: when set, the remaining tiles are skipped.
    const std::atomic<bool>* cancel = nullptr;
};

struct TileRenderResult {
    ImageLayers layers;  // the beauty pass and TileSettings::aovs, named by aov_name
    RayCounters counters;
    size_t tiles_done = 0;      // rendered or restored
    size_t tiles_restored = 0;  // of those, filled by RenderCallbacks::restore_tile
    size_t tiles_total = 0;
    bool cancelled = false;
};

/// Renders with `integrator` through `camera` (whose size is the frame's). Each pixel of each
/// layer is the average of its samples (an AOV's value per sample: aov_value).
TileRenderResult render_tiles(const Integrator& integrator, const Camera& camera,
                              const TileSettings& settings, const RenderCallbacks& callbacks = {});

}  // namespace photond
