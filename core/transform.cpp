#include "core/transform.hpp"

#include <algorithm>
#include <cmath>

namespace regbench {
namespace {
constexpr double kDegPerRad = 180.0 / M_PI;
constexpr double kRadPerDeg = M_PI / 180.0;
}  // namespace

Transform MakeTransform(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
    Transform T = Transform::Identity();
    T.topLeftCorner<3, 3>() = R;
    T.topRightCorner<3, 1>() = t;
    return T;
}

Transform InvertRigid(const Transform& T) {
    const Eigen::Matrix3d Rt = T.topLeftCorner<3, 3>().transpose();
    return MakeTransform(Rt, -Rt * T.topRightCorner<3, 1>());
}

Transform Compose(const Transform& T_a_b, const Transform& T_b_c) { return T_a_b * T_b_c; }

PointCloud Apply(const Transform& T, const PointCloud& points) {
    PointCloud out(points.rows(), 3);
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const Eigen::RowVector3d t = T.topRightCorner<3, 1>().transpose();
    out.noalias() = points * R.transpose();
    out.rowwise() += t;
    return out;
}

Eigen::Matrix3d RotationFromEulerZyxDeg(double z_deg, double y_deg, double x_deg) {
    return (Eigen::AngleAxisd(z_deg * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(y_deg * kRadPerDeg, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(x_deg * kRadPerDeg, Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
}

Eigen::Vector3d EulerZyxDegFromRotation(const Eigen::Matrix3d& R) {
    // R = Rz(a) Ry(b) Rx(c): R(2,0) = -sin(b), R(1,0)/R(0,0) = tan(a), R(2,1)/R(2,2) = tan(c).
    const double sy = std::clamp(-R(2, 0), -1.0, 1.0);
    const double b = std::asin(sy);
    double a = 0.0;
    double c = 0.0;
    constexpr double kGimbalEps = 1e-9;
    if (std::abs(std::abs(sy) - 1.0) > kGimbalEps) {
        a = std::atan2(R(1, 0), R(0, 0));
        c = std::atan2(R(2, 1), R(2, 2));
    } else {
        // Gimbal lock: only a -/+ c is defined; scipy sets the third angle to 0.
        c = 0.0;
        a = std::atan2(-R(0, 1), R(1, 1));
    }
    return Eigen::Vector3d(a, b, c) * kDegPerRad;
}

Eigen::Matrix3d RotationXyzProductDeg(double x_deg, double y_deg, double z_deg) {
    return (Eigen::AngleAxisd(x_deg * kRadPerDeg, Eigen::Vector3d::UnitX()) *
            Eigen::AngleAxisd(y_deg * kRadPerDeg, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(z_deg * kRadPerDeg, Eigen::Vector3d::UnitZ()))
        .toRotationMatrix();
}

Eigen::Matrix3d RotationFromAxisAngle(const Eigen::Vector3d& axis, double angle_rad) {
    const double n = axis.norm();
    if (n == 0.0) return Eigen::Matrix3d::Identity();
    return Eigen::AngleAxisd(angle_rad, axis / n).toRotationMatrix();
}

double RotationAngleDeg(const Eigen::Matrix3d& Ra, const Eigen::Matrix3d& Rb) {
    const double c = std::clamp(((Ra.transpose() * Rb).trace() - 1.0) / 2.0, -1.0, 1.0);
    return std::acos(c) * kDegPerRad;
}

bool IsRotation(const Eigen::Matrix3d& R, double tol) {
    if (!R.allFinite()) return false;
    const double ortho = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    return ortho <= tol && std::abs(R.determinant() - 1.0) <= tol;
}

}  // namespace regbench
