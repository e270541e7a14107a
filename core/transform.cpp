#include "core/transform.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/enum_names.hpp"

namespace regbench {
namespace {
constexpr double kDegPerRad = 180.0 / M_PI;
constexpr double kRadPerDeg = M_PI / 180.0;
/// |cos| of the middle angle below which the decomposition is treated as gimbal-locked. scipy
/// uses an angle tolerance of 1e-7 rad around +-90 deg; cos of such an angle is ~1e-7.
constexpr double kGimbalCos = 1e-7;
constexpr EnumName<EulerConvention> kEulerNames[] = {
    {EulerConvention::kZyx, "zyx"},
    {EulerConvention::kXyz, "xyz"},
};
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

const char* ToString(EulerConvention convention) { return EnumToString(kEulerNames, convention); }

EulerConvention ParseEulerConvention(const std::string& name) {
    if (const auto convention = FindEnum(kEulerNames, name)) return *convention;
    throw std::invalid_argument("unknown Euler convention '" + name +
                                "' (expected 'zyx' -- the paper's -- or 'xyz' -- RPMNet's)");
}

Eigen::Matrix3d RotationZyxProductDeg(double z_deg, double y_deg, double x_deg) {
    return (Eigen::AngleAxisd(z_deg * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(y_deg * kRadPerDeg, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(x_deg * kRadPerDeg, Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
}

Eigen::Vector3d EulerZyxDegFromRotation(const Eigen::Matrix3d& R) {
    // R = Rx(g) Ry(b) Rz(a) has first row (cos b cos a, -cos b sin a, sin b), last column
    // (sin b, -sin g cos b, cos g cos b). The middle angle comes from atan2 of sin b against
    // cos b = |first row's first two entries|, which stays accurate near b = +-90 deg.
    const double cos_b = std::hypot(R(0, 0), R(0, 1));
    const double b = std::atan2(R(0, 2), cos_b);
    double a = 0.0;
    double g = 0.0;
    if (cos_b > kGimbalCos) {
        a = std::atan2(-R(0, 1), R(0, 0));
        g = std::atan2(-R(1, 2), R(2, 2));
    } else {
        // Gimbal lock: only a combination of a and g is defined; scipy sets the last angle (g)
        // to 0, leaving R = Ry(+-90) Rz(a), whose second row is (sin a, cos a, 0).
        a = std::atan2(R(1, 0), R(1, 1));
    }
    return Eigen::Vector3d(a, b, g) * kDegPerRad;
}

Eigen::Vector3d EulerXyzDegFromRotation(const Eigen::Matrix3d& R) {
    // R = Rz(c) Ry(b) Rx(a) has last row (-sin b, cos b sin a, cos b cos a) and first column
    // (cos c cos b, sin c cos b, -sin b).
    const double cos_b = std::hypot(R(2, 1), R(2, 2));
    const double b = std::atan2(-R(2, 0), cos_b);
    double a = 0.0;
    double c = 0.0;
    if (cos_b > kGimbalCos) {
        a = std::atan2(R(2, 1), R(2, 2));
        c = std::atan2(R(1, 0), R(0, 0));
    } else {
        // Gimbal lock: scipy sets the last angle (c) to 0, leaving R = Ry(+-90) Rx(a), whose
        // second row is (0, cos a, -sin a).
        a = std::atan2(-R(1, 2), R(1, 1));
    }
    return Eigen::Vector3d(a, b, c) * kDegPerRad;
}

Eigen::Vector3d EulerDegFromRotation(const Eigen::Matrix3d& R, EulerConvention convention) {
    return convention == EulerConvention::kZyx ? EulerZyxDegFromRotation(R)
                                               : EulerXyzDegFromRotation(R);
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
