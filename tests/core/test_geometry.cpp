#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/fast_trig.hpp"
#include "core/geometry.hpp"
#include "core/time.hpp"

using namespace rilbed;

TEST(Geometry, WrapsAngles) {
  EXPECT_DOUBLE_EQ(wrap_deg_360(370.0), 10.0);
  EXPECT_DOUBLE_EQ(wrap_deg_360(-10.0), 350.0);
  EXPECT_DOUBLE_EQ(wrap_deg_360(360.0), 0.0);
  EXPECT_DOUBLE_EQ(wrap_deg_180(190.0), -170.0);
  EXPECT_DOUBLE_EQ(wrap_deg_180(-180.0), -180.0);
  EXPECT_NEAR(wrap_rad_pi(3 * kPi), -kPi, 1e-12);
}

TEST(Geometry, VectorOps) {
  const Vec2 a{3, 4}, b{1, 0};
  EXPECT_DOUBLE_EQ(a.norm(), 5.0);
  EXPECT_DOUBLE_EQ(a.dot(b), 3.0);
  EXPECT_DOUBLE_EQ(b.cross(a), 4.0);
  EXPECT_EQ(a + b, (Vec2{4, 4}));
}

TEST(Time, ConvertsSecondsAndMicroseconds) {
  EXPECT_EQ(seconds_to_us(1.5), 1'500'000);
  EXPECT_EQ(seconds_to_us(-0.000001), -1);
  EXPECT_DOUBLE_EQ(us_to_seconds(250'000), 0.25);
}

TEST(FastTrig, SinCosMatchTheLibraryOverManyTurns) {
  double worst = 0.0;
  for (int i = -200000; i <= 200000; ++i) {
    const double a = i * 1.2345e-3;  // about +-39 turns, not aligned with quarter turns
    double s = 0.0, c = 0.0;
    fast_sincos(a, s, c);
    worst = std::max({worst, std::abs(s - std::sin(a)), std::abs(c - std::cos(a))});
  }
  EXPECT_LT(worst, 1e-15);
  double s = 1.0, c = 0.0;
  for (double a : {0.0, kPi / 2, -kPi / 2, kPi, 2 * kPi, 1e5}) {
    fast_sincos(a, s, c);
    EXPECT_NEAR(s, std::sin(a), 1e-15) << a;
    EXPECT_NEAR(c, std::cos(a), 1e-15) << a;
  }
}

TEST(FastTrig, Atan2MatchesTheLibraryInEveryOctant) {
  double worst = 0.0;
  for (int i = 0; i < 100000; ++i) {
    const double a = -kPi + 2 * kPi * (i + 0.37) / 100000;
    const double r = 1e-3 + (i % 97) * 13.7;  // radii from tiny to large
    const double x = r * std::cos(a), y = r * std::sin(a);
    worst = std::max(worst, std::abs(fast_atan2(y, x) - std::atan2(y, x)));
  }
  EXPECT_LT(worst, 1e-12);
  // The axes and the diagonals, where the reductions switch.
  for (double x : {-2.0, -1.0, 0.0, 1.0, 2.0}) {
    for (double y : {-2.0, -1.0, 0.0, 1.0, 2.0}) {
      if (x == 0.0 && y == 0.0) continue;
      EXPECT_NEAR(fast_atan2(y, x), std::atan2(y, x), 1e-12) << y << "," << x;
    }
  }
  EXPECT_EQ(fast_atan2(0.0, 0.0), 0.0);
}

// wrap_deg_360 wraps within a turn of its range without fmod, and must give exactly
// what fmod gives, at the boundaries too.
TEST(Geometry, WrapDeg360MatchesFmodExactly) {
  auto reference = [](double deg) {
    double w = std::fmod(deg, 360.0);
    if (w < 0.0) w += 360.0;
    if (w >= 360.0) w -= 360.0;
    return w;
  };
  for (double deg : {-720.0, -360.0, -359.999999, -1e-17, -0.0, 0.0, 1e-300, 359.99999999999994, 360.0, 400.5, 719.9999,
                     720.0, 1080.25, -1e-9, 12345.678, -12345.678}) {
    EXPECT_EQ(wrap_deg_360(deg), reference(deg)) << deg;
  }
  for (double deg = -1000.0; deg < 1000.0; deg += 0.37) EXPECT_EQ(wrap_deg_360(deg), reference(deg)) << deg;
}
