#include "runners/align_clouds.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace regbench {

Normalization FitNormalization(const PointCloud& source, const PointCloud& target) {
    Normalization n;
    n.centre = target.colwise().mean();
    const double r = std::max((source.rowwise() - n.centre).rowwise().norm().maxCoeff(),
                              (target.rowwise() - n.centre).rowwise().norm().maxCoeff());
    if (r > 0.0) n.scale = 1.0 / r;
    return n;
}

PointCloud Normalize(const PointCloud& points, const Normalization& n) {
    return (points.rowwise() - n.centre) * n.scale;
}

Transform Denormalize(const Transform& T_normalized, const Normalization& n) {
    const Eigen::Matrix3d R = T_normalized.topLeftCorner<3, 3>();
    const Eigen::Vector3d c = n.centre.transpose();
    Transform T = T_normalized;
    T.topRightCorner<3, 1>() = T_normalized.topRightCorner<3, 1>() / n.scale - R * c + c;
    return T;
}

AlignResult AlignClouds(RegistrationMethod& method, const PointCloud& source,
                        const PointCloud& target, bool normalize, const AlignContext& context) {
    if (!normalize) return method.Align(source, target, context);
    const Normalization n = FitNormalization(source, target);
    AlignResult r = method.Align(Normalize(source, n), Normalize(target, n), context);
    r.T_target_source = Denormalize(r.T_target_source, n);
    return r;
}

}  // namespace regbench
