#pragma once
// Per-pair registration metrics; docs/metrics.md defines each one with its formula.
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.hpp"
#include "core/transform.hpp"

namespace regbench {

/// Clip distance of the paper code's clipped Chamfer distance (CCD).
constexpr double kCcdClip = 0.1;

/// What the cloud metrics are measured with. The defaults are the paper code's, chosen for
/// objects in the unit sphere: at other scales pass a clip in the data's units (`run
/// --ccd-clip`; ScaleWarning says when the defaults cannot mean anything).
struct MetricOptions {
    double ccd_clip = kCcdClip;  ///< CCD clip distance (cloud units), > 0
    /// Open3D's evaluate_registration at this max_correspondence_distance (cloud units): fitness
    /// and inlier_rmse are computed when > 0, not at all when 0 (the default).
    double inlier_threshold = 0.0;
};

/// Throws std::invalid_argument naming the flag unless ccd_clip is finite and > 0 and
/// inlier_threshold finite and >= 0.
void CheckMetricOptions(const MetricOptions& options);

struct PairMetrics {
    EulerConvention euler = EulerConvention::kZyx;  ///< the Euler angles e() of mae_r / mse_r
    double mae_r = 0.0;    ///< mean |e(R_gt) - e(R_est)| over 3 angles [deg], no wrapping
    double mae_t = 0.0;    ///< mean |t_gt - t_est| over 3 axes
    double mse_r = 0.0;    ///< mean squared angle error [deg^2] (rmse_r = sqrt(mean over pairs))
    double mse_t = 0.0;    ///< mean squared axis error (rmse_t = sqrt(mean over pairs))
    double rre = 0.0;      ///< relative rotation error [deg]
    double rte = 0.0;      ///< |t_gt - t_est|
    double ccd = 0.0;      ///< clipped Chamfer distance of T_est(source) vs target, clip 0.1
    double chamfer = 0.0;  ///< same, unclipped, squared distances
    /// RMSE of ||T_est p - T_gt p|| over the source points labelled overlapping (all points
    /// when none is labelled); NaN when not computed (MotionMetrics, old rows).
    double overlap_rmse = std::numeric_limits<double>::quiet_NaN();
    /// Paper-text variant: the pair counts for CCD only when its unclipped one-sided mean
    /// distances are both below the clip; false means "discard this pair" under that variant.
    bool ccd_within_clip = true;
    double ccd_clip = kCcdClip;  ///< the clip `ccd` was computed with
    /// Open3D's evaluate_registration(source, target, inlier_threshold, T_est): the fraction of
    /// source points whose nearest target point lies closer than the threshold, and the RMSE of
    /// those distances (0 without inliers, as Open3D); NaN when not computed (threshold 0).
    double inlier_threshold = 0.0;
    double fitness = std::numeric_limits<double>::quiet_NaN();
    double inlier_rmse = std::numeric_limits<double>::quiet_NaN();
};

/// A per-pair metric: its name (the JSONL `metrics` key, the CLI's and Python's), its field of
/// PairMetrics, and the one number format tables print it with.
struct MetricField {
    const char* name;
    double PairMetrics::*field;
    int decimals;

    /// The metric's value in `m`, or nullopt when it is not finite (a null in the JSONL: the
    /// row counts as a failure of this metric).
    std::optional<double> Of(const PairMetrics& m) const;
};

/// Every per-pair metric (mae_r, mae_t, mse_r, mse_t, rre, rte, ccd, chamfer, overlap_rmse),
/// in the order reports list them: the one list that JSONL rows, reports and the Python
/// module read and write.
const std::vector<MetricField>& PerPairMetrics();

/// Rotation/translation metrics only (no clouds needed). `euler` picks the Euler angles of
/// mae_r / mse_r: scipy's extrinsic 'zyx' (the paper's evaluation code) unless asked otherwise.
PairMetrics MotionMetrics(const Transform& T_gt, const Transform& T_est,
                          EulerConvention euler = EulerConvention::kZyx);

/// All metrics; source/target are the pair's clouds (source in its own frame).
PairMetrics ComputeMetrics(const Transform& T_gt, const Transform& T_est, const PointCloud& source,
                           const PointCloud& target, EulerConvention euler = EulerConvention::kZyx,
                           const MetricOptions& options = {});

struct InlierResult {
    double fitness = 0.0;      ///< inliers / source points
    double inlier_rmse = 0.0;  ///< sqrt(mean squared inlier distance); 0 without inliers
};

/// Open3D's evaluate_registration on a source already moved by the estimate: a source point is
/// an inlier when its nearest target point is closer than `threshold` (strictly).
InlierResult EvaluateInliers(const PointCloud& moved_source, const PointCloud& target,
                             double threshold);

/// The typical size of a pair set's clouds: the median over pairs of the target's radius (largest
/// distance from its centroid); NaN for no pairs.
double MedianCloudRadius(const std::vector<const PointCloud*>& targets);

/// A warning when clouds of radius `radius` make the default thresholds (CCD clip 0.1, report's
/// recall/success translation 0.1) meaningless: radius above 10 (millimetres, metres of a room
/// scan at scale) or below 0.1; "" otherwise or when `options` sets its own clip.
std::string ScaleWarning(double radius, const MetricOptions& options);

/// RMSE of ||T_est p - T_gt p|| over the points p of `source` whose `overlap` label is 1 (over
/// all points when `overlap` is empty or labels none); NaN for an empty cloud.
double OverlapRmse(const Transform& T_gt, const Transform& T_est, const PointCloud& source,
                   const Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>& overlap);

struct ChamferResult {
    double ccd = 0.0;         ///< mean_a min(d, clip) + mean_b min(d, clip)
    double chamfer = 0.0;     ///< mean_a d^2 + mean_b d^2, unclipped
    bool within_clip = true;  ///< both unclipped one-sided mean distances below clip
};

/// Clipped and squared Chamfer distances between two clouds (NaN for an empty cloud).
ChamferResult ChamferDistances(const PointCloud& a, const PointCloud& b, double clip = kCcdClip);

}  // namespace regbench
