#include <gtest/gtest.h>

#include "core/id_list.hpp"

using rilbed::id_ranges_text;
using rilbed::IdListResult;
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

TEST(IdList, ErrorsNameTheListAsTheCallerCallsIt) {
  EXPECT_EQ(parse_id_list("x", 1, 8).error, "bad ID list item 'x' (expected N or A-B with A<=B)");
  EXPECT_EQ(parse_id_list("1000,2", 1, 100, "list").error, "list item '1000' is outside 1..100");
  EXPECT_EQ(parse_id_list("2,abc", 1, 100, "list").error, "bad list item 'abc' (expected N or A-B with A<=B)");
  EXPECT_EQ(parse_id_list(" ", 1, 8, "list").error, "empty list");
}

TEST(IdList, RangesTextIsShortAndReadsBackTheSameIds) {
  EXPECT_EQ(id_ranges_text({}), "");
  EXPECT_EQ(id_ranges_text({5}), "5");
  EXPECT_EQ(id_ranges_text({1, 2, 3, 4, 7, 9, 10, 11, 12}), "1-4,7,9-12");
  EXPECT_EQ(id_ranges_text({3, 2, 1}), "3,2,1");  // only rising runs become ranges: the order stays
  std::vector<int> many;
  for (int id = 1; id <= 1000; ++id) {
    if (id % 97 != 0) many.push_back(id);
  }
  const std::string text = id_ranges_text(many);
  EXPECT_LT(text.size(), 120u);
  const IdListResult back = parse_id_list(text, 1, 1000);
  ASSERT_TRUE(back.ok()) << back.error;
  EXPECT_EQ(back.ids, many);
}
