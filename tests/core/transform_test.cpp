#include "core/transform.hpp"

#include <gtest/gtest.h>

#include <random>

#include "core/rng.hpp"

namespace regbench {
namespace {

constexpr double kTol = 1e-12;

TEST(Transform, EulerZyxMatchesHandComputedMatrix) {
    // Rz(90) maps x to y; scipy: R.from_euler('zyx', [90, 0, 0], degrees=True).
    const Eigen::Matrix3d R = RotationFromEulerZyxDeg(90.0, 0.0, 0.0);
    EXPECT_NEAR(R(0, 0), 0.0, kTol);
    EXPECT_NEAR(R(1, 0), 1.0, kTol);
    EXPECT_NEAR(R(0, 1), -1.0, kTol);
    // scipy.spatial.transform.Rotation.from_euler('zyx', [30, 20, 10], degrees=True).as_matrix()
    const Eigen::Matrix3d Q = RotationFromEulerZyxDeg(30.0, 20.0, 10.0);
    EXPECT_NEAR(Q(0, 0), 0.81379768, 1e-8);
    EXPECT_NEAR(Q(0, 1), -0.44096961, 1e-8);
    EXPECT_NEAR(Q(0, 2), 0.37852231, 1e-8);
    EXPECT_NEAR(Q(1, 0), 0.46984631, 1e-8);
    EXPECT_NEAR(Q(1, 1), 0.88256412, 1e-8);
    EXPECT_NEAR(Q(1, 2), 0.01802831, 1e-8);
    EXPECT_NEAR(Q(2, 0), -0.34202014, 1e-8);
    EXPECT_NEAR(Q(2, 1), 0.16317591, 1e-8);
    EXPECT_NEAR(Q(2, 2), 0.92541658, 1e-8);
}

TEST(Transform, EulerZyxRoundTrips) {
    std::mt19937_64 rng(7);
    for (int i = 0; i < 100; ++i) {
        const double z = UniformReal(rng, -179.0, 179.0);
        const double y = UniformReal(rng, -89.0, 89.0);
        const double x = UniformReal(rng, -179.0, 179.0);
        const Eigen::Vector3d e = EulerZyxDegFromRotation(RotationFromEulerZyxDeg(z, y, x));
        EXPECT_NEAR(e[0], z, 1e-9);
        EXPECT_NEAR(e[1], y, 1e-9);
        EXPECT_NEAR(e[2], x, 1e-9);
    }
}

TEST(Transform, PaperMotionIsXyzProduct) {
    const Eigen::Matrix3d R = RotationXyzProductDeg(10.0, 20.0, 30.0);
    const Eigen::Matrix3d expected =
        RotationFromAxisAngle(Eigen::Vector3d::UnitX(), 10.0 * M_PI / 180.0) *
        RotationFromAxisAngle(Eigen::Vector3d::UnitY(), 20.0 * M_PI / 180.0) *
        RotationFromAxisAngle(Eigen::Vector3d::UnitZ(), 30.0 * M_PI / 180.0);
    EXPECT_LT((R - expected).cwiseAbs().maxCoeff(), kTol);
}

TEST(Transform, InvertComposeApply) {
    const Transform T = MakeTransform(RotationFromEulerZyxDeg(10, 20, 30), {0.1, -0.2, 0.3});
    EXPECT_LT((Compose(T, InvertRigid(T)) - Transform::Identity()).cwiseAbs().maxCoeff(), kTol);
    PointCloud p(2, 3);
    p << 1, 0, 0, 0, 1, 0;
    const PointCloud q = Apply(T, p);
    const Eigen::Vector3d q0 =
        T.topLeftCorner<3, 3>() * Eigen::Vector3d(1, 0, 0) + T.topRightCorner<3, 1>();
    EXPECT_LT((q.row(0).transpose() - q0).norm(), kTol);
    EXPECT_LT((Apply(InvertRigid(T), q) - p).cwiseAbs().maxCoeff(), kTol);
}

TEST(Transform, RotationAngleOfKnownRotation) {
    const Eigen::Matrix3d R = RotationFromAxisAngle({1, 1, 0}, 0.5);
    EXPECT_NEAR(RotationAngleDeg(Eigen::Matrix3d::Identity(), R), 0.5 * 180.0 / M_PI, 1e-9);
    EXPECT_TRUE(IsRotation(R));
    EXPECT_FALSE(IsRotation(2.0 * R));
    EXPECT_FALSE(IsRotation(-R));
}

TEST(Rng, PairStreamDependsOnlyOnSeedAndIndex) {
    auto a = MakePairRng(42, 17);
    auto b = MakePairRng(42, 17);
    auto c = MakePairRng(42, 18);
    auto d = MakePairRng(43, 17);
    const auto va = a();
    EXPECT_EQ(va, b());
    EXPECT_NE(va, c());
    EXPECT_NE(va, d());
}

}  // namespace
}  // namespace regbench
