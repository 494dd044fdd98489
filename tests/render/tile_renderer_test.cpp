// The tile renderer: bit-identical output for any thread count, finite pixels, regions,
// progress and cancellation.
#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>

#include "core/image/exr_io.h"
#include "core/integrators/path.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

struct CornellFixture {
    std::shared_ptr<const RenderScene> scene;
    std::unique_ptr<PathIntegrator> integrator;
    Camera camera;
};

const CornellFixture& cornell() {
    static CornellFixture f = [] {
        auto device = EmbreeDevice::create().value();
        auto scene = std::make_shared<const Scene>(make_builtin_scene("cornell-box").value());
        CornellFixture f{RenderScene::create(device, scene).value(), nullptr,
                         Camera::create(scene->cameras.at(0), 48, 40).value()};
        f.integrator = std::make_unique<PathIntegrator>(f.scene);
        return f;
    }();
    return f;
}

TileSettings small_settings(int threads) {
    TileSettings s;
    s.tile_size = 16;
    s.samples_per_pixel = 4;
    s.seed = 42;
    s.threads = threads;
    return s;
}

TEST(TileRenderer, MakeTilesCoversTheAreaOnce) {
    const PixelRect area{3, 5, 70, 41};
    const auto tiles = make_tiles(area, 16);
    int64_t covered = 0;
    for (const PixelRect& t : tiles) {
        EXPECT_TRUE(area.contains(t));
        covered += t.area();
    }
    EXPECT_EQ(covered, area.area());
    EXPECT_EQ(tiles.size(), 5u * 3u);
}

TEST(TileRenderer, BitIdenticalForAnyThreadCount) {
    const auto& f = cornell();
    const TileRenderResult one = render_tiles(*f.integrator, f.camera, small_settings(1));
    const TileRenderResult two = render_tiles(*f.integrator, f.camera, small_settings(2));
    const TileRenderResult seven = render_tiles(*f.integrator, f.camera, small_settings(7));
    EXPECT_TRUE(one.layers.beauty == two.layers.beauty);
    EXPECT_TRUE(one.layers.beauty == seven.layers.beauty);
    EXPECT_EQ(one.counters.rays, two.counters.rays);
    ImageLayers a, b;
    a.beauty = one.layers.beauty;
    b.beauty = two.layers.beauty;
    EXPECT_EQ(encode_exr(a).value(), encode_exr(b).value());
    // A different seed gives a different image: the comparison above can fail.
    TileSettings other = small_settings(2);
    other.seed = 43;
    EXPECT_FALSE(render_tiles(*f.integrator, f.camera, other).layers.beauty == one.layers.beauty);
}

TEST(TileRenderer, EveryPixelFiniteAndNonNegative) {
    const auto& f = cornell();
    const TileRenderResult r = render_tiles(*f.integrator, f.camera, small_settings(2));
    double sum = 0.0;
    for (const Color& c : r.layers.beauty.pixels()) {
        ASSERT_TRUE(is_finite(c));
        ASSERT_GE(min_component(c), 0.0f);
        sum += average(c);
    }
    EXPECT_GT(sum, 0.0);
}

TEST(TileRenderer, RegionRendersOnlyItsPixelsAndMatchesTheFullFrame) {
    const auto& f = cornell();
    const TileRenderResult full = render_tiles(*f.integrator, f.camera, small_settings(2));
    TileSettings s = small_settings(2);
    s.region = PixelRect{10, 7, 30, 33};
    const TileRenderResult part = render_tiles(*f.integrator, f.camera, s);
    for (int y = 0; y < f.camera.height(); ++y) {
        for (int x = 0; x < f.camera.width(); ++x) {
            if (s.region->contains(x, y)) {
                ASSERT_EQ(part.layers.beauty.at(x, y), full.layers.beauty.at(x, y));
            } else {
                ASSERT_EQ(part.layers.beauty.at(x, y), Color(0.0f));
            }
        }
    }
}

TEST(TileRenderer, ProgressReportsEveryTileAndCancelStops) {
    const auto& f = cornell();
    std::atomic<size_t> events{0};
    RenderCallbacks callbacks;
    callbacks.on_tile = [&](const TileEvent& e, const ImageLayers&) {
        ++events;
        EXPECT_LE(e.tiles_done, e.tiles_total);
    };
    const TileRenderResult r = render_tiles(*f.integrator, f.camera, small_settings(2), callbacks);
    EXPECT_EQ(events.load(), r.tiles_total);
    EXPECT_FALSE(r.cancelled);

    std::atomic<bool> cancel{false};
    RenderCallbacks cancelling;
    cancelling.cancel = &cancel;
    cancelling.on_tile = [&](const TileEvent& e, const ImageLayers&) {
        if (e.tiles_done >= 2) cancel = true;
    };
    TileSettings one_thread = small_settings(1);
    const TileRenderResult c = render_tiles(*f.integrator, f.camera, one_thread, cancelling);
    EXPECT_TRUE(c.cancelled);
    EXPECT_EQ(c.tiles_done, 2u);
}

TEST(TileRenderer, RestoredTilesAreNotRenderedAndTheImageIsBitIdentical) {
    // What a resumed job does: tiles kept by an interrupted run are filled in, the rest rendered.
    const auto& f = cornell();
    const TileRenderResult whole = render_tiles(*f.integrator, f.camera, small_settings(2));
    const std::vector<PixelRect> tiles = make_tiles(whole.layers.beauty.bounds(), 16);
    ASSERT_EQ(tiles.size(), 9u);
    std::mutex mutex;
    std::vector<PixelRect> restored_seen, rendered_seen;
    RenderCallbacks callbacks;
    callbacks.restore_tile = [&](const PixelRect& rect, ImageLayers& frame) {
        const size_t index = static_cast<size_t>(std::find(tiles.begin(), tiles.end(), rect) - tiles.begin());
        if (index % 2 != 0) return false;  // "not kept": rendered
        frame.beauty.paste(whole.layers.beauty.copy_rect(rect), rect.x0, rect.y0);
        return true;
    };
    callbacks.on_tile = [&](const TileEvent& event, const ImageLayers&) {
        std::lock_guard lock(mutex);
        (event.restored ? restored_seen : rendered_seen).push_back(event.rect);
    };
    const TileRenderResult resumed = render_tiles(*f.integrator, f.camera, small_settings(2), callbacks);
    EXPECT_TRUE(resumed.layers.beauty == whole.layers.beauty);
    EXPECT_EQ(resumed.tiles_done, 9u);
    EXPECT_EQ(resumed.tiles_restored, 5u);
    EXPECT_EQ(restored_seen.size(), 5u);
    EXPECT_EQ(rendered_seen.size(), 4u);
    // Only the rendered tiles traced rays.
    EXPECT_GT(resumed.counters.rays, 0u);
    EXPECT_LT(resumed.counters.rays, whole.counters.rays * 6 / 10);
}

}  // namespace
}  // namespace photond
