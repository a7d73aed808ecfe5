#include "ekf_slam_core/models/odometry_motion_model.h"

#include <cmath>

namespace ekf_slam {
namespace {

// Below this translation (m) the direction of travel is not defined by the
// data: a millimetre of lateral wheel jitter during a turn on the spot would
// otherwise read as rot1 ≈ ±90°, rot2 ≈ ∓90°, and Q(u) would model two large
// rotations that never happened. Such a step is a turn plus its forward
// component; the lateral part (< 1 cm) is dropped.
constexpr double kMinTranslationForHeading = 0.01;

}  // namespace

bool OdometryControl::allFinite() const {
  return std::isfinite(rot1) && std::isfinite(trans) && std::isfinite(rot2);
}

std::string MotionNoiseOptions::validate() const { return checkFields(*this); }

OdometryControl controlFromOdometry(const Pose2& odom_previous, const Pose2& odom_current) {
  const Pose2 d = between(odom_previous, odom_current);
  OdometryControl u;
  const double distance = std::hypot(d.x, d.y);
  if (distance < kMinTranslationForHeading) {
    u.rot1 = 0.0;
    u.trans = d.x;
    u.rot2 = d.theta;
    return u;
  }
  u.rot1 = std::atan2(d.y, d.x);
  u.trans = distance;
  if (std::abs(u.rot1) > kPi / 2.0) {  // backing up
    u.rot1 = wrapAngle(u.rot1 + kPi);
    u.trans = -distance;
  }
  u.rot2 = wrapAngle(d.theta - u.rot1);
  return u;
}

Pose2 applyControl(const Pose2& pose, const OdometryControl& u, Matrix3* F, Matrix3* G) {
  const double heading = pose.theta + u.rot1;
  const double c = std::cos(heading), s = std::sin(heading);
  if (F) {
    *F << 1, 0, -u.trans * s,  //
        0, 1, u.trans * c,     //
        0, 0, 1;
  }
  if (G) {
    *G << -u.trans * s, c, 0,  //
        u.trans * c, s, 0,     //
        1, 0, 1;
  }
  return Pose2(pose.x + u.trans * c, pose.y + u.trans * s, pose.theta + u.rot1 + u.rot2);
}

Matrix3 controlCovariance(const OdometryControl& u, const MotionNoiseOptions& noise) {
  const double t2 = u.trans * u.trans;
  const double r1 = u.rot1 * u.rot1, r2 = u.rot2 * u.rot2;
  Matrix3 q = Matrix3::Zero();
  q(0, 0) =
      noise.rot_per_rot * r1 + noise.rot_per_trans * t2 + noise.min_rot_sigma * noise.min_rot_sigma;
  q(1, 1) = noise.trans_per_trans * t2 + noise.trans_per_rot * (r1 + r2) +
            noise.min_trans_sigma * noise.min_trans_sigma;
  q(2, 2) =
      noise.rot_per_rot * r2 + noise.rot_per_trans * t2 + noise.min_rot_sigma * noise.min_rot_sigma;
  // Random walk: the heading diffuses along the drive, half of it before and
  // half after the translation in the rotate–translate–rotate split.
  const double distance = std::abs(u.trans);
  q(0, 0) += 0.5 * noise.rot_per_metre * distance + noise.rot_per_radian * std::abs(u.rot1);
  q(1, 1) += noise.trans_per_metre * distance;
  q(2, 2) += 0.5 * noise.rot_per_metre * distance + noise.rot_per_radian * std::abs(u.rot2);
  return q;
}

}  // namespace ekf_slam
