#include "networks/families/rgm/assignment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace regbench::networks {

namespace {

/// Minimum-cost assignment of every row of an n x m cost matrix (n <= m, row-major) to its own
/// column by shortest augmenting paths: for each new row, Dijkstra over the reduced costs
/// c[i][j] - u[i] - v[j] (non-negative under the dual feasibility the updates keep) to the nearest
/// free column, then the duals updated and the path's assignments flipped. Returns each row's
/// column. O(n^2 m) in the worst case, typically far less, as no initial matching is assumed.
std::vector<int64_t> ShortestAugmentingPaths(const std::vector<double>& cost, int64_t n,
                                             int64_t m) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    std::vector<double> u(static_cast<size_t>(n), 0.0), v(static_cast<size_t>(m), 0.0);
    std::vector<double> dist(static_cast<size_t>(m));
    std::vector<int64_t> col4row(static_cast<size_t>(n), -1), row4col(static_cast<size_t>(m), -1);
    std::vector<int64_t> path(static_cast<size_t>(m)), remaining(static_cast<size_t>(m));
    std::vector<char> row_seen(static_cast<size_t>(n)), col_seen(static_cast<size_t>(m));
    for (int64_t row = 0; row < n; ++row) {
        std::fill(dist.begin(), dist.end(), kInf);
        std::fill(row_seen.begin(), row_seen.end(), 0);
        std::fill(col_seen.begin(), col_seen.end(), 0);
        for (int64_t j = 0; j < m; ++j) remaining[static_cast<size_t>(j)] = m - 1 - j;
        int64_t left = m, i = row, sink = -1;
        double reach = 0.0;  // the length of the shortest path found so far
        while (sink < 0) {
            row_seen[static_cast<size_t>(i)] = 1;
            const double* c = cost.data() + i * m;
            double lowest = kInf;
            int64_t pick = -1;
            for (int64_t k = 0; k < left; ++k) {
                const int64_t j = remaining[static_cast<size_t>(k)];
                const double r =
                    reach + c[j] - u[static_cast<size_t>(i)] - v[static_cast<size_t>(j)];
                if (r < dist[static_cast<size_t>(j)]) {
                    path[static_cast<size_t>(j)] = i;
                    dist[static_cast<size_t>(j)] = r;
                }
                // Ties go to a free column (shorter augmentations).
                const double dj = dist[static_cast<size_t>(j)];
                if (dj < lowest || (dj == lowest && row4col[static_cast<size_t>(j)] < 0)) {
                    lowest = dj;
                    pick = k;
                }
            }
            if (pick < 0) throw std::logic_error("rgm assignment: no augmenting path");
            reach = lowest;
            const int64_t j = remaining[static_cast<size_t>(pick)];
            col_seen[static_cast<size_t>(j)] = 1;
            remaining[static_cast<size_t>(pick)] = remaining[static_cast<size_t>(--left)];
            if (row4col[static_cast<size_t>(j)] < 0) {
                sink = j;
            } else {
                i = row4col[static_cast<size_t>(j)];
            }
        }
        u[static_cast<size_t>(row)] += reach;
        for (int64_t r = 0; r < n; ++r) {
            if (row_seen[static_cast<size_t>(r)] && r != row) {
                u[static_cast<size_t>(r)] +=
                    reach - dist[static_cast<size_t>(col4row[static_cast<size_t>(r)])];
            }
        }
        for (int64_t j = 0; j < m; ++j) {
            if (col_seen[static_cast<size_t>(j)]) {
                v[static_cast<size_t>(j)] -= reach - dist[static_cast<size_t>(j)];
            }
        }
        for (int64_t j = sink;;) {  // flip the path's pairs back to `row`
            const int64_t r = path[static_cast<size_t>(j)];
            row4col[static_cast<size_t>(j)] = r;
            std::swap(col4row[static_cast<size_t>(r)], j);
            if (r == row) break;
        }
    }
    return col4row;
}

}  // namespace

std::vector<int64_t> MaxWeightAssignment(const std::vector<double>& weights, int64_t rows,
                                         int64_t cols) {
    if (rows < 0 || cols < 0 || static_cast<int64_t>(weights.size()) != rows * cols) {
        throw std::invalid_argument("rgm assignment: " + std::to_string(weights.size()) +
                                    " weights for a " + std::to_string(rows) + " x " +
                                    std::to_string(cols) + " matrix");
    }
    std::vector<int64_t> match(static_cast<size_t>(rows), -1);
    if (rows == 0 || cols == 0) return match;
    // Costs -w on the smaller side's rows (the transpose when rows > cols).
    const bool transpose = rows > cols;
    const int64_t n = transpose ? cols : rows, m = transpose ? rows : cols;
    std::vector<double> cost(weights.size());
    for (int64_t r = 0; r < rows; ++r) {
        for (int64_t c = 0; c < cols; ++c) {
            const double w = weights[static_cast<size_t>(r * cols + c)];
            if (std::isnan(w)) {
                throw std::invalid_argument("rgm assignment: weight (" + std::to_string(r) +
                                            ", " + std::to_string(c) + ") is NaN");
            }
            const size_t at = static_cast<size_t>(transpose ? c * rows + r : r * cols + c);
            cost[at] = -std::clamp(w, 0.0, 1.0);
        }
    }
    const std::vector<int64_t> pick = ShortestAugmentingPaths(cost, n, m);
    for (int64_t i = 0; i < n; ++i) {
        if (transpose) {
            match[static_cast<size_t>(pick[static_cast<size_t>(i)])] = i;
        } else {
            match[static_cast<size_t>(i)] = pick[static_cast<size_t>(i)];
        }
    }
    return match;
}

}  // namespace regbench::networks
