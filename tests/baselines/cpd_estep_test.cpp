// The fused CPD E-step (baselines/cpd.hpp) against a brute-force double E-step that stores P.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>

#include "baselines/cpd.hpp"
#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"

namespace regbench {
namespace {

constexpr double kSumRelTol = 2e-5;  // float kernels, double accumulation
constexpr double kThreadTol = 1e-9;  // results must not depend on the thread count

/// Brute-force double CPD E-step, P stored in full (the reference).
struct BruteCpd {
    Eigen::MatrixXd P;  // M x N
    Eigen::VectorXd den;
};
BruteCpd BruteForceCpd(const PointCloud& Yhat, const PointCloud& X, double sigma2, double c) {
    BruteCpd b;
    const Eigen::Index m = Yhat.rows(), n = X.rows();
    Eigen::MatrixXd K(m, n);
    for (Eigen::Index i = 0; i < m; ++i) {
        for (Eigen::Index j = 0; j < n; ++j) {
            K(i, j) = std::exp(-(Yhat.row(i) - X.row(j)).squaredNorm() / (2.0 * sigma2));
        }
    }
    b.den = K.colwise().sum().transpose();
    for (Eigen::Index j = 0; j < n; ++j) {
        if (b.den[j] == 0.0) b.den[j] = CpdEStep::kDenFloor;
    }
    b.den.array() += c;
    b.P = K * b.den.cwiseInverse().asDiagonal();
    return b;
}

double MaxRelDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    return (a - b).cwiseAbs().maxCoeff() / std::max(b.cwiseAbs().maxCoeff(), 1e-300);
}

/// Source Y and target X: independent samples of the smooth blob, `m` and `n` points, from
/// one seeded stream; T is the motion the E-steps apply to Y.
struct BlobPair {
    PointCloud Y, X;
    Transform T;
};
BlobPair MakeBlobPair(std::uint64_t seed, Eigen::Index m, Eigen::Index n, const Transform& T) {
    auto rng = MakePairRng(seed, 0);
    BlobPair p;
    p.Y = SmoothBlobSurface(rng, m);
    p.X = SmoothBlobSurface(rng, n);
    p.T = T;
    return p;
}

/// Options forcing the dense E-step (the reference the approximations are compared with).
GaussSumOptions DenseOptions() {
    GaussSumOptions opt;
    opt.mode = GaussSumMode::kDense;
    return opt;
}

TEST(CpdEStep, MatchesBruteForceAndColumnIdentity) {
    auto rng = MakePairRng(5, 0);
    const PointCloud Y = SmoothBlobSurface(rng, 400);
    PointCloud X = SmoothBlobSurface(rng, 350);
    X.row(0) << 40.0, 40.0, 40.0;  // far away: its column underflows and takes the den floor
    const Transform T = MakeTransform(0.9 * RotationFromAxisAngle({1, 2, 3}, 0.4), {0.1, 0, -0.2});
    const PointCloud Yhat = Apply(T, Y);
    for (GaussSumMode mode : {GaussSumMode::kDense, GaussSumMode::kAuto}) {
        GaussSumOptions opt;
        opt.mode = mode;
        CpdEStep e_step(Y, X, opt);
        for (double sigma2 : {0.3, 0.01}) {
            const double c = 0.05;
            CpdPosteriors post;
            e_step.Compute(T, sigma2, c, post);
            const BruteCpd ref = BruteForceCpd(Yhat, X, sigma2, c);
            const Eigen::VectorXd p1 = ref.P.rowwise().sum();
            const Eigen::VectorXd pt1 = ref.P.colwise().sum().transpose();
            const Eigen::MatrixXd px = ref.P * X;
            EXPECT_LT(MaxRelDiff(post.p1, p1), kSumRelTol);
            EXPECT_LT(MaxRelDiff(post.pt1, pt1), kSumRelTol);
            EXPECT_LT(MaxRelDiff(post.px, px), kSumRelTol);
            EXPECT_NEAR(post.np, p1.sum(), kSumRelTol * p1.sum());
            // sum_m P_mn = 1 - c / den_n, den_n including c.
            const Eigen::VectorXd identity = (1.0 - c * ref.den.cwiseInverse().array()).matrix();
            EXPECT_LT((post.pt1 - identity).cwiseAbs().maxCoeff(), kSumRelTol);
            EXPECT_NEAR(post.pt1[0], CpdEStep::kDenFloor / (CpdEStep::kDenFloor + c), 1e-12);
            EXPECT_FALSE(post.truncated);
        }
    }
}

TEST(CpdEStep, ThreadCountDoesNotChangeResults) {
    const auto [Y, X, T] = MakeBlobPair(
        7, 1500, 1400, MakeTransform(RotationFromAxisAngle({0, 0, 1}, 0.3), {0.05, 0, 0}));
    CpdEStep e_step(Y, X);
    const int saved = omp_get_max_threads();
    CpdPosteriors one, two;
    omp_set_num_threads(1);
    e_step.Compute(T, 0.02, 0.01, one);
    omp_set_num_threads(2);
    e_step.Compute(T, 0.02, 0.01, two);
    omp_set_num_threads(saved);
    EXPECT_LT((one.p1 - two.p1).cwiseAbs().maxCoeff(), kThreadTol);
    EXPECT_LT((one.pt1 - two.pt1).cwiseAbs().maxCoeff(), kThreadTol);
    EXPECT_LT((one.px - two.px).cwiseAbs().maxCoeff(), kThreadTol);
}

TEST(CpdEStep, TruncatedAgreesWithDenseOnLargerCloud) {
    const auto [Y, X, T] = MakeBlobPair(
        9, 6000, 6000, MakeTransform(RotationFromAxisAngle({0, 1, 0}, 0.05), {0.01, 0, 0}));
    GaussSumOptions trunc_opt;
    trunc_opt.mode = GaussSumMode::kTruncated;
    CpdEStep dense(Y, X, DenseOptions()), trunc(Y, X, trunc_opt);
    const double sigma2 = 1e-3;  // sigma ~ 0.03: 4 sigma is well inside the shape
    CpdPosteriors a, b;
    dense.Compute(T, sigma2, 0.0, a);
    trunc.Compute(T, sigma2, 0.0, b);
    EXPECT_TRUE(b.truncated);
    EXPECT_LT(b.evaluated_pairs, a.evaluated_pairs);
    // Truncation at 4 sigma drops Gaussian tail mass of order exp(-8) per neighbour.
    EXPECT_LT(MaxRelDiff(b.p1, a.p1), 5e-3);
    EXPECT_LT(MaxRelDiff(b.px, a.px), 5e-3);
    EXPECT_NEAR(b.np, a.np, 1e-3 * a.np);
}

TEST(CpdEStep, AutoSwitchRule) {
    auto rng = MakePairRng(11, 0);
    const PointCloud Y = SmoothBlobSurface(rng, 100);
    GaussSumOptions opt;
    opt.truncation_min_points = 50;
    CpdEStep e_step(Y, Y, opt);
    // Target bbox diagonal ~ 2.4: r = 4 sigma must be below ~0.6.
    EXPECT_FALSE(e_step.UsesTruncation(0.1));  // r = 1.26
    EXPECT_TRUE(e_step.UsesTruncation(0.01));  // r = 0.4
    opt.truncation_min_points = 101;
    EXPECT_FALSE(CpdEStep(Y, Y, opt).UsesTruncation(0.01));
}

}  // namespace
}  // namespace regbench

