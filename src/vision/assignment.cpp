#include "vision/assignment.hpp"

#include <limits>
#include <span>
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

std::vector<int> assign_max_similarity(const std::vector<std::vector<double>>& similarity, double min_similarity) {
  const int rows = static_cast<int>(similarity.size());
  if (rows == 0) return {};
  const int cols = static_cast<int>(similarity[0].size());
  std::vector<double> flat;
  flat.reserve(static_cast<std::size_t>(rows) * cols);
  for (const auto& row : similarity) {
    if (static_cast<int>(row.size()) != cols) throw std::invalid_argument("ragged similarity matrix");
    flat.insert(flat.end(), row.begin(), row.end());
  }
  return assign_max_similarity(flat.data(), rows, cols, min_similarity);
}

std::vector<int> assign_max_similarity(const double* similarity, int rows, int cols, double min_similarity) {
  if (rows <= 0) return {};
  std::vector<int> result(rows, -1);
  if (cols <= 0) return result;
  // Pairs below the threshold weigh 0, so taking one is worth nothing; every allowed
  // pair weighs its (positive) similarity.
  auto weight = [&](int r, int c) {
    const double s = similarity[static_cast<std::size_t>(r) * cols + c];
    return s >= min_similarity && s > 0.0 ? s : 0.0;
  };
  // The best assignment splits over the connected parts of the graph of allowed pairs
  // (rows joined by a column both may take): each part is solved alone. A frame of
  // markers is mostly parts of one object and one ID, which need no search at all.
  std::vector<int> part(rows), owner(cols, -1);
  for (int r = 0; r < rows; ++r) part[r] = r;
  auto find = [&](int r) {
    while (part[r] != r) r = part[r] = part[part[r]];
    return r;
  };
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (weight(r, c) <= 0.0) continue;
      if (owner[c] < 0) {
        owner[c] = r;
      } else {
        part[find(r)] = find(owner[c]);
      }
    }
  }
  // The rows of each part, grouped by its root (a counting sort).
  std::vector<int> first_of(rows + 1, 0), ordered(rows);
  for (int r = 0; r < rows; ++r) ++first_of[find(r) + 1];
  for (int root = 0; root < rows; ++root) first_of[root + 1] += first_of[root];
  {
    std::vector<int> next(first_of.begin(), first_of.end() - 1);
    for (int r = 0; r < rows; ++r) ordered[next[find(r)]++] = r;
  }
  for (int root = 0; root < rows; ++root) {
    const std::span<const int> part_rows(ordered.data() + first_of[root], ordered.data() + first_of[root + 1]);
    if (part_rows.empty()) continue;
    if (part_rows.size() == 1) {  // one object: its best allowed ID, if any
      const int r = part_rows[0];
      double best = 0.0;
      for (int c = 0; c < cols; ++c) {
        if (weight(r, c) > best) {
          best = weight(r, c);
          result[r] = c;
        }
      }
      continue;
    }
    std::vector<int> part_cols;
    for (int c = 0; c < cols; ++c) {
      if (owner[c] >= 0 && find(owner[c]) == root) part_cols.push_back(c);
    }
    const int pr = static_cast<int>(part_rows.size()), pc = static_cast<int>(part_cols.size());
    // Costs are negated weights; the Hungarian form wants rows <= columns.
    const bool transpose = pr > pc;
    const int n = transpose ? pc : pr, m = transpose ? pr : pc;
    std::vector<std::vector<double>> cost(n, std::vector<double>(m));
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < m; ++j) {
        const int r = part_rows[transpose ? j : i], c = part_cols[transpose ? i : j];
        cost[i][j] = -weight(r, c);
      }
    }
    const std::vector<int> match = hungarian_min_cost(cost, n, m);
    for (int i = 0; i < n; ++i) {
      const int j = match[i];
      if (j < 0) continue;
      const int r = part_rows[transpose ? j : i], c = part_cols[transpose ? i : j];
      if (weight(r, c) > 0.0) result[r] = c;
    }
  }
  return result;
}

}  // namespace rilbed::vision
