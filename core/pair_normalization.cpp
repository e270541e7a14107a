#include "core/pair_normalization.hpp"

#include <cmath>

namespace regbench {

PairNormalization NormalizationOf(const PointCloud& source, const PointCloud& target,
                                  double data_unit) {
    PairNormalization n;
    const double limit = kTrainingFrameRadius * data_unit;
    const auto inside = [limit](const PointCloud& c) {
        return c.rows() == 0 || c.rowwise().squaredNorm().maxCoeff() <= limit * limit;
    };
    if (source.rows() == 0) return n;
    if (inside(source) && inside(target)) {
        // (x - 0) / data_unit: the unit pair this scaled copy is
        n.applied = data_unit != 1.0;
        n.scale = data_unit;
        return n;
    }
    n.applied = true;
    n.centre = source.colwise().mean().transpose();
    const double radius =
        std::sqrt((source.rowwise() - n.centre.transpose()).rowwise().squaredNorm().maxCoeff());
    n.scale = radius > 0.0 ? radius : 1.0;
    return n;
}

PointCloud NormalizeCloud(const PointCloud& cloud, const PairNormalization& n) {
    if (!n.applied) return cloud;
    return (cloud.rowwise() - n.centre.transpose()) / n.scale;
}

Transform DenormalizeTransform(const Transform& T_normalized, const PairNormalization& n) {
    if (!n.applied) return T_normalized;
    Transform T = T_normalized;
    const Eigen::Matrix3d R = T_normalized.topLeftCorner<3, 3>();
    T.topRightCorner<3, 1>() =
        n.scale * T_normalized.topRightCorner<3, 1>() + n.centre - R * n.centre;
    return T;
}

Transform NormalizeGroundTruth(const Transform& T, const PairNormalization& n) {
    if (!n.applied) return T;
    Transform out = T;
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    out.topRightCorner<3, 1>() = (T.topRightCorner<3, 1>() + R * n.centre - n.centre) / n.scale;
    return out;
}

}  // namespace regbench