namespace regbench {
namespace {

TEST(CpdEStep, CellCompressedAgreesWithDenseWhileSigmaIsLarge) {
    // Reference: the dense E-step (itself checked against brute force above). Compression with
    // cells of 0.25 sigma is second order in the cell size: ~1% on p1, px and Np.
    const auto [Y, X, T] = MakeBlobPair(
        19, 8000, 8000, MakeTransform(RotationFromAxisAngle({0, 1, 0}, 0.2), {0.05, 0, 0}));
    GaussSumOptions auto_opt;
    auto_opt.cluster_min_points = 1000;
    auto_opt.truncation_min_points = 1000;
    CpdEStep dense(Y, X, DenseOptions()), approx(Y, X, auto_opt);
    for (const double sigma2 : {0.3, 0.05}) {
        CpdPosteriors a, b;
        dense.Compute(T, sigma2, 1e-3, a);
        approx.Compute(T, sigma2, 1e-3, b);
        EXPECT_GT(b.compressed_cells, 0) << sigma2;
        EXPECT_LT(b.evaluated_pairs, a.evaluated_pairs / 4) << sigma2;
        EXPECT_NEAR(b.np, a.np, 0.01 * a.np) << sigma2;
        EXPECT_LT(MaxRelDiff(b.p1, a.p1), 0.02) << sigma2;
        EXPECT_LT(MaxRelDiff(b.pt1, a.pt1), 0.02) << sigma2;
        // PX rows relative to their p1 (the posterior-weighted target mean of each source point).
        const PointCloud mean_a = a.px.array().colwise() / a.p1.array();
        const PointCloud mean_b = b.px.array().colwise() / b.p1.array();
        EXPECT_LT((mean_a - mean_b).cwiseAbs().maxCoeff(), 0.02 * std::sqrt(sigma2)) << sigma2;
    }
    // Dense mode never compresses.
    CpdPosteriors d;
    dense.Compute(T, 0.3, 0.0, d);
    EXPECT_EQ(d.compressed_cells, 0);
}

}  // namespace
}  // namespace regbench
