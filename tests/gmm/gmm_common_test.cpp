#include "gmm/gmm_common.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace regbench {
namespace {

constexpr double kHandTol = 1e-12;

TEST(GmmCommon, SquaredDistanceMeanMatchesHandValue) {
    PointCloud Y(2, 3), X(1, 3);
    Y << 0, 0, 0, 1, 0, 0;
    X << 0, 2, 0;
    // |y - x|^2 = 4 and 5: sum 9 over D M N = 3 * 2 * 1.
    EXPECT_NEAR(SquaredDistanceMean(Y, X), 9.0 / 6.0, kHandTol);
}

TEST(GmmCommon, SigmaFromCovarianceMatchesHandValue) {
    PointCloud Y(6, 3);
    Y << 1, 0, 0, -1, 0, 0, 0, 2, 0, 0, -2, 0, 0, 0, 3, 0, 0, -3;
    // Mean 0, unbiased covariance diag(2, 8, 18) / 5: det = 288 / 125.
    EXPECT_NEAR(EstimateSigmaFromCovariance(Y), std::pow(288.0 / 125.0, 1.0 / 6.0), kHandTol);
}

}  // namespace
}  // namespace regbench
