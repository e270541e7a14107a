#include "core/kabsch.hpp"

#include <Eigen/SVD>

#include "core/transform.hpp"

namespace regbench {

Transform ProcrustesResult::ToTransform() const { return MakeTransform(scale * R, t); }

ProcrustesResult ProcrustesFromMoments(const Eigen::Vector3d& mu_source,
                                       const Eigen::Vector3d& mu_target,
                                       const Eigen::Matrix3d& H_target_source, double var_source,
                                       bool estimate_scale) {
    ProcrustesResult out;
    if (!H_target_source.allFinite() || !mu_source.allFinite() || !mu_target.allFinite()) {
        return out;
    }
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(H_target_source,
                                          Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d& U = svd.matrixU();
    const Eigen::Matrix3d& V = svd.matrixV();
    Eigen::Vector3d d(1.0, 1.0, (U * V.transpose()).determinant() < 0.0 ? -1.0 : 1.0);
    out.R = U * d.asDiagonal() * V.transpose();
    if (estimate_scale && var_source > 0.0) {
        out.scale = svd.singularValues().dot(d) / var_source;
    }
    out.t = mu_target - out.scale * out.R * mu_source;
    out.valid = out.R.allFinite() && out.t.allFinite();
    return out;
}

ProcrustesResult WeightedProcrustes(const PointCloud& source, const PointCloud& target,
                                    const Eigen::VectorXd& weights, bool estimate_scale) {
    const Eigen::Index n = source.rows();
    if (n == 0 || target.rows() != n || (weights.size() != 0 && weights.size() != n)) {
        return {};
    }
    Eigen::VectorXd w = weights.size() == 0 ? Eigen::VectorXd::Ones(n) : weights;
    const double total = w.sum();
    if (!(total > 0.0)) return {};
    const Eigen::Vector3d mu_s = (source.transpose() * w) / total;
    const Eigen::Vector3d mu_t = (target.transpose() * w) / total;
    PointCloud sc = source.rowwise() - mu_s.transpose();
    PointCloud tc = target.rowwise() - mu_t.transpose();
    const Eigen::Matrix3d H = tc.transpose() * w.asDiagonal() * sc;
    const double var_s = (sc.rowwise().squaredNorm().transpose() * w).value();
    return ProcrustesFromMoments(mu_s, mu_t, H, var_s, estimate_scale);
}

}  // namespace regbench
