#pragma once
// Weighted Procrustes (Kabsch / Umeyama) with the reflection fix.
#include <Eigen/Core>

#include "core/point_cloud.hpp"

namespace regbench {

/// Result of a weighted Procrustes fit: target ~ scale * R * source + t.
struct ProcrustesResult {
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    double scale = 1.0;
    bool valid = false;  ///< false when the total weight is zero or inputs are degenerate

    Transform ToTransform() const;
};

/// Minimises sum_i w_i |target_i - (s R source_i + t)|^2 over R in SO(3) (det +1 enforced,
/// Umeyama 1991 eq. (39)-(43)), t, and s when estimate_scale. Empty weights = all ones.
ProcrustesResult WeightedProcrustes(const PointCloud& source, const PointCloud& target,
                                    const Eigen::VectorXd& weights = Eigen::VectorXd(),
                                    bool estimate_scale = false);

/// Same fit from sufficient statistics: weighted centroids and the 3x3 cross-covariance
/// H = sum_i w_i (target_i - mu_t)(source_i - mu_s)^T; var_source = sum_i w_i |source_i - mu_s|^2
/// (used only for the scale). Lets E-step based methods skip building correspondences.
ProcrustesResult ProcrustesFromMoments(const Eigen::Vector3d& mu_source,
                                       const Eigen::Vector3d& mu_target,
                                       const Eigen::Matrix3d& H_target_source, double var_source,
                                       bool estimate_scale);

}  // namespace regbench
