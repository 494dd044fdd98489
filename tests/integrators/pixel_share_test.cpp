// Parts of a pixel's light that only a share of its samples evaluate (SampleContext::pixel_share):
// the glossy rays, by the glossy lobes' share of a point's reflectance, and the caustic estimate.
// The pixel's mean must stay what every sample evaluating them gives, for fewer rays and
// estimates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "core/integrators/photon_mapping.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"
#include "core/scene/shapes.h"
#include "tests/support/photon_fixtures.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;
using test_support::uncached_photon_map;

constexpr uint32_t kSpp = 16;

TEST(PixelShare, TheFirstSamplesTakeThePartAndTheWeightsSumToTheSampleCount) {
    Rng rng = Rng::for_stream(1, 0, 0);
    RayCounters counters;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (uint32_t n = 2; n <= 20; ++n) {
        for (const float fraction : {0.01f, 0.25f, 0.3f, 0.5f, 0.99f, 1.0f, 2.0f, 0.0f, -1.0f, nan}) {
            uint32_t taken = 0;
            double weights = 0.0;
            bool prefix = true;
            for (uint32_t s = 0; s < n; ++s) {
                const SampleContext context{rng, counters, 1, s, n};
                const PixelShare share = context.pixel_share(fraction);
                if (share.taken) {
                    prefix = prefix && taken == s;
                    ++taken;
                    weights += share.weight;
                }
            }
            const uint32_t expected =
                fraction >= 1.0f ? n : std::max(1u, static_cast<uint32_t>(std::ceil(std::max(fraction, 0.0f) * n)));
            EXPECT_EQ(taken, std::isnan(fraction) ? n : expected) << n << " samples, share " << fraction;
            EXPECT_TRUE(prefix) << "the pattern's first samples, the best stratified";
            EXPECT_NEAR(weights, n, 1e-4 * n) << n << " samples, share " << fraction;
        }
    }
    // Outside a pixel's samples (a gather, a preview's single sample) every context takes it whole.
    for (const uint32_t count : {0u, 1u}) {
        const SampleContext context{rng, counters, 1, 0, count};
        const PixelShare share = context.pixel_share(0.1f);
        EXPECT_TRUE(share.taken);
        EXPECT_EQ(share.weight, 1.0f);
    }
}

/// Each sample's radiance says what its context holds: red the weight of a quarter share where the
/// sample takes it, green the pixel's sample count, blue 1 where it takes the share.
class ShareProbe final : public Integrator {
public:
    explicit ShareProbe(std::shared_ptr<const RenderScene> scene) : scene_(std::move(scene)) {}
    std::string_view name() const override { return "share-probe"; }
    const RenderScene& scene() const override { return *scene_; }
    RadianceParts radiance_parts(const CameraRay&, SampleContext& context) const override {
        const PixelShare share = context.pixel_share(0.25f);
        RadianceParts parts;
        parts.add_direct(Color(share.taken ? share.weight : 0.0f, static_cast<float>(context.sample_count),
                               share.taken ? 1.0f : 0.0f));
        return parts;
    }

private:
    std::shared_ptr<const RenderScene> scene_;
};

// The tile renderer tells each sample its pixel's sample count: a quarter of a pixel's samples
// take a quarter share, and their weights make the pixel's whole.
TEST(PixelShare, TheTileRendererGivesEachSampleItsPixelsSampleCount) {
    const ShareProbe probe(make_render_scene(make_builtin_scene("cornell-box").value()));
    const Camera camera = Camera::create(probe.scene().scene->cameras.at(0), 8, 6).value();
    for (const int spp : {1, 5, 16}) {
        TileSettings tiles;
        tiles.samples_per_pixel = spp;
        tiles.tile_size = 4;
        const Image image = render_tiles(probe, camera, tiles).layers.beauty;
        const float taken = spp == 1 ? 1.0f : std::ceil(0.25f * spp) / static_cast<float>(spp);
        for (size_t p = 0; p < image.pixel_count(); ++p) {
            const Color c = image.pixels()[p];
            EXPECT_NEAR(c.x, 1.0f, 1e-6f) << spp << " spp";
            EXPECT_EQ(c.y, static_cast<float>(spp)) << spp << " spp";
            EXPECT_NEAR(c.z, taken, 1e-6f) << spp << " spp";
        }
    }
}

