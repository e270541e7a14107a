#pragma once
// Per-pair registration metrics exactly as ../shared/specs/protocols.md defines them.
#include <Eigen/Core>

#include "core/point_cloud.hpp"

namespace regbench {

/// Clip distance of the paper code's clipped Chamfer distance (CCD).
constexpr double kCcdClip = 0.1;

struct PairMetrics {
    double mae_r = 0.0;    ///< mean |e_zyx(R_gt) - e_zyx(R_est)| over 3 angles [deg], no wrapping
    double mae_t = 0.0;    ///< mean |t_gt - t_est| over 3 axes
    double mse_r = 0.0;    ///< mean squared angle error [deg^2] (rmse_r = sqrt(mean over pairs))
    double mse_t = 0.0;    ///< mean squared axis error (rmse_t = sqrt(mean over pairs))
    double rre = 0.0;      ///< relative rotation error [deg]
    double rte = 0.0;      ///< |t_gt - t_est|
    double ccd = 0.0;      ///< clipped Chamfer distance of T_est(source) vs target, clip 0.1
    double chamfer = 0.0;  ///< same, unclipped, squared distances
    /// Paper-text variant: the pair counts for CCD only when its unclipped one-sided mean
    /// distances are both below the clip; false means "discard this pair" under that variant.
    bool ccd_within_clip = true;
};

/// Rotation/translation metrics only (no clouds needed).
PairMetrics MotionMetrics(const Transform& T_gt, const Transform& T_est);

/// All metrics; source/target are the pair's clouds (source in its own frame).
PairMetrics ComputeMetrics(const Transform& T_gt,
                           const Transform& T_est,
                           const PointCloud& source,
                           const PointCloud& target);

struct ChamferResult {
    double ccd = 0.0;         ///< mean_a min(d, clip) + mean_b min(d, clip)
    double chamfer = 0.0;     ///< mean_a d^2 + mean_b d^2, unclipped
    bool within_clip = true;  ///< both unclipped one-sided mean distances below clip
};

/// Clipped and squared Chamfer distances between two clouds (NaN for an empty cloud).
ChamferResult ChamferDistances(const PointCloud& a, const PointCloud& b, double clip = kCcdClip);

}  // namespace regbench
