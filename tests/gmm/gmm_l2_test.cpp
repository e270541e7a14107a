#include "gmm/gmm_l2.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <set>

#include "core/math_constants.hpp"
#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"
#include "core/transform.hpp"

namespace regbench {
namespace {

MixtureFeatures RandomMixture(std::mt19937_64& rng, int n) {
    MixtureFeatures m;
    m.means.resize(n, 3);
    m.weights.resize(n);
    for (int i = 0; i < n; ++i) {
        for (int d = 0; d < 3; ++d) m.means(i, d) = 0.5 * StandardNormal(rng);
        m.weights[i] = UniformReal(rng, 0.1, 1.0);
    }
    return m;
}

Eigen::VectorXd NumericGradient(const RigidGmmL2Cost& cost, const Eigen::VectorXd& theta) {
    constexpr double kStep = 1e-6;
    Eigen::VectorXd g(7), unused;
    for (int k = 0; k < 7; ++k) {
        Eigen::VectorXd a = theta, b = theta;
        a[k] += kStep;
        b[k] -= kStep;
        g[k] = (cost(a, unused) - cost(b, unused)) / (2.0 * kStep);
    }
    return g;
}

Eigen::VectorXd OffUnitTheta() {
    Eigen::VectorXd theta(7);
    theta << 0.9, 0.2, -0.3, 0.15, 0.1, -0.2, 0.05;  // |q| = 0.99..., not 1
    return theta;
}

/// On random mixtures of 40 and 50 components (drawn from `seed`), the cost's gradient at
/// OffUnitTheta is `factor` times the central-difference gradient.
void ExpectGradientIsScaledNumeric(std::uint64_t seed, double sigma, L2Gradient gradient,
                                   double factor) {
    auto rng = MakePairRng(seed, 0);
    const MixtureFeatures s = RandomMixture(rng, 40), t = RandomMixture(rng, 50);
    const RigidGmmL2Cost cost(s, t, sigma, gradient);
    Eigen::VectorXd g;
    cost(OffUnitTheta(), g);
    const Eigen::VectorXd numeric = NumericGradient(cost, OffUnitTheta());
    ASSERT_GT(numeric.norm(), 1e-2);  // a test that can fail
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(g[k], factor * numeric[k], 1e-6) << "k = " << k;
}

TEST(GmmL2, CompatGradientIsHalfTheNumericGradient) {
    ExpectGradientIsScaledNumeric(7, 0.4, L2Gradient::kProbregHalf, 0.5);
}

TEST(GmmL2, ExactGradientMatchesTheNumericGradient) {
    ExpectGradientIsScaledNumeric(8, 0.3, L2Gradient::kExact, 1.0);
}

TEST(GmmL2, CostMatchesBruteForce) {
    auto rng = MakePairRng(9, 0);
    const MixtureFeatures s = RandomMixture(rng, 7), t = RandomMixture(rng, 9);
    const double sigma = 0.5;
    const RigidGmmL2Cost cost(s, t, sigma, L2Gradient::kExact);
    const Eigen::VectorXd theta = OffUnitTheta();
    const Transform T = TransformFromTheta(theta);
    const double z = std::pow(2.0 * M_PI * sigma * sigma, 1.5);
    double expected = 0.0;
    for (int i = 0; i < 7; ++i) {
        const Eigen::Vector3d x =
            T.topLeftCorner<3, 3>() * s.means.row(i).transpose() + T.topRightCorner<3, 1>();
        for (int j = 0; j < 9; ++j) {
            const double d2 = (x - t.means.row(j).transpose()).squaredNorm();
            expected -= s.weights[i] * t.weights[j] / z * std::exp(-d2 / (2 * sigma * sigma));
        }
    }
    Eigen::VectorXd g;
    EXPECT_NEAR(cost(theta, g), expected, 1e-14);
}

TEST(GmmL2, QuaternionRotationIsNormalisedAndMatchesAxisAngle) {
    const double angle = 0.7;
    const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -1).normalized();
    Eigen::Vector4d q;
    q << std::cos(angle / 2), std::sin(angle / 2) * axis;
    const Eigen::Matrix3d expected = RotationFromAxisAngle(axis, angle);
    EXPECT_LT((RotationFromQuaternionWxyz(3.0 * q) - expected).norm(), 1e-12);
    EXPECT_TRUE(IsRotation(RotationFromQuaternionWxyz(Eigen::Vector4d(0.3, -2, 0.1, 5))));
}

TEST(GmmL2, RotationDerivativeMatchesFiniteDifferences) {
    const Eigen::Vector4d q(0.8, -0.4, 0.3, 0.9);
    const auto dR = RotationDerivativeFromQuaternionWxyz(q);
    for (int k = 0; k < 4; ++k) {
        Eigen::Vector4d a = q, b = q;
        a[k] += 1e-6;
        b[k] -= 1e-6;
        const Eigen::Matrix3d numeric =
            (RotationFromQuaternionWxyz(a) - RotationFromQuaternionWxyz(b)) / 2e-6;
        EXPECT_LT((dR[k] - numeric).norm(), 1e-8) << "k = " << k;
    }
}

}  // namespace
}  // namespace regbench

