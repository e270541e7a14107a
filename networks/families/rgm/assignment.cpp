#include "networks/families/rgm/assignment.hpp"

#include <dlib/matrix.h>
#include <dlib/optimization/max_cost_assignment.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace regbench::networks {

std::vector<int64_t> MaxWeightAssignment(const std::vector<double>& weights, int64_t rows,
                                         int64_t cols) {
    if (rows < 0 || cols < 0 || static_cast<int64_t>(weights.size()) != rows * cols) {
        throw std::invalid_argument("rgm assignment: " + std::to_string(weights.size()) +
                                    " weights for a " + std::to_string(rows) + " x " +
                                    std::to_string(cols) + " matrix");
    }
    std::vector<int64_t> match(static_cast<size_t>(rows), -1);
    if (rows == 0 || cols == 0) return match;
    const int64_t n = std::max(rows, cols);
    dlib::matrix<long> cost(n, n);
    cost = 0;  // the dummy rows or columns of the padded square
    for (int64_t r = 0; r < rows; ++r) {
        for (int64_t c = 0; c < cols; ++c) {
            const double w = weights[static_cast<size_t>(r * cols + c)];
            if (std::isnan(w)) {
                throw std::invalid_argument("rgm assignment: weight (" + std::to_string(r) +
                                            ", " + std::to_string(c) + ") is NaN");
            }
            cost(r, c) = std::lround(std::clamp(w, 0.0, 1.0) * kAssignmentScale);
        }
    }
    const std::vector<long> assignment = dlib::max_cost_assignment(cost);
    for (int64_t r = 0; r < rows; ++r) {
        const long c = assignment[static_cast<size_t>(r)];
        if (c < cols) match[static_cast<size_t>(r)] = c;
    }
    return match;
}

}  // namespace regbench::networks
