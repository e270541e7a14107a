#include "gmm/gmm_common.hpp"

#include <Eigen/LU>  // determinant()
#include <cmath>

namespace regbench {

double SquaredDistanceMean(const PointCloud& Y, const PointCloud& X) {
    const double m = static_cast<double>(Y.rows());
    const double n = static_cast<double>(X.rows());
    if (m == 0.0 || n == 0.0) return 0.0;
    // sum_mn |y - x|^2 = N sum_m |y|^2 + M sum_n |x|^2 - 2 (sum y) . (sum x)
    const double sy2 = Y.squaredNorm();
    const double sx2 = X.squaredNorm();
    const double cross = Y.colwise().sum().dot(X.colwise().sum());
    return (n * sy2 + m * sx2 - 2.0 * cross) / (3.0 * m * n);
}

double EstimateSigmaFromCovariance(const PointCloud& Y) {
    if (Y.rows() < 2) return 0.0;
    const PointCloud c = Y.rowwise() - Y.colwise().mean();
    const Eigen::Matrix3d cov = (c.transpose() * c) / static_cast<double>(Y.rows() - 1);
    const double det = cov.determinant();
    return det > 0.0 ? std::pow(det, 1.0 / 6.0) : 0.0;
}

}  // namespace regbench
