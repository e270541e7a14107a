#include "runners/align_clouds.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/metrics.hpp"
#include "core/transform.hpp"
#include "runners/registry.hpp"
#include "tests/testing/synthetic.hpp"

namespace regbench {
namespace {

TEST(AlignClouds, DenormalizeInvertsTheNormalization) {
    // Hand check: with x' = s (x - c), a transform [R | t'] between normalised clouds is
    // [R | t' / s - R c + c] between the originals. Build target = R source + t, normalise both
    // and verify the denormalised ground truth of the normalised pair is the original one.
    const Transform T = MakeTransform(RotationXyzProductDeg(10, -20, 30), {3.0, -1.0, 2.0});
    PointCloud source(4, 3);
    source << 0, 0, 0, 10, 0, 0, 0, 20, 0, 0, 0, 5;
    const PointCloud target = Apply(T, source);
    const Normalization n = FitNormalization(source, target);
    const PointCloud ns = Normalize(source, n);
    const PointCloud nt = Normalize(target, n);
    EXPECT_NEAR(std::max(ns.rowwise().norm().maxCoeff(), nt.rowwise().norm().maxCoeff()), 1.0,
                1e-12);
    // The normalised pair's own transform (rotation unchanged, translation nt - R ns).
    Transform Tn = T;
    Tn.topRightCorner<3, 1>() =
        (nt.row(0) - ns.row(0) * T.topLeftCorner<3, 3>().transpose()).transpose();
    EXPECT_LT((Denormalize(Tn, n) - T).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(AlignClouds, NormalizeMakesTheResultIndependentOfUnits) {
    // The same pair in other units (x100, shifted): with --normalize ICP sees the same clouds
    // up to rounding, so its result is the unit-scale one conjugated by the change of units.
    const Pair pair = testing::SyntheticPair(
        200, 3, MakeTransform(RotationXyzProductDeg(8, -5, 12), {0.05, -0.02, 0.04}));
    const Eigen::RowVector3d shift(500, -200, 30);
    const PointCloud big_source = (pair.source * 100.0).rowwise() + shift;
    const PointCloud big_target = (pair.target * 100.0).rowwise() + shift;
    auto icp = CreateMethod("icp", {});
    const AlignResult small = AlignClouds(*icp, pair.source, pair.target, true, AlignContext{});
    const AlignResult big = AlignClouds(*icp, big_source, big_target, true, AlignContext{});
    ASSERT_EQ(small.status, AlignStatus::kOk);
    ASSERT_EQ(big.status, AlignStatus::kOk);
    const Eigen::Matrix3d R = small.T_target_source.topLeftCorner<3, 3>();
    EXPECT_LT((big.T_target_source.topLeftCorner<3, 3>() - R).cwiseAbs().maxCoeff(), 1e-6);
    const Eigen::Vector3d c = shift.transpose();
    const Eigen::Vector3d expected_t =
        100.0 * small.T_target_source.topRightCorner<3, 1>() + c - R * c;
    EXPECT_LT((big.T_target_source.topRightCorner<3, 1>() - expected_t).norm(), 1e-4);
    // And ICP moved towards the truth (so the comparison above is not between two identities).
    EXPECT_LT(MotionMetrics(pair.T_gt, small.T_target_source).rre,
              MotionMetrics(pair.T_gt, Transform::Identity()).rre);
}

}  // namespace
}  // namespace regbench
