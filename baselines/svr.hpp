#pragma once
#include <Eigen/Core>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/registration.hpp"

namespace regbench {

/// One-class nu-SVM with an RBF kernel exp(-gamma |x - x'|^2), solved by libsvm (SMO with
/// WSS3), as sklearn's OneClassSVM(nu, kernel='rbf', gamma, tol) fits it.
struct OneClassSvm {
    std::vector<int> support;  ///< indices of the support vectors in the input cloud
    Eigen::VectorXd alpha;     ///< their dual coefficients: 0 < alpha <= 1, sum = nu n
    double rho = 0.0;          ///< offset: decision(x) = sum alpha K(sv, x) - rho
};

/// Fits X (n >= 1 points). Throws std::invalid_argument for nu outside (0, 1], gamma <= 0
/// or tol <= 0.
OneClassSvm FitOneClassSvm(const PointCloud& X, double nu, double gamma, double tol);

/// `svr`: Support Vector Registration (Campbell & Petersson 2015) as probreg's
/// registration_svr runs it; probabilistic-baselines.md Sec. 3.
MethodInfo SvrMethodInfo();

}  // namespace regbench
