#include "core/metrics.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/kd_tree.hpp"
#include "core/transform.hpp"

namespace regbench {

const std::vector<MetricField>& PerPairMetrics() {
    static const std::vector<MetricField> metrics = {
        {"mae_r", &PairMetrics::mae_r, 4},
        {"mae_t", &PairMetrics::mae_t, 4},
        {"mse_r", &PairMetrics::mse_r, 4},
        {"mse_t", &PairMetrics::mse_t, 4},
        {"rre", &PairMetrics::rre, 4},
        {"rte", &PairMetrics::rte, 4},
        {"ccd", &PairMetrics::ccd, 4},
        {"chamfer", &PairMetrics::chamfer, 4},
        {"overlap_rmse", &PairMetrics::overlap_rmse, 4}};
    return metrics;
}

std::optional<double> MetricField::Of(const PairMetrics& m) const {
    const double x = m.*field;
    if (!std::isfinite(x)) return std::nullopt;
    return x;
}

PairMetrics MotionMetrics(const Transform& T_gt, const Transform& T_est, EulerConvention euler) {
    PairMetrics m;
    m.euler = euler;
    const Eigen::Matrix3d R_gt = T_gt.topLeftCorner<3, 3>();
    // A similarity estimate (e.g. CPD with update_scale) carries s*R: divide the scale out so the
    // rotation metrics measure the rotation only (scale is reported separately in the row).
    Eigen::Matrix3d R_est = T_est.topLeftCorner<3, 3>();
    const double det = R_est.determinant();
    if (det > 0.0) R_est /= std::cbrt(det);
    const Eigen::Vector3d dr =
        (EulerDegFromRotation(R_gt, euler) - EulerDegFromRotation(R_est, euler)).cwiseAbs();
    const Eigen::Vector3d dt = (T_gt.topRightCorner<3, 1>() - T_est.topRightCorner<3, 1>());
    m.mae_r = dr.mean();
    m.mae_t = dt.cwiseAbs().mean();
    m.mse_r = dr.squaredNorm() / 3.0;
    m.mse_t = dt.squaredNorm() / 3.0;
    m.rre = RotationAngleDeg(R_gt, R_est);
    m.rte = dt.norm();
    return m;
}

ChamferResult ChamferDistances(const PointCloud& a, const PointCloud& b, double clip) {
    ChamferResult r;
    if (a.rows() == 0 || b.rows() == 0) {
        r.ccd = r.chamfer = std::numeric_limits<double>::quiet_NaN();
        r.within_clip = false;
        return r;
    }
    const KdTree tree_a(a);
    const KdTree tree_b(b);
    const Eigen::VectorXd d_ab = NearestDistances(tree_b, a);
    const Eigen::VectorXd d_ba = NearestDistances(tree_a, b);
    r.ccd = d_ab.cwiseMin(clip).mean() + d_ba.cwiseMin(clip).mean();
    r.chamfer = d_ab.squaredNorm() / static_cast<double>(d_ab.size()) +
                d_ba.squaredNorm() / static_cast<double>(d_ba.size());
    r.within_clip = d_ab.mean() < clip && d_ba.mean() < clip;
    return r;
}

double OverlapRmse(const Transform& T_gt, const Transform& T_est, const PointCloud& source,
                   const Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 1>& overlap) {
    const bool use_mask = overlap.size() == source.rows() && (overlap.array() != 0).any();
    const PointCloud diff = Apply(T_est, source) - Apply(T_gt, source);
    double sum = 0.0;
    std::size_t n = 0;
    for (Eigen::Index i = 0; i < source.rows(); ++i) {
        if (use_mask && overlap[i] == 0) continue;
        sum += diff.row(i).squaredNorm();
        ++n;
    }
    return n == 0 ? std::numeric_limits<double>::quiet_NaN()
                  : std::sqrt(sum / static_cast<double>(n));
}

PairMetrics ComputeMetrics(const Transform& T_gt, const Transform& T_est, const PointCloud& source,
                           const PointCloud& target, EulerConvention euler,
                           const MetricOptions& options) {
    PairMetrics m = MotionMetrics(T_gt, T_est, euler);
    const PointCloud moved = Apply(T_est, source);
    const ChamferResult c = ChamferDistances(moved, target, options.ccd_clip);
    m.ccd = c.ccd;
    m.chamfer = c.chamfer;
    m.ccd_within_clip = c.within_clip;
    m.ccd_clip = options.ccd_clip;
    if (options.inlier_threshold > 0.0) {
        m.inlier_threshold = options.inlier_threshold;
        if (moved.rows() > 0 && target.rows() > 0) {
            const InlierResult r = EvaluateInliers(moved, target, options.inlier_threshold);
            m.fitness = r.fitness;
            m.inlier_rmse = r.inlier_rmse;
        }
    }
    return m;
}

void CheckMetricOptions(const MetricOptions& o) {
    if (!std::isfinite(o.ccd_clip) || o.ccd_clip <= 0.0) {
        throw std::invalid_argument("--ccd-clip must be a finite number > 0, got " +
                                    std::to_string(o.ccd_clip));
    }
    if (!std::isfinite(o.inlier_threshold) || o.inlier_threshold < 0.0) {
        throw std::invalid_argument("--inlier-threshold must be a finite number >= 0, got " +
                                    std::to_string(o.inlier_threshold));
    }
}

InlierResult EvaluateInliers(const PointCloud& moved_source, const PointCloud& target,
                             double threshold) {
    InlierResult r;
    if (moved_source.rows() == 0 || target.rows() == 0) return r;
    const Eigen::VectorXd d = NearestDistances(KdTree(target), moved_source);
    double sum = 0.0;
    Eigen::Index inliers = 0;
    for (Eigen::Index i = 0; i < d.size(); ++i) {
        if (d[i] < threshold) {
            sum += d[i] * d[i];
            ++inliers;
        }
    }
    r.fitness = static_cast<double>(inliers) / static_cast<double>(d.size());
    r.inlier_rmse = inliers == 0 ? 0.0 : std::sqrt(sum / static_cast<double>(inliers));
    return r;
}

double MedianCloudRadius(const std::vector<const PointCloud*>& targets) {
    std::vector<double> radii;
    for (const PointCloud* t : targets) {
        if (t->rows() == 0) continue;
        const Eigen::RowVector3d centroid = t->colwise().mean();
        radii.push_back(std::sqrt((t->rowwise() - centroid).rowwise().squaredNorm().maxCoeff()));
    }
    if (radii.empty()) return std::numeric_limits<double>::quiet_NaN();
    std::nth_element(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(radii.size() / 2),
                     radii.end());
    return radii[radii.size() / 2];
}

std::string ScaleWarning(double radius, const MetricOptions& options) {
    if (!std::isfinite(radius) || options.ccd_clip != kCcdClip) return "";
    if (radius <= 10.0 && radius >= 0.1) return "";
    char text[512];
    std::snprintf(text, sizeof(text),
                  "the clouds' median radius is %.4g (cloud units), but the default CCD clip "
                  "%.4g and report's recall/success translation thresholds (0.1) are meant for "
                  "objects in the unit sphere: at this scale they cannot tell methods apart; "
                  "pass --ccd-clip (e.g. %.4g, 10%% of the radius) and report --recall-t / "
                  "--success-rte in these units, or normalize the data",
                  radius, kCcdClip, 0.1 * radius);
    return text;
}

}  // namespace regbench
