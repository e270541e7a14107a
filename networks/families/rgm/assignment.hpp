#pragma once
// Maximum-weight linear assignment for RGM's test-time correspondences (networks/families/rgm/net.hpp), by
// dlib's max_cost_assignment (Debian libdlib-dev, the Hungarian algorithm in O(n^3)). Kept in
// its own translation unit, free of LibTorch: dlib's matrix headers are large and only this
// file includes them.
#include <cstdint>
#include <vector>

namespace regbench::networks {

/// Integer resolution of the assignment: dlib's solver takes integer costs only, so every
/// weight w in [0, 1] enters as round(w * kAssignmentScale). Two assignments whose totals
/// differ by less than about rows / kAssignmentScale may be taken for equal (ties broken by
/// dlib, where scipy's linear_sum_assignment on the float weights may pick the other one).
constexpr double kAssignmentScale = 1e9;

/// The assignment of `rows` x `cols` weights (row-major, each in [0, 1]; values outside are
/// clamped) that maximises the sum of the chosen weights, every row matched to at most one
/// column and every column to at most one row, min(rows, cols) pairs in all (the rectangular
/// problem: the smaller side is padded with zero-weight dummies). Returns, per row, its column
/// or -1. Throws std::invalid_argument when weights.size() != rows * cols or a weight is NaN.
std::vector<int64_t> MaxWeightAssignment(const std::vector<double>& weights, int64_t rows,
                                         int64_t cols);

}  // namespace regbench::networks
