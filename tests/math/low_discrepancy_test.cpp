// The camera-sample pattern: scrambled Sobol' points must stay a (0, 2)-sequence (every
// elementary interval of the first 2^m points holds exactly one point), and each point must stay
// uniformly distributed over the pattern seeds, or pixel estimates would be biased.
#include "core/math/low_discrepancy.h"

#include <gtest/gtest.h>

#include <vector>

#include "core/math/rng.h"

namespace photond {
namespace {

TEST(LowDiscrepancy, SobolDimensionsMatchTheirDefinition) {
    // The first points of the 2D Sobol' sequence in binary (not Gray-code) index order.
    const float expected[4][2] = {{0.0f, 0.0f}, {0.5f, 0.5f}, {0.25f, 0.75f}, {0.75f, 0.25f}};
    for (uint32_t i = 0; i < 4; ++i) {
        EXPECT_EQ(fixed_point_to_float(sobol_dimension0(i)), expected[i][0]) << i;
        EXPECT_EQ(fixed_point_to_float(sobol_dimension1(i)), expected[i][1]) << i;
    }
}

TEST(LowDiscrepancy, ScrambledPointsFormA02NetForEveryPowerOfTwo) {
    for (uint64_t seed : {1ull, 0x123456789abcdefull, 0xfeedfacecafebeefull}) {
        for (int m = 0; m <= 8; ++m) {
            const uint32_t n = 1u << m;
            // Every split of [0,1)^2 into 2^a x 2^(m-a) cells holds one point per cell.
            for (int a = 0; a <= m; ++a) {
                std::vector<int> count(n, 0);
                for (uint32_t i = 0; i < n; ++i) {
                    const Vec2 p = scrambled_sobol_2d(i, seed);
                    const uint32_t cx = static_cast<uint32_t>(p.x * static_cast<float>(1u << a));
                    const uint32_t cy = static_cast<uint32_t>(p.y * static_cast<float>(1u << (m - a)));
                    ++count[(cy << a) | cx];
                }
                for (uint32_t c = 0; c < n; ++c)
                    ASSERT_EQ(count[c], 1) << "seed " << seed << ", " << n << " points, cell " << c
                                           << " of the " << (1u << a) << " x " << (1u << (m - a)) << " split";
            }
            // The 1D pattern: one point in each interval of length 1/n.
            std::vector<int> count(n, 0);
            for (uint32_t i = 0; i < n; ++i) ++count[static_cast<uint32_t>(scrambled_sobol_1d(i, seed) * n)];
            for (uint32_t c = 0; c < n; ++c) ASSERT_EQ(count[c], 1) << n << " points, interval " << c;
        }
    }
}

TEST(LowDiscrepancy, EachPointIsUniformOverSeeds) {
    // Point i over many pattern seeds: a 16 x 16 histogram, chi-square against uniform.
    constexpr int kBins = 16, kSeeds = 64 * 1024;
    for (uint32_t index : {0u, 1u, 5u, 31u}) {
        std::vector<int> histogram(kBins * kBins, 0), histogram_1d(kBins, 0);
        for (int s = 0; s < kSeeds; ++s) {
            const uint64_t seed = hash_indices(7, static_cast<uint64_t>(s));
            const Vec2 p = scrambled_sobol_2d(index, seed);
            ++histogram[static_cast<int>(p.y * kBins) * kBins + static_cast<int>(p.x * kBins)];
            ++histogram_1d[static_cast<int>(scrambled_sobol_1d(index, seed) * kBins)];
        }
        const auto chi_square = [](const std::vector<int>& h, double expected) {
            double chi2 = 0.0;
            for (int c : h) chi2 += (c - expected) * (c - expected) / expected;
            return chi2;
        };
        // 255 and 15 degrees of freedom: the 99.9 % quantiles are 330.5 and 37.7.
        EXPECT_LT(chi_square(histogram, double(kSeeds) / (kBins * kBins)), 330.5) << "point " << index;
        EXPECT_LT(chi_square(histogram_1d, double(kSeeds) / kBins), 37.7) << "point " << index;
    }
}

}  // namespace
}  // namespace photond
