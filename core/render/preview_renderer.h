// The progressive preview: a quick image of the whole frame (or region) shown before the final
// render's tiles, which replace it (README.md, "Progressive previews"). One camera sample at the
// centre of each stride x stride block of pixels, through the integrator's cheap preview form
// (Integrator::make_preview: the photon-map integrator reads the global map at the first hit
// instead of final gathering, so nothing waits for the irradiance-cache prepass); every pixel is
// interpolated bilinearly between the block centres around it.
//
// The preview draws from random streams of its own and changes nothing the final render reads:
// the final image is the same bytes with or without it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/camera/camera.h"
#include "core/image/image.h"
#include "core/integrators/integrator.h"
#include "core/render/aov.h"
#include "core/render/tile_renderer.h"

namespace photond {

struct PreviewSettings {
    /// The stride grows from kMinPreviewStride until the blocks number at most this many, so
    /// that the preview costs about the same at any image size (stride 5 at 512 x 512).
    int64_t max_samples = 105 * 105;
    int tile_size = 32;                // reported in the final render's tiles (make_tiles)
    uint64_t seed = 1;                 // the render's seed; the preview's streams are its own
    int threads = 0;                   // 0 = every core
    std::optional<PixelRect> region;   // preview only this part of the frame
    std::vector<Aov> aovs;             // layers beside the beauty pass, as TileSettings::aovs
};

inline constexpr int kMinPreviewStride = 2;

/// The block edge for `area`: the smallest stride >= kMinPreviewStride whose blocks
/// (ceil(w / stride) x ceil(h / stride)) number at most `max_samples`.
int preview_stride(const PixelRect& area, int64_t max_samples);

struct PreviewResult {
    ImageLayers layers;  // the frame's size; the area interpolated, the rest black
    RayCounters counters;
    int stride = 0;
    size_t samples = 0;     // camera samples taken (one per block)
    size_t tiles = 0;       // tiles reported through on_tile
    bool cancelled = false;
};

/// Renders the preview with `integrator` (pass Integrator::make_preview()'s, or the render's own
/// when that is null) and reports it through `callbacks.on_tile`, one call per tile of
/// make_tiles(area, tile_size) in that order, each with TileEvent::preview set, from the calling
/// thread once every pixel is interpolated. `callbacks.cancel` is checked between rows of blocks;
/// a cancelled preview reports no tile.
PreviewResult render_preview(const Integrator& integrator, const Camera& camera, const PreviewSettings& settings,
                             const RenderCallbacks& callbacks = {});

}  // namespace photond
