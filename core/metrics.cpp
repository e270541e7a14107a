#include "core/metrics.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

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
                           const PointCloud& target, EulerConvention euler) {
    PairMetrics m = MotionMetrics(T_gt, T_est, euler);
    const ChamferResult c = ChamferDistances(Apply(T_est, source), target);
    m.ccd = c.ccd;
    m.chamfer = c.chamfer;
    m.ccd_within_clip = c.within_clip;
    return m;
}

}  // namespace regbench
