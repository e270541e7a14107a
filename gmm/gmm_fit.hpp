#pragma once
// Spherical Gaussian mixture EM as sklearn's GaussianMixture(covariance_type='spherical')
// runs it (n_init 1, init_params 'kmeans': k-means++ then Lloyd, tol 1e-3 on the change of
// the mean log-likelihood lower bound, reg_covar 1e-6, max_iter 100), seeded explicitly.
#include <Eigen/Core>
#include <random>
#include <vector>

#include "core/point_cloud.hpp"

namespace regbench {

struct KMeansOptions {
    int max_iter = 300;  ///< Lloyd iterations (sklearn KMeans default)
    double tol = 1e-4;   ///< stop when sum |c_new - c_old|^2 <= tol * mean per-axis variance
};

struct KMeansResult {
    PointCloud centers;
    std::vector<int> labels;  ///< nearest center of each point, consistent with `centers`
    int iterations = 0;
    double inertia = 0.0;  ///< sum of squared distances to the assigned centers
};

/// sklearn's KMeans(n_clusters=k, n_init=1): greedy k-means++ seeding (2 + floor(ln k)
/// local trials, first center uniform) then Lloyd with empty clusters relocated to the
/// points farthest from their centers. Requires 1 <= k <= rows of X.
KMeansResult KMeansPlusPlusLloyd(const PointCloud& X, int k, const KMeansOptions& options,
                                 std::mt19937_64& rng);

struct GmmFitOptions {
    int n_components = 1;     ///< K, 1 <= K <= number of points
    double tol = 1e-3;        ///< EM stops when |lower_bound - previous| < tol
    double reg_covar = 1e-6;  ///< added to every variance
    int max_iter = 100;       ///< EM iterations
    KMeansOptions kmeans;     ///< initialisation
};

struct SphericalGmm {
    PointCloud means;           ///< K x 3
    Eigen::VectorXd weights;    ///< K, sum 1
    Eigen::VectorXd variances;  ///< K, per-axis variance of each component
    int iterations = 0;         ///< EM iterations run
    bool converged = false;
    double lower_bound = 0.0;  ///< mean log-likelihood per point at the last E-step
    int kmeans_iterations = 0;
};

/// Fits a spherical GMM to X. The E-step is dense (distances by GEMM, vectorised exp,
/// rows in parallel); results do not depend on the thread count.
SphericalGmm FitSphericalGmm(const PointCloud& X, const GmmFitOptions& options,
                             std::mt19937_64& rng);

}  // namespace regbench
