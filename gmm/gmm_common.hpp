#pragma once
// Pieces shared by the GMM-family methods (CPD, GMMReg, SVR, FilterReg, DeepGMR, OGMM).
// Notation as docs/probabilistic-baselines.md: source Y (M x D), target X (N x D).
#include <nlohmann/json.hpp>
#include <string>

#include "core/point_cloud.hpp"

namespace regbench {

/// probreg's sqsum(Y, X) = sum_mn |y_m - x_n|^2 / (D M N), in O(M + N) via moments.
double SquaredDistanceMean(const PointCloud& Y, const PointCloud& X);

/// probreg's sigma_est(Y) = det(cov(Y))^(1 / 2D), unbiased covariance of Y only.
double EstimateSigmaFromCovariance(const PointCloud& Y);

/// Iteration bookkeeping every iterative method reports in its result row.
struct Convergence {
    int iterations = 0;
    double objective = 0.0;   ///< final objective value (method-defined)
    std::string stop_reason;  ///< "converged", "max_iterations", "line_search_failed", ...
    nlohmann::json ToJson() const {
        return {{"iterations", iterations}, {"objective", objective}, {"stop_reason", stop_reason}};
    }
};

}  // namespace regbench
