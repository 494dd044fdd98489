// Fireflies: isolated outlier pixels of the built-in scenes rendered with photon-map at modest
// settings (64 x 64, 4 spp, 20000 global and 10000 caustic photons, 64 gather rays, irradiance
// cache a = 0.25 with gradients, as the presets use them).
//
// Statistic (stress_support.h, isolated_outliers): a pixel is an outlier when its luminance
// exceeds 10 times the median of its 3x3 neighbourhood (and 1e-3). Pixels where a small bright
// feature is legitimate are not examined: those whose camera path reaches a light directly or
// through ideal specular bounces (the light, its reflection in the mirror ball, its image through
// the glass) or leaves the scene (silhouettes against the void), dilated by one pixel. The
// furnace is left out: every one of its pixels sees an emitter.
#include <gtest/gtest.h>

#include <string>

#include "core/scene/builtin_scenes.h"
#include "tests/stress/stress_support.h"

namespace photond {
namespace {

// Measured outliers among the examined pixels (64 x 64):
//   cornell-box-diffuse 0 of 3389; caustic 2 of 3592 (the two pixels of the point light's
//   focused caustic, a genuine feature); caustic-area 4 of 3592 (its caustic's core and three
//   stray caustic photons); cornell-box 0 of 2828 without cache gradients, but 17 with them: the
//   box's corners, where cache records gathered on the edge line itself carry translation
//   gradients 1e4 times their irradiance per record radius (see the report) and the extrapolated
//   irradiance reaches 500 times its neighbours'.
// Largest luminance / neighbourhood median among examined pixels: 26 (caustic-area), 9255 in
// cornell-box with gradients.
constexpr double kMaxOutlierFraction = 0.002;  // 7 of 3592 pixels
constexpr double kMaxWorstRatio = 100.0;

class Fireflies : public testing::TestWithParam<std::string> {};

TEST_P(Fireflies, FewIsolatedOutliersWithPhotonMapping) {
    auto scene = std::make_shared<const Scene>(make_builtin_scene(GetParam()).value());
    stress::StressRenderSettings settings;
    settings.integrator = "photon-map";
    settings.width = settings.height = 64;
    auto rendered = stress::render_scene(scene, settings);
    ASSERT_TRUE(rendered.has_value()) << rendered.error().message;
    const Image& image = rendered->image;
    ASSERT_EQ(stress::non_finite_pixels(image), 0u);
    ASSERT_EQ(stress::negative_pixels(image), 0u);

    auto rs = RenderScene::create(stress::shared_device(), scene).value();
    const Camera camera =
        Camera::create(scene->cameras.front(), image.width(), image.height()).value();
    const std::vector<uint8_t> legitimate = stress::legitimately_bright_pixels(*rs, camera);
    const stress::OutlierStatistics stats = stress::isolated_outliers(image, legitimate);
    // Most of the frame is examined, so the statistic means something.
    ASSERT_GT(stats.pixels, image.pixel_count() / 2);
    EXPECT_LE(stats.fraction(), kMaxOutlierFraction)
        << stats.outliers << " outliers of " << stats.pixels;
    EXPECT_LT(stats.worst_ratio, kMaxWorstRatio);
}

TEST(FireflyStatistic, FindsInjectedFirefliesAndIgnoresSmoothImages) {
    // A smooth ramp has none; single pixels raised 20-fold are each found; a bright stripe three
    // pixels wide (a feature, not a firefly) is not. (The corners of a small bright block would
    // be: 4 of their 9 neighbourhood pixels are bright, hence the mask of legitimate features.)
    Image image(32, 32);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x)
            image.at(x, y) = Color(0.1f + 0.01f * static_cast<float>(x + y));
    EXPECT_EQ(stress::isolated_outliers(image).outliers, 0u);
    Image fireflies = image;
    fireflies.at(5, 7) *= 20.0f;
    fireflies.at(20, 20) *= 20.0f;
    for (int y = 0; y < 32; ++y)
        for (int x = 25; x < 28; ++x) fireflies.at(x, y) *= 20.0f;
    EXPECT_EQ(stress::isolated_outliers(fireflies).outliers, 2u);
    std::vector<uint8_t> exclude(image.pixel_count(), 0);
    exclude[7 * 32 + 5] = 1;
    EXPECT_EQ(stress::isolated_outliers(fireflies, exclude).outliers, 1u);
}

INSTANTIATE_TEST_SUITE_P(BuiltinScenes, Fireflies,
                         testing::Values("cornell-box", "cornell-box-diffuse", "caustic",
                                         "caustic-area"),
                         [](const testing::TestParamInfo<std::string>& info) {
                             std::string name = info.param;
                             for (char& c : name)
                                 if (c == '-') c = '_';
                             return name;
                         });

}  // namespace
}  // namespace photond
