#include <gtest/gtest.h>

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
