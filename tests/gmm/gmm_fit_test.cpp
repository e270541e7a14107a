#include "gmm/gmm_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.hpp"

namespace regbench {
namespace {

/// Three well separated isotropic blobs with per-axis std 0.05 and sizes 100, 200, 300.
PointCloud ThreeBlobs(std::mt19937_64& rng) {
    const Eigen::RowVector3d centers[3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 1}};
    const int sizes[3] = {100, 200, 300};
    PointCloud X(600, 3);
    int row = 0;
    for (int c = 0; c < 3; ++c) {
        for (int i = 0; i < sizes[c]; ++i, ++row) {
            for (int d = 0; d < 3; ++d) X(row, d) = centers[c][d] + 0.05 * StandardNormal(rng);
        }
    }
    return X;
}

TEST(KMeans, SeparatesBlobsAndLabelsMatchNearestCenters) {
    auto rng = MakePairRng(1, 0);
    const PointCloud X = ThreeBlobs(rng);
    const KMeansResult km = KMeansPlusPlusLloyd(X, 3, KMeansOptions{}, rng);
    for (int i = 0; i < 600; ++i) {
        const int expected_blob = i < 100 ? 0 : (i < 300 ? 1 : 2);
        // every point shares its label with the first point of its blob
        const int first = expected_blob == 0 ? 0 : (expected_blob == 1 ? 100 : 300);
        EXPECT_EQ(km.labels[i], km.labels[first]) << i;
        Eigen::Index nearest;
        (km.centers.rowwise() - X.row(i)).rowwise().squaredNorm().minCoeff(&nearest);
        EXPECT_EQ(km.labels[i], nearest);
    }
    EXPECT_NE(km.labels[0], km.labels[100]);
    EXPECT_NE(km.labels[100], km.labels[300]);
}

TEST(GmmFit, RecoversBlobWeightsMeansAndVariances) {
    auto rng = MakePairRng(2, 0);
    const PointCloud X = ThreeBlobs(rng);
    GmmFitOptions options;
    options.n_components = 3;
    const SphericalGmm g = FitSphericalGmm(X, options, rng);
    EXPECT_TRUE(g.converged);
    EXPECT_NEAR(g.weights.sum(), 1.0, 1e-12);
    for (int j = 0; j < 3; ++j) {
        const double w = g.weights[j];
        EXPECT_TRUE(std::abs(w - 1.0 / 6) < 1e-6 || std::abs(w - 2.0 / 6) < 1e-6 ||
                    std::abs(w - 3.0 / 6) < 1e-6)
            << w;
        EXPECT_NEAR(g.variances[j], 0.05 * 0.05, 0.0008);
    }
    // Blob 1 (weight 1/3) has its mean at (2, 0, 0) up to sampling noise.
    Eigen::Index j1;
    (g.weights.array() - 2.0 / 6).abs().minCoeff(&j1);
    EXPECT_LT((g.means.row(j1) - Eigen::RowVector3d(2, 0, 0)).norm(), 0.02);
}

TEST(GmmFit, ManyComponentsKeepValidParametersAndIsSeeded) {
    auto rng = MakePairRng(3, 0);
    PointCloud X(300, 3);
    for (int i = 0; i < 300; ++i) {
        for (int d = 0; d < 3; ++d) X(i, d) = StandardNormal(rng);
    }
    GmmFitOptions options;
    options.n_components = 240;  // probreg's 0.8 N
    auto r1 = MakePairRng(5, 1), r2 = MakePairRng(5, 1);
    const SphericalGmm a = FitSphericalGmm(X, options, r1);
    const SphericalGmm b = FitSphericalGmm(X, options, r2);
    EXPECT_EQ((a.means - b.means).norm(), 0.0);
    EXPECT_NEAR(a.weights.sum(), 1.0, 1e-12);
    EXPECT_GE(a.variances.minCoeff(), options.reg_covar * 0.999);
    EXPECT_TRUE(a.means.allFinite());
    EXPECT_LE(a.iterations, options.max_iter);
}

TEST(GmmFit, RejectsTooManyComponents) {
    PointCloud X = PointCloud::Random(5, 3);
    GmmFitOptions options;
    options.n_components = 6;
    auto rng = MakePairRng(0, 0);
    EXPECT_THROW(FitSphericalGmm(X, options, rng), std::invalid_argument);
}

}  // namespace
}  // namespace regbench
