#include "gmm/cell_compress.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.hpp"
#include "core/synthetic_shapes.hpp"

namespace regbench {
namespace {

TEST(CompressToCells, HandExample) {
    // Cell edge 1: (0.2,0.2,0.2) and (0.6,0.4,0.2) share cell (0,0,0); (1.5,0,0) is alone.
    PointCloud p(3, 3);
    p << 0.2, 0.2, 0.2, 1.5, 0.0, 0.0, 0.6, 0.4, 0.2;
    Eigen::VectorXd w(3);
    w << 1.0, 2.0, 3.0;
    const CellCompressed c = CompressToCells(p, &w, 1.0);
    ASSERT_EQ(c.centroids.rows(), 2);
    // Hand values: weights 1 + 3 = 4 and 2; centroid (1*0.2 + 3*0.6)/4 = 0.5, (0.2 + 1.2)/4
    // = 0.35, 0.2.
    EXPECT_DOUBLE_EQ(c.weights[0], 4.0);
    EXPECT_DOUBLE_EQ(c.weights[1], 2.0);
    EXPECT_NEAR(c.centroids(0, 0), 0.5, 1e-15);
    EXPECT_NEAR(c.centroids(0, 1), 0.35, 1e-15);
    EXPECT_NEAR(c.centroids(0, 2), 0.2, 1e-15);
    EXPECT_NEAR(c.centroids(1, 0), 1.5, 1e-15);
    // Unweighted: counts and plain centroids.
    const CellCompressed u = CompressToCells(p, nullptr, 1.0);
    EXPECT_DOUBLE_EQ(u.weights[0], 2.0);
    EXPECT_NEAR(u.centroids(0, 0), 0.4, 1e-15);
}

TEST(CompressToCells, RejectsBadInputByName) {
    PointCloud p(1, 3);
    p << 0, 0, 0;
    EXPECT_THROW(CompressToCells(PointCloud(0, 3), nullptr, 1.0), std::invalid_argument);
    EXPECT_THROW(CompressToCells(p, nullptr, 0.0), std::invalid_argument);
    PointCloud wide(2, 3);
    wide << 0, 0, 0, 1e9, 0, 0;
    EXPECT_THROW(CompressToCells(wide, nullptr, 1e-6), std::invalid_argument);
}

TEST(CompressToCells, WeightedGaussSumsKeepSecondOrderAccuracy) {
    // Reference: brute-force double sums over the points. With cells of 0.25 sigma the merged
    // sum's relative error is second order, ~ kappa^2 / 24 * (d^2 / sigma^2 - 3) per member
    // (Taylor expansion about the weighted centroid, member spread <= h^2 / 12 per axis); over
    // a surface within ~3 sigma that stays below 1%.
    auto rng = MakePairRng(4, 0);
    const PointCloud x = SmoothBlobSurface(rng, 20000);
    Eigen::VectorXd w(x.rows());
    for (Eigen::Index j = 0; j < w.size(); ++j) w[j] = UniformReal(rng, 0.5, 1.5);
    const double sigma = 0.2;
    const CellCompressed c = CompressToCells(x, &w, 0.25 * sigma);
    EXPECT_LT(c.centroids.rows(), x.rows() / 4);
    EXPECT_NEAR(c.weights.sum(), w.sum(), 1e-8 * w.sum());
    for (int q = 0; q < 20; ++q) {
        const Eigen::RowVector3d query = x.row(q * 997);
        double exact0 = 0.0, approx0 = 0.0;
        Eigen::RowVector3d exact1 = Eigen::RowVector3d::Zero(), approx1 = exact1;
        for (Eigen::Index j = 0; j < x.rows(); ++j) {
            const double k =
                w[j] * std::exp(-(x.row(j) - query).squaredNorm() / (2 * sigma * sigma));
            exact0 += k;
            exact1 += k * x.row(j);
        }
        for (Eigen::Index j = 0; j < c.centroids.rows(); ++j) {
            const double k = c.weights[j] * std::exp(-(c.centroids.row(j) - query).squaredNorm() /
                                                     (2 * sigma * sigma));
            approx0 += k;
            approx1 += k * c.centroids.row(j);
        }
        EXPECT_NEAR(approx0, exact0, 0.01 * exact0);
        EXPECT_LT((approx1 / approx0 - exact1 / exact0).norm(), 0.01 * sigma);
    }
}

}  // namespace
}  // namespace regbench
