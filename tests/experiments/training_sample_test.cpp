// A protocol pair as the trainer takes it (experiments/training_bundle.cpp ToTrainSample): in
// the frame the learned methods run in, so a network trained on indoor scans in their camera
// frame sees at training what it sees at inference (core/pair_normalization.hpp).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "experiments/training_bundle.hpp"

namespace regbench {
namespace {

/// A noise-free pair y_i = R x_i + t of `n` points with the given source centre and spread.
Pair MakePair(const Eigen::Vector3d& centre, double spread) {
    Pair p;
    const int n = 50;
    p.source = PointCloud::Random(n, 3) * spread;
    p.source.rowwise() += centre.transpose();
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, -0.5).normalized()).toRotationMatrix();
    const Eigen::Vector3d t(0.3, -0.2, 0.4);
    p.T_gt.topLeftCorner<3, 3>() = R;
    p.T_gt.topRightCorner<3, 1>() = t;
    p.target = (p.source * R.transpose()).rowwise() + t.transpose();
    p.source_overlap.setOnes(n);
    p.target_overlap.setOnes(n);
    return p;
}

TEST(TrainSample, PairOutsideTheTrainingFrameIsNormalisedWithItsGroundTruth) {
    // An indoor-like pair: 2.2 m across, 2.6 m in front of the camera (outside radius 2).
    const Pair p = MakePair(Eigen::Vector3d(0.1, -0.3, 2.6), 1.3);
    const networks::TrainSample s = ToTrainSample(p);
    // The source is centred and its farthest point at distance 1 (definition of the frame).
    EXPECT_LT(s.source.colwise().mean().norm(), 1e-12);
    EXPECT_NEAR(s.source.rowwise().squaredNorm().maxCoeff(), 1.0, 1e-12);
    // The ground truth still maps source onto target, point by point (the pair is noise-free,
    // so y' = R x' + t' must hold exactly; an independent check of t' = (t + R c - c) / s).
    const Eigen::Matrix3d R = s.T_gt.topLeftCorner<3, 3>();
    const Eigen::Vector3d t = s.T_gt.topRightCorner<3, 1>();
    const PointCloud moved = (s.source * R.transpose()).rowwise() + t.transpose();
    EXPECT_LT((moved - s.target).cwiseAbs().maxCoeff(), 1e-12);
    const Eigen::Matrix3d R_gt = p.T_gt.topLeftCorner<3, 3>();
    EXPECT_TRUE(R == R_gt);  // the rotation is unchanged
    EXPECT_EQ(s.source_overlap.size(), p.source_overlap.size());
}

TEST(TrainSample, PairInsideTheTrainingFrameIsPassedBitForBit) {
    const Pair p = MakePair(Eigen::Vector3d(0.2, 0.0, -0.1), 0.5);
    const networks::TrainSample s = ToTrainSample(p);
    EXPECT_TRUE(s.source == p.source);
    EXPECT_TRUE(s.target == p.target);
    EXPECT_TRUE(s.T_gt == p.T_gt);
}

}  // namespace
}  // namespace regbench
