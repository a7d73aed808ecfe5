// The robot's planar pose from tf, for the nodes that drive it
// (waypoint_driver, explorer_node): the newest transform frame -> base
// frame, refused when it is missing or older than a timeout (a stopped
// localisation, a dead driver), with the reason.
#pragma once

#include <ros/time.h>
#include <tf2_ros/buffer.h>

#include <optional>
#include <string>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {
namespace waypoints {

// The pose of `base_frame` in `frame` from the newest transform in
// `buffer`; none when there is none or it is more than `timeout` s older
// than `now`, and then `why` says which.
std::optional<Pose2> lookupRobotPose(const tf2_ros::Buffer& buffer, const std::string& frame,
                                     const std::string& base_frame, const ros::Time& now,
                                     double timeout, std::string* why);

}  // namespace waypoints
}  // namespace ekf_slam
