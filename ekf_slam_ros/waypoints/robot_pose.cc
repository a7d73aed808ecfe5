#include "ekf_slam_ros/waypoints/robot_pose.h"

#include <tf2/exceptions.h>

#include <cstdio>

#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace waypoints {

std::optional<Pose2> lookupRobotPose(const tf2_ros::Buffer& buffer, const std::string& frame,
                                     const std::string& base_frame, const ros::Time& now,
                                     double timeout, std::string* why) {
  geometry_msgs::TransformStamped transform;
  try {
    transform = buffer.lookupTransform(frame, base_frame, ros::Time(0));
  } catch (const tf2::TransformException& exception) {
    *why = "no transform " + frame + " -> " + base_frame + ": " + exception.what();
    return std::nullopt;
  }
  const double age = (now - transform.header.stamp).toSec();
  if (age > timeout) {
    char text[256];
    std::snprintf(text, sizeof(text),
                  "the newest %s -> %s transform is %.2f s old (timeout %.2f s)", frame.c_str(),
                  base_frame.c_str(), age, timeout);
    *why = text;
    return std::nullopt;
  }
  return ros_conversions::fromTransformMessage(transform.transform);
}

}  // namespace waypoints
}  // namespace ekf_slam
