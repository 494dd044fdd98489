// compare_images: the error figures against values worked out by hand, and the listing of the
// pixels the error comes from.
#include <gtest/gtest.h>

#include "core/image/image_metrics.h"

namespace photond {
namespace {

// A 4 x 3 reference of 1.0 and an image equal to it but for two pixels, 2.0 at (1, 0) and 1.5
// at (3, 2): their relative squared errors are 1 / 1.01 and 0.25 / 1.01 in every channel.
struct TwoBadPixels {
    Image reference{4, 3, Color(1.0f)};
    Image image{4, 3, Color(1.0f)};
    TwoBadPixels() {
        image.at(1, 0) = Color(2.0f);
        image.at(3, 2) = Color(1.5f);
    }
};

TEST(CompareImages, RelativeErrorBiasAndMeanAreTheirDefinitions) {
    const TwoBadPixels t;
    const auto e = compare_images(t.image, t.reference);
    ASSERT_TRUE(e.has_value()) << e.error().message;
    EXPECT_NEAR(e->relative_mse, (1.0 + 0.25) / 1.01 / 12.0, 1e-12);
    EXPECT_NEAR(e->rmse, std::sqrt(1.25 / 12.0), 1e-12);
    EXPECT_NEAR(e->mean, 1.0 + 1.5 / 12.0, 1e-12);
    EXPECT_NEAR(e->mean_bias, 1.5 / 12.0, 1e-12);
    EXPECT_EQ(e->pixels, 12u);
    EXPECT_TRUE(e->worst.empty());  // not asked for
}

TEST(CompareImages, ListsTheWorstPixelsWithTheirShareOfTheError) {
    const TwoBadPixels t;
    const auto e = compare_images(t.image, t.reference, std::nullopt, 0.01, 3);
    ASSERT_TRUE(e.has_value()) << e.error().message;
    ASSERT_EQ(e->worst.size(), 3u);
    EXPECT_EQ(e->worst[0].x, 1);
    EXPECT_EQ(e->worst[0].y, 0);
    EXPECT_NEAR(e->worst[0].relative_squared_error, 1.0 / 1.01, 1e-12);
    EXPECT_NEAR(e->worst[0].share, 0.8, 1e-12);  // 1 of 1.25
    EXPECT_EQ(e->worst[0].value, Color(2.0f));
    EXPECT_EQ(e->worst[0].reference, Color(1.0f));
    EXPECT_EQ(e->worst[1].x, 3);
    EXPECT_EQ(e->worst[1].y, 2);
    EXPECT_NEAR(e->worst[1].share, 0.2, 1e-12);
    // The third is exact: of the ten tied at zero, the first in row order.
    EXPECT_EQ(e->worst[2].x, 0);
    EXPECT_EQ(e->worst[2].y, 0);
    EXPECT_EQ(e->worst[2].relative_squared_error, 0.0);
}

TEST(CompareImages, TheListingKeepsToTheRegionAndItsCount) {
    const TwoBadPixels t;
    // Rows 1 and 2 only: (1, 0) is outside, (3, 2) holds the whole error there.
    const auto e = compare_images(t.image, t.reference, PixelRect{0, 1, 4, 3}, 0.01, 50);
    ASSERT_TRUE(e.has_value()) << e.error().message;
    EXPECT_EQ(e->pixels, 8u);
    ASSERT_EQ(e->worst.size(), 8u);
    EXPECT_EQ(e->worst[0].x, 3);
    EXPECT_EQ(e->worst[0].y, 2);
    EXPECT_NEAR(e->worst[0].share, 1.0, 1e-12);
    EXPECT_NEAR(e->relative_mse, 0.25 / 1.01 / 8.0, 1e-12);
}

}  // namespace
}  // namespace photond
