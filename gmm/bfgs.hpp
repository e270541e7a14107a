#pragma once
// scipy-like BFGS (scipy.optimize.minimize(method='BFGS', jac=True)) with the Moré-Thuente
// line search of MINPACK-2 (dcsrch / dcstep), as scipy's line_search_wolfe1 drives it.
// Shared by the L2-distance methods (GMMReg, SVR) and available to DeepGMR/OGMM refinements.
#include <Eigen/Core>
#include <functional>
#include <string>

namespace regbench {

/// Objective with gradient: returns f(x) and writes df/dx into `grad` (same size as x).
using BfgsObjective = std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd& grad)>;

struct BfgsOptions {
    int maxiter = 50;     ///< BFGS iterations (scipy's options['maxiter']; scipy default 200 n)
    double gtol = 1e-5;   ///< stop when |g|_inf <= gtol (scipy's tol/gtol)
    double c1 = 1e-4;     ///< sufficient-decrease constant (Armijo), scipy's c1
    double c2 = 0.9;      ///< curvature constant (strong Wolfe), scipy's c2
    double xtol = 1e-14;  ///< dcsrch relative interval-width tolerance (scipy's xtol)
    int max_line_search_evals = 100;  ///< dcsrch calls per line search (scipy: 100)
};

struct BfgsResult {
    Eigen::VectorXd x;        ///< last accepted iterate
    double f = 0.0;           ///< f(x)
    Eigen::VectorXd grad;     ///< df/dx at x
    int iterations = 0;       ///< accepted BFGS steps
    int evaluations = 0;      ///< objective calls, including the one at x0
    std::string stop_reason;  ///< "converged", "max_iterations" or "line_search_failed"
};

/// Minimises `fun` from `x0` like scipy's _minimize_bfgs:
/// H0 = I; the first trial step is min(1, 1.01 / |g0|_2) (scipy's old_old_fval = f0 + |g0|/2),
/// later ones min(1, 2.02 (f_k - f_{k-1}) / g_k.p_k); strong-Wolfe Moré-Thuente search with
/// stpmin 1e-100, stpmax 1e100; rho = 1000 when y's = 0; stops on |g|_inf <= gtol, maxiter, a
/// failed line search (dcsrch error/warning, or 100 calls) or a non-finite f.
/// Unlike scipy, a failed Moré-Thuente search does not fall back to line_search_wolfe2.
BfgsResult MinimizeBfgs(const BfgsObjective& fun, const Eigen::VectorXd& x0,
                        const BfgsOptions& options);

/// Outcome of one Moré-Thuente search along p from x.
struct LineSearchResult {
    bool ok = false;       ///< true when dcsrch reported CONVERGENCE (strong Wolfe holds)
    double step = 0.0;     ///< accepted step (valid when ok)
    double f = 0.0;        ///< f(x + step p)
    Eigen::VectorXd grad;  ///< gradient there
    int evaluations = 0;   ///< objective calls made
    std::string task;      ///< dcsrch's last task string ("CONVERGENCE", "WARNING: ...", ...)
};

/// scipy's scalar_search_wolfe1 over phi(a) = f(x + a p): MINPACK-2 dcsrch with ftol = c1,
/// gtol = c2, starting at `step0`.
LineSearchResult MoreThuenteSearch(const BfgsObjective& fun, const Eigen::VectorXd& x,
                                   const Eigen::VectorXd& p, double f0, const Eigen::VectorXd& g0,
                                   double step0, const BfgsOptions& options);

}  // namespace regbench
