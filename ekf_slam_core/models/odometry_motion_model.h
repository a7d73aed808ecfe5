// Odometry motion model (thesis §2.3.2, §3.2.1, §3.4.2), generalised.
//
// The SLAM frame is independent of the robot's own odometry frame: the robot
// is never corrected. The control u of an iteration is extracted from two
// successive odometry poses o_{k-1}, o_k as the relative motion
//   d = ⊖o_{k-1} ⊕ o_k = (dx, dy, dθ)          (in the robot frame at k-1)
// decomposed rotate–translate–rotate:
//   u = (rot1, trans, rot2),  rot1 = atan2(dy, dx), trans = |(dx, dy)|,
//                             rot2 = dθ − rot1,
// with trans taken negative (and rot1 turned by π) when the robot backs up,
// so a reverse motion is not mistaken for a half turn, and, below 1 cm of
// translation, where the direction of travel is undefined, u = (0, dx, dθ)
// (a turn on the spot with its small forward part; lateral jitter dropped). The thesis allows only
// a pure translation or a pure rotation per step (rot2 = 0); this model
// accepts any motion, so every scan can be an iteration.
//
// Prediction (eq. 2.37 with the extra final rotation):
//   x' = x + trans cos(θ + rot1)
//   y' = y + trans sin(θ + rot1)
//   θ' = θ + rot1 + rot2
// Jacobians (derived in docs/maths.md, checked numerically in the tests):
//   F = ∂x'/∂x = [1 0 −trans sin(θ+rot1); 0 1 trans cos(θ+rot1); 0 0 1]
//   G = ∂x'/∂u = [−trans sin(θ+rot1)  cos(θ+rot1)  0;
//                  trans cos(θ+rot1)  sin(θ+rot1)  0;
//                  1                  0            1]
// Noise on u is zero-mean Gaussian with diagonal covariance Q(u) growing with
// the motion (MotionNoiseOptions).
#pragma once

#include <string>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

struct OdometryControl {
  double rot1 = 0.0;   // rad, turn before translating
  double trans = 0.0;  // m, signed (negative when driving backwards)
  double rot2 = 0.0;   // rad, turn after translating

  Vector3 vector() const { return Vector3(rot1, trans, rot2); }
  bool allFinite() const;
};

// Variances of the control grow with the motion (Thrun et al. style, in SI
// units). All fields ≥ 0.
struct MotionNoiseOptions {
  double rot_per_rot = 0.01;      // rad²/rad²: rotation variance per squared rotation
  double rot_per_trans = 0.0005;  // rad²/m²:   rotation variance per squared translation
  double trans_per_trans = 0.01;  // m²/m²:     translation variance per squared translation
  double trans_per_rot = 0.0001;  // m²/rad²:   translation variance per squared rotation
  double min_rot_sigma = 0.0;     // rad: floor added in quadrature to each rotation
  double min_trans_sigma = 0.0;   // m:   floor added in quadrature to the translation
  // Random-walk terms: variance linear in the motion. Wheel slip and encoder
  // quantisation add independent errors along the way, so the error of a
  // drive of length d has variance ∝ d, whatever the number of filter steps
  // it is cut into. The quadratic terms above (thesis §3.4.2) instead give a
  // drive cut into N steps 1/N of the variance of the same drive in one step,
  // so a filter iterating at every scan would trust the odometry too much.
  double rot_per_metre =
      0.0;  // rad²/m:   heading variance per metre driven (split over rot1, rot2)
  double trans_per_metre = 0.0;  // m²/m:     translation variance per metre driven
  double rot_per_radian = 0.0;   // rad²/rad: rotation variance per radian turned

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("rot_per_rot", rot_per_rot, Bounds::atLeast(0.0, "rad²/rad²"));
    v.number("rot_per_trans", rot_per_trans, Bounds::atLeast(0.0, "rad²/m²"));
    v.number("trans_per_trans", trans_per_trans, Bounds::atLeast(0.0, "m²/m²"));
    v.number("trans_per_rot", trans_per_rot, Bounds::atLeast(0.0, "m²/rad²"));
    v.number("min_rot_sigma", min_rot_sigma, Bounds::atLeast(0.0, "rad"));
    v.number("min_trans_sigma", min_trans_sigma, Bounds::atLeast(0.0, "m"));
    v.number("rot_per_metre", rot_per_metre, Bounds::atLeast(0.0, "rad²/m"));
    v.number("trans_per_metre", trans_per_metre, Bounds::atLeast(0.0, "m²/m"));
    v.number("rot_per_radian", rot_per_radian, Bounds::atLeast(0.0, "rad²/rad"));
  }

  // Empty when valid, else a message naming the bad field.
  std::string validate() const;
};

// u from two odometry poses (pose differences; §3.4.2).
OdometryControl controlFromOdometry(const Pose2& odom_previous, const Pose2& odom_current);

// The pose reached by applying u to `pose`. Optional Jacobians F (pose), G (u).
Pose2 applyControl(const Pose2& pose, const OdometryControl& u, Matrix3* F = nullptr,
                   Matrix3* G = nullptr);

// Covariance Q of u (3×3 diagonal, order rot1, trans, rot2).
Matrix3 controlCovariance(const OdometryControl& u, const MotionNoiseOptions& noise);

}  // namespace ekf_slam
