#include <gtest/gtest.h>

#include "core/id_list.hpp"

using rilbed::parse_id_list;

TEST(IdList, ParsesRangesAndSingles) {
  const auto r = parse_id_list("1-3, 5,7-8", 1, 8);
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.ids, (std::vector<int>{1, 2, 3, 5, 7, 8}));
}

TEST(IdList, SortsAndRemovesDuplicates) {
  const auto r = parse_id_list("8,2-4,3", 1, 8);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.ids, (std::vector<int>{2, 3, 4, 8}));
}

TEST(IdList, RejectsOutOfRangeNamingTheItem) {
  const auto r = parse_id_list("1-9", 1, 8);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.error.find("1-9"), std::string::npos);
}

TEST(IdList, RejectsGarbage) {
  EXPECT_FALSE(parse_id_list("", 1, 8).ok());
  EXPECT_FALSE(parse_id_list("a", 1, 8).ok());
  EXPECT_FALSE(parse_id_list("3-1", 1, 8).ok());
  EXPECT_FALSE(parse_id_list("1,,2", 1, 8).ok());
  EXPECT_FALSE(parse_id_list("1-", 1, 8).ok());
}
