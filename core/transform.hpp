#pragma once
// Rigid transform helpers: compose, invert, apply, Euler angles, axis-angle.
#include <Eigen/Geometry>
#include <string>

#include "core/point_cloud.hpp"

namespace regbench {

/// Builds a 4x4 transform from rotation (or s*R) and translation.
Transform MakeTransform(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
/// Inverse of a rigid transform (uses R^T, so R must be orthonormal).
Transform InvertRigid(const Transform& T);
/// T_a_c = T_a_b * T_b_c.
Transform Compose(const Transform& T_a_b, const Transform& T_b_c);
/// Applies T to every point: p' = R p + t.
PointCloud Apply(const Transform& T, const PointCloud& points);

/// Euler-angle conventions of the rotation metrics (mae_r, rmse_r), named as scipy names them.
/// Both are *extrinsic* (lower-case in scipy): rotations about the fixed axes in the named order.
enum class EulerConvention {
    kZyx,  ///< scipy as_euler('zyx'): R = Rx(x) Ry(y) Rz(z), angles (z, y, x); DCP/OGMM's metric
    kXyz,  ///< scipy as_euler('xyz'): R = Rz(z) Ry(y) Rx(x), angles (x, y, z); RPMNet's metric
};
/// "zyx" or "xyz".
const char* ToString(EulerConvention convention);
/// Parses "zyx" / "xyz"; throws std::invalid_argument naming the value otherwise.
EulerConvention ParseEulerConvention(const std::string& name);

/// Rotation R = Rz(z) * Ry(y) * Rx(x) (scipy from_euler('ZYX', [z, y, x]) -- upper case,
/// intrinsic -- which equals from_euler('xyz', [x, y, z])).
Eigen::Matrix3d RotationZyxProductDeg(double z_deg, double y_deg, double x_deg);
/// Old name of RotationZyxProductDeg (kept so existing callers compile); prefer the new name,
/// which says which matrix product it builds.
inline Eigen::Matrix3d RotationFromEulerZyxDeg(double z_deg, double y_deg, double x_deg) {
    return RotationZyxProductDeg(z_deg, y_deg, x_deg);
}
/// scipy's Rotation.as_euler('zyx', degrees=True) (lower case, extrinsic): for
/// R = Rx(x) Ry(y) Rz(z) returns (z, y, x); z, x in (-180, 180], y in [-90, 90]. At gimbal lock
/// (y = +-90) the last angle (x) is set to 0, as scipy does.
Eigen::Vector3d EulerZyxDegFromRotation(const Eigen::Matrix3d& R);
/// scipy's Rotation.as_euler('xyz', degrees=True) (lower case, extrinsic): for
/// R = Rz(z) Ry(y) Rx(x) returns (x, y, z). At gimbal lock the last angle (z) is set to 0.
Eigen::Vector3d EulerXyzDegFromRotation(const Eigen::Matrix3d& R);
/// The angles of `convention`, in the order scipy returns them.
Eigen::Vector3d EulerDegFromRotation(const Eigen::Matrix3d& R, EulerConvention convention);
/// R = Rx(x) * Ry(y) * Rz(z) with angles in degrees: the paper's motion convention.
Eigen::Matrix3d RotationXyzProductDeg(double x_deg, double y_deg, double z_deg);
/// Rotation about a (not necessarily unit) axis by angle_rad.
Eigen::Matrix3d RotationFromAxisAngle(const Eigen::Vector3d& axis, double angle_rad);
/// Rotation angle in degrees between two rotations: arccos((tr(Ra^T Rb) - 1) / 2).
double RotationAngleDeg(const Eigen::Matrix3d& Ra, const Eigen::Matrix3d& Rb);
/// True when R is orthonormal with det +1 within tol.
bool IsRotation(const Eigen::Matrix3d& R, double tol = 1e-9);

}  // namespace regbench
