// The progressive preview (core/render/preview_renderer.h): its stride, every tile of the area
// reported once as a preview tile with the interpolated pixels, nothing outside a region,
// cancellation, and random streams of its own.
#include "core/render/preview_renderer.h"

#include <gtest/gtest.h>

#include <atomic>

#include "core/integrators/path.h"
#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

/// Radiance `value` along every ray: the preview must be `value` at every pixel of its area.
class ConstantIntegrator final : public Integrator {
public:
    ConstantIntegrator(std::shared_ptr<const RenderScene> scene, Color value) : scene_(std::move(scene)), value_(value) {}
    std::string_view name() const override { return "constant"; }
    const RenderScene& scene() const override { return *scene_; }
    RadianceParts radiance_parts(const CameraRay&, SampleContext&) const override {
        RadianceParts parts;
        parts.add_emission(value_);
        return parts;
    }

private:
    std::shared_ptr<const RenderScene> scene_;
    Color value_;
};

std::shared_ptr<const RenderScene> cornell() {
    static const std::shared_ptr<const RenderScene> scene = RenderScene::create(
        EmbreeDevice::create().value(), std::make_shared<const Scene>(make_builtin_scene("cornell-box").value())).value();
    return scene;
}

Camera camera(int width, int height) { return Camera::create(cornell()->scene->cameras.at(0), width, height).value(); }

TEST(PreviewRenderer, TheStrideKeepsTheSamplesUnderTheCap) {
    const int64_t cap = PreviewSettings{}.max_samples;
    EXPECT_EQ(preview_stride({0, 0, 512, 512}, cap), 5);  // 103 x 103 blocks
    EXPECT_EQ(preview_stride({0, 0, 64, 48}, cap), kMinPreviewStride);
    for (const PixelRect area : {PixelRect{0, 0, 4096, 4096}, PixelRect{0, 0, 1920, 1080}, PixelRect{7, 9, 333, 20}}) {
        const int s = preview_stride(area, cap);
        const auto blocks = [&](int stride) {
            return int64_t((area.width() + stride - 1) / stride) * ((area.height() + stride - 1) / stride);
        };
        EXPECT_LE(blocks(s), cap);
        if (s > kMinPreviewStride) {
            EXPECT_GT(blocks(s - 1), cap);  // the smallest that fits
        }
    }
}

TEST(PreviewRenderer, EveryTileOfTheRegionOnceAsAPreviewTileOfInterpolatedPixels) {
    const Color value(0.25f, 0.5f, 2.0f);
    const ConstantIntegrator integrator(cornell(), value);
    PreviewSettings settings;
    settings.tile_size = 16;
    settings.region = PixelRect{5, 3, 90, 61};
    settings.aovs = {Aov::Emission};
    settings.threads = 2;
    std::vector<PixelRect> reported;
    RenderCallbacks callbacks;
    callbacks.on_tile = [&](const TileEvent& event, const ImageLayers& frame) {
        EXPECT_TRUE(event.preview);
        EXPECT_FALSE(event.restored);
        EXPECT_EQ(event.tiles_done, reported.size() + 1);
        EXPECT_EQ(event.tiles_total, make_tiles(*settings.region, 16).size());
        // The tile's pixels are there when it is reported.
        EXPECT_EQ(frame.beauty.at(event.rect.x0, event.rect.y0), value);
        reported.push_back(event.rect);
    };
    const PreviewResult result = render_preview(integrator, camera(100, 70), settings, callbacks);
    EXPECT_FALSE(result.cancelled);
    EXPECT_EQ(reported, make_tiles(*settings.region, 16));
    EXPECT_EQ(result.tiles, reported.size());
    EXPECT_EQ(result.stride, kMinPreviewStride);
    EXPECT_EQ(result.samples, size_t(43 * 29));
    ASSERT_EQ(result.layers.aovs.size(), 1u);
    for (int y = 0; y < 70; ++y)
        for (int x = 0; x < 100; ++x) {
            const Color expected = settings.region->contains(x, y) ? value : Color(0.0f);
            ASSERT_EQ(result.layers.beauty.at(x, y), expected) << x << ", " << y;
            ASSERT_EQ(result.layers.aovs[0].second.at(x, y), expected) << x << ", " << y;
        }
}

TEST(PreviewRenderer, ACancelledPreviewReportsNoTile) {
    const ConstantIntegrator integrator(cornell(), Color(1.0f));
    std::atomic<bool> cancel{true};
    RenderCallbacks callbacks;
    size_t reported = 0;
    callbacks.on_tile = [&](const TileEvent&, const ImageLayers&) { ++reported; };
    callbacks.cancel = &cancel;
    const PreviewResult result = render_preview(integrator, camera(64, 64), PreviewSettings{}, callbacks);
    EXPECT_TRUE(result.cancelled);
    EXPECT_EQ(reported, 0u);
}

TEST(PreviewRenderer, ThePathTracersPreviewIsDeterministicAndNotBlack) {
    const PathIntegrator integrator(cornell());
    PreviewSettings settings;
    settings.threads = 1;
    const PreviewResult one = render_preview(integrator, camera(96, 64), settings);
    settings.threads = 3;
    const PreviewResult three = render_preview(integrator, camera(96, 64), settings);
    EXPECT_TRUE(one.layers.beauty == three.layers.beauty);  // streams by block, not by thread
    double sum = 0.0;
    for (const Color& c : one.layers.beauty.pixels()) sum += c.x + c.y + c.z;
    EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace photond
