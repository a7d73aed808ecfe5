// The one angle-wrapping function of the project. Every difference of angles
// (innovations, association, bearings near ±pi) goes through wrapAngle.
#pragma once

#include <cmath>

namespace ekf_slam {

constexpr double kPi = 3.14159265358979323846;

// Wraps `angle` (rad) into [-pi, pi). Finite input only; NaN stays NaN.
inline double wrapAngle(double angle) {
  if (angle >= -kPi && angle < kPi) return angle;
  double wrapped = std::fmod(angle + kPi, 2.0 * kPi);
  if (wrapped < 0.0) wrapped += 2.0 * kPi;
  return wrapped - kPi;
}

inline constexpr double degToRad(double degrees) { return degrees * kPi / 180.0; }
inline constexpr double radToDeg(double radians) { return radians * 180.0 / kPi; }

}  // namespace ekf_slam
