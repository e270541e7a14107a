#include "gmm/bfgs.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>

namespace regbench {
namespace {

double Rosenbrock(const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    const double a = 1.0 - x[0], b = x[1] - x[0] * x[0];
    g.resize(2);
    g[0] = -2.0 * a - 400.0 * x[0] * b;
    g[1] = 200.0 * b;
    return a * a + 100.0 * b * b;
}

/// BFGS on Rosenbrock from the classic start (-1.2, 1), with at most `maxiter` iterations and
/// gradient tolerance `gtol`.
BfgsResult MinimizeRosenbrock(int maxiter, double gtol) {
    BfgsOptions options;
    options.maxiter = maxiter;
    options.gtol = gtol;
    return MinimizeBfgs(Rosenbrock, Eigen::Vector2d(-1.2, 1.0), options);
}

TEST(Bfgs, MinimisesRosenbrockFromTheClassicStart) {
    const BfgsResult r = MinimizeRosenbrock(/*maxiter=*/200, /*gtol=*/1e-8);
    EXPECT_EQ(r.stop_reason, "converged");
    EXPECT_NEAR(r.x[0], 1.0, 1e-6);
    EXPECT_NEAR(r.x[1], 1.0, 1e-6);
    EXPECT_LE(r.grad.lpNorm<Eigen::Infinity>(), 1e-8);
    // scipy needs 32-34 iterations here; a broken line search or update needs far more.
    EXPECT_LT(r.iterations, 60);
}

TEST(Bfgs, SolvesAQuadraticInAFewIterations) {
    Eigen::MatrixXd A(4, 4);
    A << 4, 1, 0, 0, 1, 3, 0.5, 0, 0, 0.5, 2, 0.2, 0, 0, 0.2, 1;
    const Eigen::VectorXd b = Eigen::Vector4d(1, -2, 0.5, 3);
    auto quad = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
        g = A * x - b;
        return 0.5 * x.dot(A * x) - b.dot(x);
    };
    BfgsOptions options;
    options.gtol = 1e-10;
    const BfgsResult r = MinimizeBfgs(quad, Eigen::VectorXd::Zero(4), options);
    EXPECT_EQ(r.stop_reason, "converged");
    EXPECT_LT((r.x - A.ldlt().solve(b)).norm(), 1e-9);
    EXPECT_LE(r.iterations, 12);
}

TEST(Bfgs, FirstTrialStepIsScipys) {
    // f = |x|^2 / 2 from x0 = (10, 0): |g0| = 10, first trial step min(1, 1.01 / 10) = 0.101,
    // which satisfies the strong Wolfe conditions, so the first iterate is x0 (1 - 0.101).
    int calls = 0;
    Eigen::VectorXd first_trial;
    auto f = [&](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
        if (++calls == 2) first_trial = x;
        g = x;
        return 0.5 * x.squaredNorm();
    };
    BfgsOptions options;
    options.maxiter = 1;
    const BfgsResult r = MinimizeBfgs(f, Eigen::Vector2d(10.0, 0.0), options);
    EXPECT_NEAR(first_trial[0], 10.0 * (1.0 - 0.101), 1e-12);
    EXPECT_NEAR(r.x[0], 10.0 * (1.0 - 0.101), 1e-12);
    EXPECT_EQ(r.iterations, 1);
    EXPECT_EQ(r.stop_reason, "max_iterations");
}

TEST(Bfgs, ReportsMaxIterations) {
    const BfgsResult r = MinimizeRosenbrock(/*maxiter=*/3, /*gtol=*/1e-12);
    EXPECT_EQ(r.stop_reason, "max_iterations");
    EXPECT_EQ(r.iterations, 3);
}

TEST(Bfgs, ReportsLineSearchFailureOnAWrongGradient) {
    // The gradient points uphill, so the search direction is not a descent direction and
    // dcsrch stops with "ERROR: INITIAL G .GE. ZERO".
    auto wrong = [](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
        g = -x;
        return 0.5 * x.squaredNorm();
    };
    const BfgsResult r = MinimizeBfgs(wrong, Eigen::Vector2d(1.0, 2.0), BfgsOptions{});
    EXPECT_EQ(r.stop_reason, "line_search_failed");
    EXPECT_EQ(r.iterations, 0);
}

TEST(MoreThuente, AcceptedStepSatisfiesStrongWolfe) {
    // phi(a) = f(x + a p) for the Rosenbrock function along the steepest-descent direction.
    const Eigen::VectorXd x = Eigen::Vector2d(-1.2, 1.0);
    Eigen::VectorXd g0;
    const double f0 = Rosenbrock(x, g0);
    const Eigen::VectorXd p = -g0;
    BfgsOptions options;
    const LineSearchResult ls = MoreThuenteSearch(Rosenbrock, x, p, f0, g0, 1.0, options);
    ASSERT_TRUE(ls.ok) << ls.task;
    EXPECT_LE(ls.f, f0 + options.c1 * ls.step * g0.dot(p));
    EXPECT_LE(std::abs(ls.grad.dot(p)), options.c2 * std::abs(g0.dot(p)));
}

}  // namespace
}  // namespace regbench
