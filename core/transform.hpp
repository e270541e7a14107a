#pragma once
// Rigid transform helpers: compose, invert, apply, Euler zyx <-> matrix, axis-angle.
#include <Eigen/Geometry>

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

/// Rotation R = Rz(z) * Ry(y) * Rx(x): the intrinsic zyx convention. Its Euler angles
/// as scipy's Rotation.as_euler('zyx', degrees=True) returns them are (z, y, x).
Eigen::Matrix3d RotationFromEulerZyxDeg(double z_deg, double y_deg, double x_deg);
/// scipy's as_euler('zyx', degrees=True): returns (z, y, x) in degrees,
/// z, x in (-180, 180], y in [-90, 90].
Eigen::Vector3d EulerZyxDegFromRotation(const Eigen::Matrix3d& R);
/// R = Rx(x) * Ry(y) * Rz(z) with angles in degrees: the paper's motion convention.
Eigen::Matrix3d RotationXyzProductDeg(double x_deg, double y_deg, double z_deg);
/// Rotation about a (not necessarily unit) axis by angle_rad.
Eigen::Matrix3d RotationFromAxisAngle(const Eigen::Vector3d& axis, double angle_rad);
/// Rotation angle in degrees between two rotations: arccos((tr(Ra^T Rb) - 1) / 2).
double RotationAngleDeg(const Eigen::Matrix3d& Ra, const Eigen::Matrix3d& Rb);
/// True when R is orthonormal with det +1 within tol.
bool IsRotation(const Eigen::Matrix3d& R, double tol = 1e-9);

}  // namespace regbench
