#pragma once
// Mathematical constants used across the tree, defined once.

namespace regbench {

inline constexpr double kPi = 3.14159265358979323846;  ///< pi to double precision
inline constexpr double kDegToRad = kPi / 180.0;       ///< degrees -> radians

}  // namespace regbench
