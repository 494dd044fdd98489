// The sampling warps' sine and cosine against libm's, in double, over their whole ranges.
#include <gtest/gtest.h>

#include <cmath>

#include "core/math/trig.h"

namespace photond {
namespace {

constexpr double kPiDouble = 3.14159265358979323846;
constexpr double kMaxError = 0x1p-23;

TEST(Trig, QuarterTurnMatchesLibm) {
    double worst = 0.0;
    for (int i = -1000000; i <= 1000000; ++i) {
        const float a = static_cast<float>(i * 1e-6 * kPiDouble / 4.0);
        const Vec2 cs = cos_sin_eighth(a);
        worst = std::max({worst, std::abs(cs.x - std::cos(double(a))), std::abs(cs.y - std::sin(double(a)))});
    }
    EXPECT_LT(worst, kMaxError);
    // The ends of the range and zero exactly where it matters: cos 0 = 1, sin 0 = 0.
    EXPECT_EQ(cos_sin_eighth(0.0f), Vec2(1.0f, 0.0f));
}

TEST(Trig, FullTurnMatchesLibm) {
    double worst = 0.0;
    for (int i = 0; i < 4000000; ++i) {
        const float u = static_cast<float>(i) / 4000000.0f;
        const Vec2 cs = cos_sin_turn(u);
        const double phi = 2.0 * kPiDouble * double(u);
        worst = std::max({worst, std::abs(cs.x - std::cos(phi)), std::abs(cs.y - std::sin(phi))});
    }
    EXPECT_LT(worst, kMaxError);
    // Quarter turns land on the axes exactly, and the largest u below 1 just short of a turn.
    EXPECT_EQ(cos_sin_turn(0.25f), Vec2(0.0f, 1.0f));
    EXPECT_EQ(cos_sin_turn(0.5f), Vec2(-1.0f, 0.0f));
    EXPECT_EQ(cos_sin_turn(0.75f), Vec2(0.0f, -1.0f));
    const Vec2 last = cos_sin_turn(0x1.fffffep-1f);
    EXPECT_NEAR(last.x, 1.0f, 1e-6f);
    EXPECT_LT(last.y, 0.0f);
}

}  // namespace
}  // namespace photond
