// Planar poses between ROS messages and the core (Pose2, 3×3 covariances):
// the one place where a quaternion becomes a heading and back, for the
// drivers, the live node and the offline runner alike, so that all read a
// transform the same way to the last bit. Below ekf_slam_ros: it needs only
// the core's geometry (tools/ci/check_layers.sh).
#pragma once

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/Transform.h>
#include <nav_msgs/Path.h>

#include <boost/array.hpp>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {
namespace ros_conversions {

// The rotation's heading about z (a planar robot: roll and pitch ignored).
double yawOf(const geometry_msgs::Quaternion& q);
geometry_msgs::Quaternion quaternionOfYaw(double yaw);
// The rotation yaw · pitch · roll (about z, then y, then x: REP-103's roll,
// pitch and yaw; laserMountOf reads them back).
geometry_msgs::Quaternion quaternionOfRollPitchYaw(double roll, double pitch, double yaw);

geometry_msgs::Pose toPoseMessage(const Pose2& pose);
Pose2 fromPoseMessage(const geometry_msgs::Pose& pose);
Pose2 fromTransformMessage(const geometry_msgs::Transform& transform);

// A polyline as a path message: one pose a point, heading 0, each with
// `header` (the frame and the stamp).
nav_msgs::Path toPathMessage(const std::vector<Vector2>& points, const std_msgs::Header& header);

// A planar laser's mount from its 3-D transform base → laser. `pose` is
// planar: the translation and the heading of the laser's x axis (beam
// 0°). `inverted`: the laser's z axis points down (roll or pitch near π),
// so its bearings run clockwise seen from above (see mirroredScan). `tilt`:
// the angle between its scan plane and the floor, 0 when level, upright or
// inverted; `roll` and `pitch` (rad) for messages. `scan_roll` and
// `scan_pitch`: the tilt as levelledScan takes it, for the scan as the
// pipeline sees it (mirrored first when inverted: the roll then counts from
// π); both exactly 0 for a level mount.
struct LaserMount {
  Pose2 pose;
  bool inverted = false;
  double tilt = 0.0;
  double roll = 0.0;
  double pitch = 0.0;
  double scan_roll = 0.0;
  double scan_pitch = 0.0;
};
LaserMount laserMountOf(const geometry_msgs::Transform& transform);

// The (x, y, yaw) block of a ROS 6×6 covariance (row-major, x y z roll
// pitch yaw), and the block written into one (other entries untouched).
Matrix3 planarCovariance(const boost::array<double, 36>& covariance);
void setPlanarCovariance(const Matrix3& planar, boost::array<double, 36>* covariance);

}  // namespace ros_conversions
}  // namespace ekf_slam
