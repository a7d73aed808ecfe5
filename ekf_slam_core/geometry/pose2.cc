#include "ekf_slam_core/geometry/pose2.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {

Matrix2 Pose2::rotation() const {
  const double c = std::cos(theta), s = std::sin(theta);
  Matrix2 r;
  r << c, -s, s, c;
  return r;
}

Pose2 compose(const Pose2& a, const Pose2& b, Matrix3* J_out_a, Matrix3* J_out_b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  if (J_out_a) {
    *J_out_a << 1, 0, -s * b.x - c * b.y,  //
        0, 1, c * b.x - s * b.y,           //
        0, 0, 1;
  }
  if (J_out_b) {
    *J_out_b << c, -s, 0,  //
        s, c, 0,           //
        0, 0, 1;
  }
  return Pose2(a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, a.theta + b.theta);
}

Pose2 inverse(const Pose2& a, Matrix3* J_out_a) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  if (J_out_a) {
    *J_out_a << -c, -s, s * a.x - c * a.y,  //
        s, -c, c * a.x + s * a.y,           //
        0, 0, -1;
  }
  return Pose2(-c * a.x - s * a.y, s * a.x - c * a.y, -a.theta);
}

Pose2 between(const Pose2& a, const Pose2& b, Matrix3* J_out_a, Matrix3* J_out_b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  const double dx = b.x - a.x, dy = b.y - a.y;
  if (J_out_a) {
    *J_out_a << -c, -s, -s * dx + c * dy,  //
        s, -c, -c * dx - s * dy,           //
        0, 0, -1;
  }
  if (J_out_b) {
    *J_out_b << c, s, 0,  //
        -s, c, 0,         //
        0, 0, 1;
  }
  return Pose2(c * dx + s * dy, -s * dx + c * dy, b.theta - a.theta);
}

Vector2 transformFrom(const Pose2& pose, const Vector2& point, Matrix23* J_out_pose,
                      Matrix2* J_out_point) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  if (J_out_pose) {
    *J_out_pose << 1, 0, -s * point.x() - c * point.y(),  //
        0, 1, c * point.x() - s * point.y();
  }
  if (J_out_point) *J_out_point << c, -s, s, c;
  return Vector2(pose.x + c * point.x() - s * point.y(), pose.y + s * point.x() + c * point.y());
}

Vector2 transformTo(const Pose2& pose, const Vector2& point, Matrix23* J_out_pose,
                    Matrix2* J_out_point) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const double dx = point.x() - pose.x, dy = point.y() - pose.y;
  if (J_out_pose) {
    *J_out_pose << -c, -s, -s * dx + c * dy,  //
        s, -c, -c * dx - s * dy;
  }
  if (J_out_point) *J_out_point << c, s, -s, c;
  return Vector2(c * dx + s * dy, -s * dx + c * dy);
}

double maxAbsDifference(const Pose2& a, const Pose2& b) {
  return std::max(
      {std::abs(a.x - b.x), std::abs(a.y - b.y), std::abs(wrapAngle(a.theta - b.theta))});
}

}  // namespace ekf_slam
