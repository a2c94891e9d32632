#include <gtest/gtest.h>

#include <set>

#include "vision/marker_family.hpp"

using rilbed::vision::MarkerFamily;

TEST(MarkerFamily, SixUcpHasThePapersAngles) {
  const auto f = MarkerFamily::six_ucp();
  EXPECT_EQ(f.slice_widths_deg(), (std::vector<double>{85, 55, 55, 55, 55, 55}));
  EXPECT_EQ(f.max_id(), 8);
}

TEST(MarkerFamily, SlicesFollowTheTemplate) {
  const auto f = MarkerFamily::six_ucp();
  // ID = 1 + x1 + 2 x2 + 4 x3: ID 6 -> code 5 -> x1 = 1, x2 = 0, x3 = 1.
  const auto s = f.slices(6);
  ASSERT_EQ(s.size(), 6u);
  EXPECT_DOUBLE_EQ(s[0].start_deg, -42.5);
  EXPECT_DOUBLE_EQ(s[0].end_deg, 42.5);
  EXPECT_TRUE(s[0].white);
  EXPECT_FALSE(s[1].white);
  EXPECT_TRUE(s[2].white);
  EXPECT_FALSE(s[3].white);
  EXPECT_TRUE(s[4].white);
  EXPECT_FALSE(s[5].white);
  EXPECT_DOUBLE_EQ(s[5].end_deg, 317.5);
}

TEST(MarkerFamily, ColourAtMatchesRingsAndSlices) {
  const auto f = MarkerFamily::six_ucp();
  EXPECT_EQ(f.colour_at(1, 0.05, 0), 0.0);   // hole
  EXPECT_EQ(f.colour_at(1, 0.4, 0), 1.0);    // key slice
  EXPECT_EQ(f.colour_at(1, 0.4, 70), 0.0);   // guard slice
  EXPECT_EQ(f.colour_at(8, 0.4, 180), 1.0);  // x2 of ID 8
  EXPECT_EQ(f.colour_at(1, 0.4, 180), 0.0);
  EXPECT_EQ(f.colour_at(1, 0.7, 0), 0.0);   // black ring
  EXPECT_EQ(f.colour_at(1, 0.9, 0), 1.0);   // white ring
  EXPECT_EQ(f.colour_at(1, 1.1, 0), -1.0);  // outside
}

// Codes must be unique under rotation, or two robots could not be told apart.
TEST(MarkerFamily, CodesAreUniqueUnderRotation) {
  for (const char* name : {"6ucp", "9ucp", "12ucp"}) {
    const auto f = MarkerFamily::by_name(name);
    std::set<std::vector<int>> seen;
    constexpr int kSteps = 720;
    for (int id = f.min_id(); id <= f.max_id(); ++id) {
      std::vector<int> signal(kSteps);
      for (int k = 0; k < kSteps; ++k) signal[k] = static_cast<int>(f.colour_at(id, 0.4, k * 0.5 + 0.25));
      for (int shift = 0; shift < kSteps; ++shift) {
        std::vector<int> rotated(kSteps);
        for (int k = 0; k < kSteps; ++k) rotated[k] = signal[(k + shift) % kSteps];
        if (shift == 0) {
          EXPECT_TRUE(seen.insert(rotated).second) << name << " ID " << id << " repeats another ID";
        } else {
          EXPECT_NE(rotated, signal) << name << " ID " << id << " is symmetric under a rotation";
        }
      }
    }
    // Every rotation of every ID differs from every other ID.
    for (int id = f.min_id(); id <= f.max_id(); ++id) {
      std::vector<int> signal(kSteps);
      for (int k = 0; k < kSteps; ++k) signal[k] = static_cast<int>(f.colour_at(id, 0.4, k * 0.5 + 0.25));
      for (int shift = 1; shift < kSteps; ++shift) {
        std::vector<int> rotated(kSteps);
        for (int k = 0; k < kSteps; ++k) rotated[k] = signal[(k + shift) % kSteps];
        ASSERT_EQ(seen.count(rotated), 0u) << name << " ID " << id << " rotated equals another ID";
      }
    }
  }
}

TEST(MarkerFamily, LargerFamiliesCountEnoughIds) {
  EXPECT_EQ(MarkerFamily::by_name("9ucp").max_id(), 64);
  EXPECT_EQ(MarkerFamily::by_name("12UCP").max_id(), 512);
  EXPECT_THROW(MarkerFamily::by_name("5ucp"), std::invalid_argument);
  EXPECT_THROW(MarkerFamily::by_name("ucp"), std::invalid_argument);
  EXPECT_THROW(MarkerFamily::six_ucp().slices(9), std::out_of_range);
}
