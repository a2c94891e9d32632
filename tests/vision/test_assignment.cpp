#include <gtest/gtest.h>

#include <functional>

#include "vision/assignment.hpp"

using rilbed::vision::assign_max_similarity;

// The paper's Table 1: 5 objects, IDs {1, 3, 6}.
TEST(Assignment, PapersTableOne) {
  const std::vector<std::vector<double>> table = {{0.27433464, 0.3336813, 0.40391427},
                                                  {0.6221739, 0.93153024, 0.16337222},
                                                  {0.5072501, 0.19723846, 0.9139368},
                                                  {0.3381496, 0.47814554, 0.36910614},
                                                  {0.9299889, 0.65918684, 0.51369625}};
  const auto a = assign_max_similarity(table, 0.0);
  EXPECT_EQ(a, (std::vector<int>{-1, 1, 2, -1, 0}));
}

TEST(Assignment, PrefersTotalOverGreedy) {
  // Greedy would give row 0 column 0 (0.9) and leave row 1 with 0.1; the optimum is 0.8 + 0.8.
  const auto a = assign_max_similarity({{0.9, 0.8}, {0.8, 0.1}}, 0.0);
  EXPECT_EQ(a, (std::vector<int>{1, 0}));
}

TEST(Assignment, DropsPairsBelowThreshold) {
  const auto a = assign_max_similarity({{0.5, 0.95}, {0.6, 0.2}}, 0.7);
  EXPECT_EQ(a, (std::vector<int>{1, -1}));
}

TEST(Assignment, MoreIdsThanObjectsAndEmpty) {
  EXPECT_EQ(assign_max_similarity({{0.1, 0.2, 0.99, 0.3}}, 0.5), (std::vector<int>{2}));
  EXPECT_TRUE(assign_max_similarity({}, 0.5).empty());
  EXPECT_THROW(assign_max_similarity({{0.1, 0.2}, {0.3}}, 0.0), std::invalid_argument);
}

// Brute force over all permutations agrees on random matrices.
// Dense matrices (one connected part) and sparse ones (several parts, solved apart, as
// a frame of markers is), against brute force.
TEST(Assignment, MatchesBruteForce) {
  std::srand(3);
  for (int trial = 0; trial < 400; ++trial) {
    const bool sparse = trial >= 200;
    const int rows = 1 + std::rand() % (sparse ? 7 : 5), cols = 1 + std::rand() % (sparse ? 7 : 5);
    std::vector<std::vector<double>> s(rows, std::vector<double>(cols));
    for (auto& r : s) {
      for (auto& v : r) v = sparse && std::rand() % 10 < 7 ? 0.0 : (std::rand() % 1000) / 1000.0;
    }
    const double threshold = 0.3;
    const auto a = assign_max_similarity(s, threshold);
    double got = 0.0;
    std::vector<int> used(cols, 0);
    for (int r = 0; r < rows; ++r) {
      if (a[r] < 0) continue;
      ASSERT_GE(s[r][a[r]], threshold);
      ASSERT_EQ(used[a[r]]++, 0);
      got += s[r][a[r]];
    }
    // Brute force: assign rows recursively.
    std::function<double(int, std::vector<int>&)> best = [&](int r, std::vector<int>& taken) -> double {
      if (r == rows) return 0.0;
      double b = best(r + 1, taken);
      for (int c = 0; c < cols; ++c) {
        if (taken[c] || s[r][c] < threshold) continue;
        taken[c] = 1;
        b = std::max(b, s[r][c] + best(r + 1, taken));
        taken[c] = 0;
      }
      return b;
    };
    std::vector<int> taken(cols, 0);
    EXPECT_NEAR(got, best(0, taken), 1e-9);
  }
}
