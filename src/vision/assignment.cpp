#include "vision/assignment.hpp"

#include <limits>
#include <stdexcept>

namespace rilbed::vision {

namespace {

// Minimum-cost assignment of every row to a distinct column, rows <= cols
// (the shortest augmenting path form of the Hungarian algorithm, with potentials).
std::vector<int> hungarian_min_cost(const std::vector<std::vector<double>>& cost, int rows, int cols) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(rows + 1, 0.0), v(cols + 1, 0.0);
  std::vector<int> match_col(cols + 1, 0), way(cols + 1, 0);  // match_col[c] = row (1-based)
  for (int r = 1; r <= rows; ++r) {
    match_col[0] = r;
    int c0 = 0;
    std::vector<double> min_to(cols + 1, inf);
    std::vector<char> used(cols + 1, 0);
    do {
      used[c0] = 1;
      const int r0 = match_col[c0];
      double delta = inf;
      int c1 = 0;
      for (int c = 1; c <= cols; ++c) {
        if (used[c]) continue;
        const double reduced = cost[r0 - 1][c - 1] - u[r0] - v[c];
        if (reduced < min_to[c]) {
          min_to[c] = reduced;
          way[c] = c0;
        }
        if (min_to[c] < delta) {
          delta = min_to[c];
          c1 = c;
        }
      }
      for (int c = 0; c <= cols; ++c) {
        if (used[c]) {
          u[match_col[c]] += delta;
          v[c] -= delta;
        } else {
          min_to[c] -= delta;
        }
      }
      c0 = c1;
    } while (match_col[c0] != 0);
    do {
      const int c1 = way[c0];
      match_col[c0] = match_col[c1];
      c0 = c1;
    } while (c0 != 0);
  }
  std::vector<int> row_to_col(rows, -1);
  for (int c = 1; c <= cols; ++c) {
    if (match_col[c] != 0) row_to_col[match_col[c] - 1] = c - 1;
  }
  return row_to_col;
}

}  // namespace

std::vector<int> assign_max_similarity(const std::vector<std::vector<double>>& similarity,
                                       double min_similarity) {
  const int rows = static_cast<int>(similarity.size());
  if (rows == 0) return {};
  const int cols = static_cast<int>(similarity[0].size());
  for (const auto& row : similarity) {
    if (static_cast<int>(row.size()) != cols) throw std::invalid_argument("ragged similarity matrix");
  }
  std::vector<int> result(rows, -1);
  if (cols == 0) return result;
  // Pairs below the threshold weigh 0, so taking one is worth nothing; every allowed
  // pair weighs its (positive) similarity. Costs are negated weights.
  auto weight = [&](int r, int c) {
    const double s = similarity[r][c];
    return s >= min_similarity && s > 0.0 ? s : 0.0;
  };
  const bool transpose = rows > cols;
  const int n = transpose ? cols : rows, m = transpose ? rows : cols;
  std::vector<std::vector<double>> cost(n, std::vector<double>(m));
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < m; ++j) cost[i][j] = -(transpose ? weight(j, i) : weight(i, j));
  }
  const std::vector<int> match = hungarian_min_cost(cost, n, m);
  for (int i = 0; i < n; ++i) {
    const int j = match[i];
    if (j < 0) continue;
    const int r = transpose ? j : i, c = transpose ? i : j;
    if (weight(r, c) > 0.0) result[r] = c;
  }
  return result;
}

}  // namespace rilbed::vision
