#include "ros_conversions/pose_conversion.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {
namespace ros_conversions {
namespace {
constexpr int kPlanarIndex[3] = {0, 1, 5};  // x, y, yaw in the 6×6 layout
}  // namespace

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

geometry_msgs::Quaternion quaternionOfYaw(double yaw) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(0.5 * yaw);
  q.w = std::cos(0.5 * yaw);
  return q;
}

geometry_msgs::Quaternion quaternionOfRollPitchYaw(double roll, double pitch, double yaw) {
  const double cr = std::cos(0.5 * roll), sr = std::sin(0.5 * roll);
  const double cp = std::cos(0.5 * pitch), sp = std::sin(0.5 * pitch);
  const double cy = std::cos(0.5 * yaw), sy = std::sin(0.5 * yaw);
  geometry_msgs::Quaternion q;
  q.w = cr * cp * cy + sr * sp * sy;
  q.x = sr * cp * cy - cr * sp * sy;
  q.y = cr * sp * cy + sr * cp * sy;
  q.z = cr * cp * sy - sr * sp * cy;
  return q;
}

nav_msgs::Path toPathMessage(const std::vector<Vector2>& points, const std_msgs::Header& header) {
  nav_msgs::Path path;
  path.header = header;
  for (const Vector2& point : points) {
    geometry_msgs::PoseStamped stamped;
    stamped.header = header;
    stamped.pose.position.x = point.x();
    stamped.pose.position.y = point.y();
    stamped.pose.orientation.w = 1.0;
    path.poses.push_back(stamped);
  }
  return path;
}

geometry_msgs::Pose toPoseMessage(const Pose2& pose) {
  geometry_msgs::Pose p;
  p.position.x = pose.x;
  p.position.y = pose.y;
  p.orientation = quaternionOfYaw(pose.theta);
  return p;
}

Pose2 fromPoseMessage(const geometry_msgs::Pose& pose) {
  return Pose2(pose.position.x, pose.position.y, yawOf(pose.orientation));
}

Pose2 fromTransformMessage(const geometry_msgs::Transform& transform) {
  return Pose2(transform.translation.x, transform.translation.y, yawOf(transform.rotation));
}

LaserMount laserMountOf(const geometry_msgs::Transform& transform) {
  LaserMount mount;
  mount.pose = fromTransformMessage(transform);
  const geometry_msgs::Quaternion& q = transform.rotation;
  // The laser's z axis in the base frame has z component R₂₂.
  const double up = 1.0 - 2.0 * (q.x * q.x + q.y * q.y);
  mount.inverted = up < 0.0;
  mount.tilt = std::acos(std::min(1.0, std::abs(up)));
  mount.roll = std::atan2(2.0 * (q.w * q.x + q.y * q.z), up);
  mount.pitch = std::asin(std::max(-1.0, std::min(1.0, 2.0 * (q.w * q.y - q.z * q.x))));
  // Mirroring a scan (its bearings negated) turns roll π + δ into δ.
  mount.scan_roll = mount.inverted ? wrapAngle(mount.roll - kPi) : mount.roll;
  mount.scan_pitch = mount.pitch;
  return mount;
}

Matrix3 planarCovariance(const boost::array<double, 36>& covariance) {
  Matrix3 planar;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) planar(r, c) = covariance[kPlanarIndex[r] * 6 + kPlanarIndex[c]];
  }
  return planar;
}

void setPlanarCovariance(const Matrix3& planar, boost::array<double, 36>* covariance) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) (*covariance)[kPlanarIndex[r] * 6 + kPlanarIndex[c]] = planar(r, c);
  }
}

}  // namespace ros_conversions
}  // namespace ekf_slam