/// The radiance along make_ray(context)'s ray summed over `pixels` pixels of kSpp samples each,
/// every sample with its pixel's pattern; `in_pixel` false: the same samples as contexts outside
/// a pixel, which evaluate every part.
struct PixelSums {
    DVec3 total{0.0};
    DVec3 caustic{0.0};
    RayCounters counters;
    std::vector<double> pixel_means;  // the luminance of each pixel's mean
};
template <class MakeRay>
PixelSums sum_pixels(const Integrator& integrator, MakeRay make_ray, int pixels, bool in_pixel) {
    PixelSums sums;
    for (int p = 0; p < pixels; ++p) {
        DVec3 pixel(0.0);
        const uint64_t pattern = hash_indices(7, static_cast<uint64_t>(p)) | 1u;
        for (uint32_t s = 0; s < kSpp; ++s) {
            Rng rng = Rng::for_stream(3, static_cast<uint64_t>(p), s);
            SampleContext context{rng, sums.counters, pattern, s, in_pixel ? kSpp : 0u};
            const CameraRay ray = make_ray(context);
            const RadianceParts parts = integrator.radiance_parts(ray, context);
            pixel += DVec3(parts.total);
            sums.caustic += DVec3(parts.caustic);
        }
        sums.total += pixel;
        sums.pixel_means.push_back(luminance(Color(pixel / double(kSpp))));
    }
    return sums;
}

/// A pixel's mean with the share (the shared samples) against every sample evaluating every part,
/// over pixels whose samples draw the same numbers both ways: their difference is what the rays
/// the share leaves out would have added, noise of mean zero.
struct Comparison {
    double mean = 0.0;             // every sample evaluating every part
    double difference = 0.0;       // shared minus every, mean over the pixels
    double standard_error = 0.0;   // of that difference
    double rays_saved = 0.0;
};
template <class MakeRay>
Comparison compare_shared(const Integrator& integrator, MakeRay make_ray, int pixels) {
    const PixelSums shared = sum_pixels(integrator, make_ray, pixels, true);
    const PixelSums every = sum_pixels(integrator, make_ray, pixels, false);
    double sum = 0.0, sum2 = 0.0;
    for (int p = 0; p < pixels; ++p) {
        const double d = shared.pixel_means[p] - every.pixel_means[p];
        sum += d;
        sum2 += d * d;
    }
    Comparison c;
    c.mean = luminance(Color(every.total / double(pixels * kSpp)));
    c.difference = sum / pixels;
    c.standard_error = std::sqrt((sum2 / pixels - c.difference * c.difference) / (pixels - 1));
    // Rays: the camera's, a gather's (no cache) and the glossy rays, counted alike.
    c.rays_saved = double(every.counters.rays) - double(shared.counters.rays);
    return c;
}

