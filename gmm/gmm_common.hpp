#pragma once
// Pieces shared by the GMM-family methods (CPD, GMMReg, SVR, FilterReg, DeepGMR, OGMM).
// Notation as docs/probabilistic-baselines.md: source Y (M x D), target X (N x D).
#include <nlohmann/json.hpp>
#include <string>

#include "core/params.hpp"
#include "core/point_cloud.hpp"

namespace regbench {

/// probreg's sqsum(Y, X) = sum_mn |y_m - x_n|^2 / (D M N), in O(M + N) via moments.
double SquaredDistanceMean(const PointCloud& Y, const PointCloud& X);

/// probreg's sigma_est(Y) = det(cov(Y))^(1 / 2D), unbiased covariance of Y only.
double EstimateSigmaFromCovariance(const PointCloud& Y);

/// The EM options CPD and FilterReg share, under the same JSON keys in both; their options
/// structs derive from it and bind these fields with their own docs.
struct GmmEmOptions {
    double w = 0.0;       ///< weight of the uniform outlier component
    int maxiter = 50;     ///< maximum EM iterations
    double tol = 0.001;   ///< stop when |q - q_prev| < tol, absolute on the objective q
    double sigma2 = 0.0;  ///< initial sigma^2; 0: estimated from the clouds

    /// The ranges of these fields (core/params.hpp; `regbench methods` prints them).
    void Validate(ParamCheck& c) const {
        c.AtLeast("w", w, 0.0);
        c.Below("w", w, 1.0);
        c.AtLeast("maxiter", maxiter, 1);
        c.AtLeast("tol", tol, 0.0);
        c.Finite("tol", tol);
        c.AtLeast("sigma2", sigma2, 0.0);
        c.Finite("sigma2", sigma2);
    }
};

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