namespace regbench {
namespace {

TEST(RigidGmmL2Cost, CutoffSumsEqualDenseWithinTheStatedTolerance) {
    // Every skipped term has e_ij < tol, so |f_cut - f_dense| <= tol * sum_ij phi_i phi_j / Z
    // (hand derivation). Its translation gradient term (exact mode) is
    // phi_i phi_j / Z e_ij (x_i - mu_j) / sigma^2, of size <= tol * r / sigma^2 * phi phi / Z for
    // d >= r > sigma, giving the gradient bound below.
    for (const std::uint64_t seed : {1u, 2u, 3u}) {
        auto rng = MakePairRng(seed, 0);
        const MixtureFeatures s = RandomMixture(rng, 600);
        const MixtureFeatures t = RandomMixture(rng, 500);
        const double sigma = 0.15;
        const double tol = 1e-4;
        const double r = sigma * CutoffRadiusSigmas(tol);
        EXPECT_NEAR(r / sigma, std::sqrt(2.0 * std::log(1e4)), 1e-12);  // 4.29 sigma
        const RigidGmmL2Cost dense(s, t, sigma, L2Gradient::kExact);
        const RigidGmmL2Cost cut(s, t, sigma, L2Gradient::kExact, r);
        const Eigen::VectorXd theta = OffUnitTheta();
        Eigen::VectorXd gd, gc;
        const double fd = dense(theta, gd);
        const double fc = cut(theta, gc);
        const double weight_sum =
            s.weights.sum() * t.weights.sum() / std::pow(2.0 * kPi * sigma * sigma, 1.5);
        EXPECT_LE(std::abs(fc - fd), tol * weight_sum) << seed;
        EXPECT_GT(std::abs(fc - fd), 0.0) << seed;  // something was cut off
        EXPECT_LE((gc.segment<3>(4) - gd.segment<3>(4)).norm(),
                  std::sqrt(3.0) * tol * r / (sigma * sigma) * weight_sum)
            << seed;
    }
}

TEST(MinimizeRigidL2, ApproximatedSumsLandNearDenseOptimum) {
    // Reference: the dense run on the same mixtures. Compression at 0.1 sigma and the 1e-4
    // cutoff shift the optimum by far less than 0.5 degrees.
    auto rng = MakePairRng(7, 0);
    MixtureFeatures s{SmoothBlobSurface(rng, 2000), Eigen::VectorXd::Constant(2000, 1.0 / 2000)};
    const Eigen::Matrix3d R = RotationFromAxisAngle({0.2, 1, 0.1}, 0.3);
    MixtureFeatures t{Apply(MakeTransform(R, {0.05, 0.0, 0.02}), s.means), s.weights};
    BfgsOptions bfgs;
    bfgs.maxiter = 200;
    bfgs.gtol = 1e-6;
    L2SumOptions dense_sums, approx_sums;
    dense_sums.kernel_sums = L2KernelSums::kDense;
    approx_sums.min_pairs = 0;
    bool approximated = false;
    // sigma 0.1: the 4.29-sigma cutoff (0.43) is below a quarter of the blob's bounding-box
    // diagonal (~0.65), so PlanL2Sums uses it.
    const double sigma = 0.1;
    const BfgsResult a = MinimizeRigidL2(s, t, sigma, L2Gradient::kExact,
                                         RigidGmmL2Cost::InitialTheta(), bfgs, dense_sums);
    const BfgsResult b =
        MinimizeRigidL2(s, t, sigma, L2Gradient::kExact, RigidGmmL2Cost::InitialTheta(), bfgs,
                        approx_sums, &approximated);
    EXPECT_TRUE(approximated);
    const Eigen::Matrix3d Ra = TransformFromTheta(a.x).topLeftCorner<3, 3>();
    const Eigen::Matrix3d Rb = TransformFromTheta(b.x).topLeftCorner<3, 3>();
    EXPECT_LT(RotationAngleDeg(Ra, Rb), 0.5);
    EXPECT_LT(RotationAngleDeg(Ra, R), 0.5);
}

// PlanL2Sums' rules, with the expected decisions computed here independently: occupied cells
// counted with a std::set of floor(x / cell) triples, the bounding box from the coordinates.
std::size_t OccupiedCells(const PointCloud& p, double cell) {
    std::set<std::array<long, 3>> cells;
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
        cells.insert({static_cast<long>(std::floor(p(i, 0) / cell)),
                      static_cast<long>(std::floor(p(i, 1) / cell)),
                      static_cast<long>(std::floor(p(i, 2) / cell))});
    }
    return cells.size();
}

double BoxDiagonal(const PointCloud& p) {
    return (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm();
}

TEST(PlanL2Sums, CompressesOnlyWhenItHalvesTheComponentsAndCutsOffOnlyBelowAQuarterDiagonal) {
    auto rng = MakePairRng(11, 0);
    const int n = 4000;
    MixtureFeatures s{SmoothBlobSurface(rng, n), Eigen::VectorXd::Constant(n, 1.0 / n)};
    const MixtureFeatures t = s;
    const double diagonal = BoxDiagonal(t.means);
    const double radius_sigmas = CutoffRadiusSigmas(1e-4);
    L2SumOptions sums;
    sums.min_pairs = 0;
    struct Case {
        double sigma;
        double cell_sigmas;
    };
    // Coarse cells at a large sigma, fine cells at a small sigma, and one sigma whose cutoff
    // radius covers the whole cloud.
    for (const Case c : {Case{0.3, 0.5}, Case{0.02, 0.1}, Case{1.0, 0.25}, Case{0.1, 0.25}}) {
        sums.compress_cell_sigmas = c.cell_sigmas;
        const L2SumsPlan plan = PlanL2Sums(s, t, c.sigma, sums);
        const std::size_t cells = OccupiedCells(s.means, c.cell_sigmas * c.sigma);
        const bool expect_compress = 2 * cells <= static_cast<std::size_t>(n);
        const bool expect_cutoff = c.sigma * radius_sigmas < 0.25 * diagonal;
        SCOPED_TRACE(testing::Message() << "sigma " << c.sigma << ", cells " << cells);
        EXPECT_EQ(plan.compressed_source, expect_compress);
        EXPECT_EQ(plan.compressed_target, expect_compress);
        EXPECT_EQ(plan.source.means.rows(), expect_compress ? static_cast<Eigen::Index>(cells) : n);
        EXPECT_EQ(std::isfinite(plan.cutoff_radius), expect_cutoff);
        EXPECT_EQ(plan.approximated(), expect_compress || expect_cutoff);
    }
    // The cases above must cover both outcomes of both rules, or the test proves little.
    sums.compress_cell_sigmas = 0.5;
    EXPECT_TRUE(PlanL2Sums(s, t, 0.3, sums).compressed_source);
    sums.compress_cell_sigmas = 0.1;
    EXPECT_FALSE(PlanL2Sums(s, t, 0.02, sums).compressed_source);
    EXPECT_TRUE(std::isfinite(PlanL2Sums(s, t, 0.02, sums).cutoff_radius));
    EXPECT_FALSE(std::isfinite(PlanL2Sums(s, t, 1.0, sums).cutoff_radius));
    // Below min_pairs nothing is approximated.
    sums.min_pairs = 1e12;
    EXPECT_FALSE(PlanL2Sums(s, t, 0.02, sums).approximated());
}

}  // namespace
}  // namespace regbench
