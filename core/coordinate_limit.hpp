#pragma once
// One coordinate limit for every entry point of point data.

namespace regbench {

/// The largest coordinate magnitude regbench accepts, one limit for every entry point: the
/// pair-file, PLY/PCD/XYZ and xyz-import readers refuse a larger |x| naming the file and the
/// point, `generate` refuses a --max-translation above half of it, and every method's input
/// check (RegistrationMethod::Align) turns such a cloud into a `failed` row. Why 1e15: PCL's
/// GICP and NDT, and the float E-steps, square and sum coordinates in float; finite
/// coordinates of 1e30 (still "fitting in a float") made PCL's kd-tree assert and abort the
/// whole process. At 1e15 a squared distance is at most ~1e31, and sums of a million of them
/// stay below float's 3.4e38. No metric point cloud comes near it (1e15 m is 6,700 AU).
inline constexpr double kMaxCoordinate = 1e15;

/// The largest translation a transform may carry: one between two clouds within the coordinate
/// limit moves a point by at most twice it. Beyond it a method's result is `failed` and a
/// transform given to `score` is refused (a 1e300 translation was scored `ok`; issue 44).
inline constexpr double kMaxTranslation = 2 * kMaxCoordinate;

}  // namespace regbench
