#include "core/metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/transform.hpp"

namespace regbench {
namespace {

constexpr double kTol = 1e-9;

TEST(Metrics, RotationErrorsMatchHandComputation) {
    // R_gt = Rz(30) Ry(20) Rx(10) has scipy zyx angles (30, 20, 10); R_est = Rz(25) Ry(20) Rx(16)
    // gives |dz| = 5, |dy| = 0, |dx| = 6: mae_r = 11/3, mse_r = (25 + 36) / 3.
    const Transform T_gt = MakeTransform(RotationFromEulerZyxDeg(30, 20, 10), {0.1, 0.2, 0.3});
    const Transform T_est = MakeTransform(RotationFromEulerZyxDeg(25, 20, 16), {0.1, 0.0, 0.0});
    const PairMetrics m = MotionMetrics(T_gt, T_est);
    EXPECT_NEAR(m.mae_r, 11.0 / 3.0, kTol);
    EXPECT_NEAR(m.mse_r, 61.0 / 3.0, kTol);
    // t error (0, 0.2, 0.3): mae_t = 0.5 / 3, rte = sqrt(0.13), mse_t = 0.13 / 3.
    EXPECT_NEAR(m.mae_t, 0.5 / 3.0, kTol);
    EXPECT_NEAR(m.rte, std::sqrt(0.13), kTol);
    EXPECT_NEAR(m.mse_t, 0.13 / 3.0, kTol);
}

TEST(Metrics, RreOfKnownAxisAngle) {
    const Transform T_gt = Transform::Identity();
    const Transform T_est = MakeTransform(RotationFromAxisAngle({0, 0, 1}, 7.5 * M_PI / 180.0),
                                          Eigen::Vector3d::Zero());
    EXPECT_NEAR(MotionMetrics(T_gt, T_est).rre, 7.5, 1e-9);
    // About z only, the zyx angles differ in z alone: mae_r = 7.5 / 3.
    EXPECT_NEAR(MotionMetrics(T_gt, T_est).mae_r, 2.5, 1e-9);
}

TEST(Metrics, EulerDifferenceIsNotWrapped) {
    // z = 179 vs z = -179: the paper's metric takes |179 - (-179)| = 358, not 2.
    const Transform a = MakeTransform(RotationFromEulerZyxDeg(179, 0, 0), Eigen::Vector3d::Zero());
    const Transform b = MakeTransform(RotationFromEulerZyxDeg(-179, 0, 0), Eigen::Vector3d::Zero());
    EXPECT_NEAR(MotionMetrics(a, b).mae_r, 358.0 / 3.0, 1e-9);
    EXPECT_NEAR(MotionMetrics(a, b).rre, 2.0, 1e-9);
}

TEST(Metrics, ClippedChamferMatchesHandComputation) {
    // a = {(0,0,0), (1,0,0)}, b = {(0,0,0.05)}: a->b distances 0.05 and sqrt(1.0025) (clipped to
    // 0.1); b->a distance 0.05. ccd = (0.05 + 0.1) / 2 + 0.05 = 0.125.
    PointCloud a(2, 3);
    a << 0, 0, 0, 1, 0, 0;
    PointCloud b(1, 3);
    b << 0, 0, 0.05;
    const ChamferResult c = ChamferDistances(a, b);
    EXPECT_NEAR(c.ccd, 0.125, kTol);
    EXPECT_NEAR(c.chamfer, (0.0025 + 1.0025) / 2.0 + 0.0025, kTol);
    EXPECT_FALSE(c.within_clip);  // mean a->b distance ~0.53 > 0.1
}

TEST(Metrics, PerfectEstimateGivesZeroErrors) {
    PointCloud src(4, 3);
    src << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    const Transform T = MakeTransform(RotationFromEulerZyxDeg(40, -20, 10), {0.3, -0.1, 0.2});
    const PairMetrics m = ComputeMetrics(T, T, src, Apply(T, src));
    EXPECT_NEAR(m.mae_r, 0.0, 1e-9);
    EXPECT_NEAR(m.rre, 0.0, 1e-5);
    EXPECT_NEAR(m.ccd, 0.0, 1e-12);
    EXPECT_NEAR(m.chamfer, 0.0, 1e-12);
    EXPECT_TRUE(m.ccd_within_clip);
}

}  // namespace
}  // namespace regbench

namespace regbench {
namespace {

TEST(Metrics, ScaleIsDividedOutOfRotationErrors) {
    // A similarity estimate 1.3 * R_gt has the right rotation: rotation errors are zero.
    const Eigen::Matrix3d R = RotationFromEulerZyxDeg(20, 10, 5);
    const Transform T_gt = MakeTransform(R, {0.1, 0.2, 0.3});
    const Transform T_est = MakeTransform(1.3 * R, {0.1, 0.2, 0.3});
    const PairMetrics m = MotionMetrics(T_gt, T_est);
    EXPECT_NEAR(m.mae_r, 0.0, 1e-9);
    EXPECT_NEAR(m.rre, 0.0, 1e-5);
}

}  // namespace
}  // namespace regbench
