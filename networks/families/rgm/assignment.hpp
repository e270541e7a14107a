#pragma once
// Maximum-weight linear assignment for RGM's test-time correspondences
// (networks/families/rgm/net.hpp): shortest augmenting paths on the float weights (the
// Jonker-Volgenant family that scipy's linear_sum_assignment, the authors' solver, also belongs
// to; written from the algorithm's description: Crouse, "On implementing 2D rectangular
// assignment algorithms", IEEE TAES 2016). It replaced dlib's max_cost_assignment (the O(n^3)
// Hungarian algorithm on integer costs), slower on RGM's 717 x 717 correspondences
// (docs/performance.md, "RGM against its floor").
#include <cstdint>
#include <vector>

namespace regbench::networks {

/// The assignment of `rows` x `cols` weights (row-major, each in [0, 1]; values outside are
/// clamped) that maximises the sum of the chosen weights, every row matched to at most one
/// column and every column to at most one row, min(rows, cols) pairs in all (the rectangular
/// problem: every row of the smaller side is matched). Returns, per row, its column or -1.
/// Exact ties are broken by the solver (scipy may pick another of the equal assignments).
/// Throws std::invalid_argument when weights.size() != rows * cols or a weight is NaN.
std::vector<int64_t> MaxWeightAssignment(const std::vector<double>& weights, int64_t rows,
                                         int64_t cols);

}  // namespace regbench::networks