/// A white plastic floor (a rough dielectric layer over a Lambertian base) reflecting a bright
/// square lamp, beside a grey box, under a uniform sky: the camera looks at the lamp's glossy
/// reflection, whose light comes by the light sample and the glossy ray (MIS).
TEST(PixelShare, GlossyRaysAtAShareOfThePixelsSamplesKeepItsMean) {
    SceneBuilder builder("plastic floor");
    Material plastic;
    plastic.base_color = Color(0.8f);
    plastic.metallic = 0.0f;
    plastic.roughness = 0.3f;
    const uint32_t floor = builder.add_material(plastic);
    const uint32_t grey = builder.add_material(lambertian(Color(0.5f)));
    Material lamp = lambertian(Color(0.0f));
    lamp.emission = Color(20.0f);
    const uint32_t emitter = builder.add_material(lamp);
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-4, 0, -4), Vec3(8, 0, 0), Vec3(0, 0, 8), Vec3(0, 1, 0)), floor).is_ok());
    ASSERT_TRUE(add_mesh(builder, make_box(Vec3(0.6f, 0.0f, -0.6f), Vec3(1.2f, 0.8f, 0.2f)), grey).is_ok());
    ASSERT_TRUE(add_mesh(builder, make_quad(Vec3(-0.5f, 1.5f, -1.5f), Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, -1, 0)), emitter).is_ok());
    // From (0, 1, 1.2) towards the floor's point under the lamp's mirror image; at 4 x 3 pixels
    // the middle pixel spans about 10 degrees, over which the floor's glossy share changes.
    CameraDesc view;
    view.position = Vec3(0.0f, 1.0f, 1.2f);
    view.look_at = Vec3(0.0f, 0.0f, -0.57f);
    view.vfov_deg = 30.0f;
    builder.add_camera(view);
    Scene scene = builder.build().value();
    scene.environment = Environment{};
    const auto rs = make_render_scene(std::move(scene));

    const auto photon_map = uncached_photon_map(rs, 20000, 0, 64);
    ASSERT_TRUE(photon_map);
    const PhotonMapIntegrator& integrator = *photon_map;
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 4, 3).value();
    const auto share_at = [&](const CameraRay& ray) {
        const std::optional<Hit> hit = rs->tracer->intersect(Ray{ray.origin, ray.direction});
        if (!hit) return -1.0f;
        const SurfaceInteraction si = make_interaction(*rs->scene, *hit, ray.direction);
        if (si.material != floor) return -1.0f;
        return make_bsdf(*rs, si, -ray.direction).glossy_share(-ray.direction);
    };

    // One ray through the pixel's centre: every sample shares one c.
    const CameraRay centre = camera.generate_ray(2.0f, 1.5f);
    const float share = share_at(centre);
    ASSERT_GT(share, 0.0f);
    ASSERT_LT(4.0f * share, 1.0f) << "the lobes' share must leave samples without rays";
    const auto expected_count = static_cast<uint32_t>(std::ceil(4.0f * share * kSpp));
    constexpr int kPixels = 600;
    const Comparison fixed = compare_shared(integrator, [&](SampleContext&) { return centre; }, kPixels);
    std::printf("one ray, glossy share %.3f: rays at %u of %u samples, %.0f rays saved; pixel mean %.4f, "
                "difference %+.5f (standard error %.5f)\n",
                share, expected_count, kSpp, fixed.rays_saved, fixed.mean, fixed.difference, fixed.standard_error);
    EXPECT_LT(std::abs(fixed.difference), 4.0 * fixed.standard_error + 1e-6 * fixed.mean);
    // Without the weight N / c the pixel loses (1 - c / N) of the rays' light, -1.8 % here: the
    // test must see a quarter of that.
    EXPECT_LT(4.0 * fixed.standard_error, 0.25 * 0.018 * fixed.mean);
    // The rays saved: one glossy ray at each sample the share leaves out (a few lobe samples
    // come out empty and trace none; a glossy ray landing close to the box traces a short-ray
    // bounce more).
    const double left_out = double(kPixels) * (kSpp - expected_count);
    EXPECT_GT(fixed.rays_saved, 0.9 * left_out);
    EXPECT_LT(fixed.rays_saved, 1.5 * left_out);

    // The samples spread over the pixel, as the tile renderer draws them: c differs from
    // sample to sample, and the mean still holds.
    const auto jittered = [&](SampleContext& context) {
        const Vec2 jitter = context.next_2d();
        return camera.generate_ray(1.0f + jitter.x, 1.0f + jitter.y);
    };
    float lowest = 1.0f, highest = 0.0f;
    for (int i = 0; i <= 8; ++i) {
        for (int j = 0; j <= 8; ++j) {
            const float s = share_at(camera.generate_ray(1.0f + i / 8.0f, 1.0f + j / 8.0f));
            ASSERT_GT(s, 0.0f) << "the pixel sees the floor";
            lowest = std::min(lowest, s);
            highest = std::max(highest, s);
        }
    }
    const Comparison spread = compare_shared(integrator, jittered, kPixels);
    std::printf("samples over the pixel, glossy shares %.3f to %.3f (rays at %.0f to %.0f of 16): pixel mean "
                "%.4f, difference %+.5f (standard error %.5f)\n",
                lowest, highest, std::ceil(4.0f * lowest * kSpp), std::ceil(4.0f * highest * kSpp), spread.mean,
                spread.difference, spread.standard_error);
    EXPECT_GT(std::ceil(4.0f * highest * kSpp), std::ceil(4.0f * lowest * kSpp)) << "c differs over the pixel";
    EXPECT_LT(std::abs(spread.difference), 4.0 * spread.standard_error + 1e-6 * spread.mean);
    EXPECT_LT(4.0 * spread.standard_error, 0.25 * 0.018 * spread.mean);
}

/// caustic-area's caustic: a point under the glass sphere, the same for every sample (no jitter),
/// so that a share of the samples estimating it gives the pixel exactly what all of them do.
TEST(PixelShare, ACausticEstimateAtAShareOfTheSamplesGivesThePixelTheSameLight) {
    const auto rs = make_render_scene(make_builtin_scene("caustic-area").value());
    const auto photon_map = uncached_photon_map(rs, 20000, 20000, 16);
    ASSERT_TRUE(photon_map);
    const PhotonMapIntegrator& integrator = *photon_map;
    const Camera camera = Camera::create(rs->scene->cameras.at(0), 128, 96).value();
    const CameraRay ray = camera.generate_ray(68.5f, 58.5f);  // in the caustic (its benchmark region)

    const auto fixed = [&ray](SampleContext&) { return ray; };
    const PixelSums shared = sum_pixels(integrator, fixed, 4, true);
    const PixelSums every = sum_pixels(integrator, fixed, 4, false);
    std::printf("caustic %.5f vs %.5f from %llu vs %llu estimates\n", luminance(Color(shared.caustic)),
                luminance(Color(every.caustic)), static_cast<unsigned long long>(shared.counters.caustic_points),
                static_cast<unsigned long long>(every.counters.caustic_points));
    ASSERT_GT(luminance(Color(every.caustic)), 0.0);
    EXPECT_EQ(shared.counters.caustic_points * 4, every.counters.caustic_points) << "a quarter of the samples";
    EXPECT_EQ(every.counters.caustic_skipped, 0u) << "the caustic shows there";
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(shared.caustic[c], every.caustic[c], 1e-5 * every.caustic[c]);
}

}  // namespace
}  // namespace photond
