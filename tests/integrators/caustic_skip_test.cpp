// Caustic estimates skipped where the caustic is too faint to show
// (CausticVisibility::may_show): the image with them skipped against the one with every
// estimate made, on the glass sphere of `caustic-area`, whose caustic lies in the sphere's shadow
// and nowhere else.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/integrators/photon_mapping.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

constexpr int kWidth = 128, kHeight = 96;

TileRenderResult render(const std::shared_ptr<const RenderScene>& rs, std::shared_ptr<const PhotonMaps> maps,
                        const Camera& camera, int spp) {
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = 64;
    // Short gather rays read the caustic map's precomputed irradiance where the maps have it:
    // off, so that the two renders differ by the skipped estimates at visible points alone.
    settings.gather.short_ray_radii = 0.0f;
    PhotonMapIntegrator integrator(rs, std::move(maps), settings);
    integrator.build_cache(camera, nullptr);
    TileSettings tiles;
    tiles.samples_per_pixel = spp;
    return render_tiles(integrator, camera, tiles);
}

TEST(CausticSkip, SkipsOnlyWhereTheCausticWouldNotShow) {
    const auto rs = test_support::make_render_scene(make_builtin_scene("caustic-area").value());
    PhotonTracingSettings photons;
    photons.global_photons = 50000;
    photons.caustic_photons = 50000;
    auto maps = std::make_shared<const PhotonMaps>(trace_photons(*rs, photons).value());
    ASSERT_TRUE(maps->caustic);
    ASSERT_TRUE(maps->caustic_irradiance);
    // The same maps without the precomputed caustic irradiance: every estimate is made.
    auto every = std::make_shared<PhotonMaps>(*maps);
    every->caustic_irradiance = nullptr;
    const Camera camera = Camera::create(rs->scene->cameras.at(0), kWidth, kHeight).value();

    // At 1 spp each point's estimate is its pixel's; at 4 spp one sample in four estimates the
    // caustic for all of them (kCausticEstimateShare), and is left out only where four times its
    // light would not show beside its sample's other light.
    for (const int spp : {1, 4}) {
        const TileRenderResult skipped = render(rs, maps, camera, spp);
        const TileRenderResult full = render(rs, every, camera, spp);
        const RayCounters& s = skipped.counters;
        ASSERT_GT(s.caustic_points, 0u);
        EXPECT_EQ(full.counters.caustic_points, s.caustic_points);
        EXPECT_EQ(full.counters.caustic_skipped, 0u);
        const double skipped_share = static_cast<double>(s.caustic_skipped) / static_cast<double>(s.caustic_points);

        // Nothing else differs between the two (the estimates draw no random numbers): each pixel
        // differs by the skipped estimates alone, under kInvisibleCausticRatio of its light (the
        // glass's Fresnel reflection spreads a faint caustic over the whole floor: skipped, 0.3 %
        // of the image). The 1.5 allows for the caustic irradiance taken at the nearest photon
        // rather than at the point.
        const Image& a = skipped.layers.beauty;
        const Image& b = full.layers.beauty;
        double largest = 0.0, sum_a = 0.0, sum_b = 0.0;
        int differing = 0;
        for (size_t p = 0; p < a.pixel_count(); ++p) {
            const double va = luminance(a.pixels()[p]), vb = luminance(b.pixels()[p]);
            sum_a += va;
            sum_b += vb;
            if (va != vb) ++differing;
            if (vb > 0.0) largest = std::max(largest, std::abs(va - vb) / vb);
        }
        std::printf("%d spp: caustic estimates skipped at %.1f %% of %llu points; %d pixels differ, by at most "
                    "%.3f %%; image mean %+.4f %%\n",
                    spp, 100.0 * skipped_share, static_cast<unsigned long long>(s.caustic_points), differing,
                    100.0 * largest, 100.0 * (sum_a / sum_b - 1.0));
        if (spp == 1) EXPECT_GT(skipped_share, 0.5) << "most of the floor is far from the caustic";
        EXPECT_LT(skipped_share, 0.99) << "the caustic itself is estimated";
        EXPECT_LT(largest, 1.5 * kInvisibleCausticRatio) << spp << " spp";
        EXPECT_LT(std::abs(sum_a / sum_b - 1.0), kInvisibleCausticRatio) << spp << " spp";
    }
}

}  // namespace
}  // namespace photond
