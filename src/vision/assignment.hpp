// Object-to-ID assignment of paper 001 (Table 1): each ID goes to at most one object and
// each object takes at most one ID, so that the total similarity is maximal (the
// Hungarian algorithm).
#pragma once

#include <vector>

namespace rilbed::vision {

/// Maximum-weight assignment on a rectangular similarity matrix.
/// `similarity[r][c]` is the similarity of object r to ID column c (rows may be fewer or
/// more than columns; every row must have the same length). Pairs below
/// `min_similarity` are never made. Returns, for each row, the column it takes or -1.
/// O(n^2 m) for n = min(rows, cols), m = max(rows, cols).
std::vector<int> assign_max_similarity(const std::vector<std::vector<double>>& similarity, double min_similarity);

/// The same on a row-major `rows` x `cols` matrix (not owned; `similarity[r * cols + c]`),
/// for a caller that keeps one buffer from frame to frame.
std::vector<int> assign_max_similarity(const double* similarity, int rows, int cols, double min_similarity);

}  // namespace rilbed::vision
