// IrradianceBoundGrid: never below the irradiance of the nearest site a search of its radius
// finds (PhotonMap::nearest_irradiance), and zero where no site is in reach; against a brute-force
// scan of the sites at random points.
#include <gtest/gtest.h>

#include <limits>
#include <span>
#include <vector>

#include "core/math/rng.h"
#include "core/photon/irradiance_bound_grid.h"

namespace photond {
namespace {

/// `count` sites on random planes in the unit cube, irradiance spread over four decades.
std::vector<Photon> random_sites(size_t count, Rng& rng) {
    std::vector<Photon> sites;
    for (size_t i = 0; i < count; ++i) {
        const Vec3 p(rng.next_float(), rng.next_float(), rng.next_float());
        const Vec3 n = glm::normalize(Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f) +
                                      Vec3(0.0f, 0.0f, 1e-3f));
        const float scale = std::pow(10.0f, 4.0f * rng.next_float() - 2.0f);
        sites.push_back(make_irradiance_site(p, n, scale * Color(rng.next_float(), rng.next_float(), rng.next_float()),
                                             0.05f));
    }
    return sites;
}

TEST(IrradianceBoundGrid, NeverBelowTheSiteANearestSearchFinds) {
    Rng rng = Rng::for_stream(7, 0, 0);
    for (const float reach : {0.01f, 0.05f, 0.3f}) {
        const PhotonMap map(random_sites(2000, rng), 0);
        const IrradianceBoundGrid grid(map, reach);
        ASSERT_FALSE(grid.empty());
        size_t found = 0, below_site_max = 0;
        const std::span<const Photon> all = map.tree().photons();
        for (int i = 0; i < 20000; ++i) {
            // Half of the points anywhere around the cube, half beside a site, facing as it does
            // (where searches find sites).
            Vec3 p(1.4f * rng.next_float() - 0.2f, 1.4f * rng.next_float() - 0.2f, 1.4f * rng.next_float() - 0.2f);
            Vec3 n = glm::normalize(Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f) +
                                    Vec3(0.0f, 0.0f, 1e-3f));
            if (i % 2 == 1) {
                const Photon& site = all[std::min(all.size() - 1, size_t(rng.next_float() * float(all.size())))];
                p = site.position + 1.5f * reach * (Vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 0.5f);
                n = site.normal();
            }
            const float bound = grid.bound(p);
            Color e;
            if (map.nearest_irradiance(p, n, reach, &e)) {
                ++found;
                ASSERT_GE(bound, luminance(e)) << "reach " << reach << " at (" << p.x << ", " << p.y << ", " << p.z << ")";
            }
            // Brute force: the largest site within reach bounds every search's answer, and the
            // grid's bound is at least that.
            float largest = 0.0f;
            for (const Photon& site : map.tree().photons())
                if (glm::distance(site.position, p) <= reach) largest = std::max(largest, luminance(site.flux()));
            ASSERT_GE(bound, largest) << "reach " << reach;
            if (bound < 1.01f * largest) ++below_site_max;
        }
        std::printf("reach %.2f: %zu of 20000 searches found a site; the bound was the largest site in reach at %zu\n",
                    reach, found, below_site_max);
        EXPECT_GT(found, 100u) << "the test must exercise searches that find sites";
    }
}

TEST(IrradianceBoundGrid, ZeroBeyondEverySiteAndForNonFinitePoints) {
    const PhotonMap map({make_irradiance_site(Vec3(0.0f), Vec3(0, 0, 1), Color(5.0f), 0.1f),
                         make_irradiance_site(Vec3(1.0f, 0.0f, 0.0f), Vec3(0, 0, 1), Color(1.0f), 0.1f)},
                        0);
    const IrradianceBoundGrid grid(map, 0.1f);
    EXPECT_GE(grid.bound(Vec3(0.05f, 0.0f, 0.0f)), 5.0f);
    EXPECT_GE(grid.bound(Vec3(0.95f, 0.0f, 0.0f)), 1.0f);
    EXPECT_EQ(grid.bound(Vec3(0.0f, 0.5f, 0.0f)), 0.0f);  // beyond the widened bounds
    EXPECT_EQ(grid.bound(Vec3(3.0f, 0.0f, 0.0f)), 0.0f);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(grid.bound(Vec3(nan, 0.0f, 0.0f)), 0.0f);
    EXPECT_TRUE(IrradianceBoundGrid(PhotonMap(std::vector<Photon>{}, 0), 0.1f).empty());
}

}  // namespace
}  // namespace photond
