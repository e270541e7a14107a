#include "core/kabsch.hpp"

#include <gtest/gtest.h>

#include "core/rng.hpp"
#include "core/transform.hpp"

namespace regbench {
namespace {

constexpr double kExactTol = 1e-9;

PointCloud RandomCloud(std::mt19937_64& rng, Eigen::Index n) {
    PointCloud p(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) p(i, k) = UniformReal(rng, -1.0, 1.0);
    }
    return p;
}

TEST(Kabsch, RecoversRandomTransformExactly) {
    auto rng = MakePairRng(1, 0);
    for (int trial = 0; trial < 20; ++trial) {
        const PointCloud src = RandomCloud(rng, 50);
        const Eigen::Matrix3d R = RotationFromAxisAngle(
            {UniformReal(rng, -1, 1), UniformReal(rng, -1, 1), UniformReal(rng, -1, 1)},
            UniformReal(rng, 0, M_PI));
        const Eigen::Vector3d t(UniformReal(rng, -1, 1), UniformReal(rng, -1, 1), 0.3);
        const PointCloud tgt = Apply(MakeTransform(R, t), src);
        const ProcrustesResult fit = WeightedProcrustes(src, tgt);
        ASSERT_TRUE(fit.valid);
        EXPECT_LT((fit.R - R).cwiseAbs().maxCoeff(), kExactTol);
        EXPECT_LT((fit.t - t).cwiseAbs().maxCoeff(), kExactTol);
        EXPECT_NEAR(fit.R.determinant(), 1.0, kExactTol);
    }
}

TEST(Kabsch, FixesReflection) {
    // A mirrored target: the best rotation must still have det +1.
    auto rng = MakePairRng(2, 0);
    const PointCloud src = RandomCloud(rng, 30);
    PointCloud tgt = src;
    tgt.col(0) *= -1.0;
    const ProcrustesResult fit = WeightedProcrustes(src, tgt);
    ASSERT_TRUE(fit.valid);
    EXPECT_NEAR(fit.R.determinant(), 1.0, kExactTol);
    EXPECT_TRUE(IsRotation(fit.R));
}

TEST(Kabsch, RecoversSimilarityWithScale) {
    auto rng = MakePairRng(3, 0);
    const PointCloud src = RandomCloud(rng, 40);
    const Eigen::Matrix3d R = RotationZyxProductDeg(30, -10, 5);
    const PointCloud tgt = Apply(MakeTransform(1.7 * R, {0.2, 0.1, -0.4}), src);
    const ProcrustesResult fit = WeightedProcrustes(src, tgt, {}, true);
    EXPECT_NEAR(fit.scale, 1.7, 1e-10);
    EXPECT_LT((fit.R - R).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(Kabsch, ZeroWeightsIgnoreOutliers) {
    auto rng = MakePairRng(4, 0);
    const PointCloud src = RandomCloud(rng, 30);
    const Transform T = MakeTransform(RotationZyxProductDeg(5, 15, 25), {0.1, 0.2, 0.3});
    PointCloud tgt = Apply(T, src);
    tgt.row(0) << 10, 10, 10;  // an outlier with zero weight
    Eigen::VectorXd w = Eigen::VectorXd::Ones(30);
    w[0] = 0.0;
    const ProcrustesResult fit = WeightedProcrustes(src, tgt, w);
    EXPECT_LT((fit.ToTransform() - T).cwiseAbs().maxCoeff(), kExactTol);
}

TEST(Kabsch, RejectsMismatchedOrEmptyInput) {
    EXPECT_FALSE(WeightedProcrustes(PointCloud(0, 3), PointCloud(0, 3)).valid);
    EXPECT_FALSE(WeightedProcrustes(PointCloud::Zero(3, 3), PointCloud::Zero(4, 3)).valid);
    EXPECT_FALSE(
        WeightedProcrustes(PointCloud::Ones(3, 3), PointCloud::Ones(3, 3), Eigen::VectorXd::Zero(3))
            .valid);
}

}  // namespace
}  // namespace regbench
