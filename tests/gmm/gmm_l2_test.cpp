#include "gmm/gmm_l2.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.hpp"
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

TEST(GmmL2, CompatGradientIsHalfTheNumericGradient) {
    auto rng = MakePairRng(7, 0);
    const MixtureFeatures s = RandomMixture(rng, 40), t = RandomMixture(rng, 50);
    const RigidGmmL2Cost cost(s, t, 0.4, L2Gradient::kProbregHalf);
    Eigen::VectorXd g;
    cost(OffUnitTheta(), g);
    const Eigen::VectorXd numeric = NumericGradient(cost, OffUnitTheta());
    ASSERT_GT(numeric.norm(), 1e-2);  // a test that can fail
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(g[k], 0.5 * numeric[k], 1e-6) << "k = " << k;
}

TEST(GmmL2, ExactGradientMatchesTheNumericGradient) {
    auto rng = MakePairRng(8, 0);
    const MixtureFeatures s = RandomMixture(rng, 40), t = RandomMixture(rng, 50);
    const RigidGmmL2Cost cost(s, t, 0.3, L2Gradient::kExact);
    Eigen::VectorXd g;
    cost(OffUnitTheta(), g);
    const Eigen::VectorXd numeric = NumericGradient(cost, OffUnitTheta());
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(g[k], numeric[k], 1e-6) << "k = " << k;
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
