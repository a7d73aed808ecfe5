// calibration_tf_publisher: broadcasts the base_link -> laser mount of
// config/calibration.yaml as a static transform (latched on /tf_static).
//
//   rosrun ekf_slam calibration_tf_publisher _file:=$(rospack find
//   ekf_slam)/config/calibration.yaml
//
// Private parameter `file` (required): the calibration YAML. A missing or
// malformed file stops the node with a message naming the file and the key;
// a robot must not run SLAM with the laser silently at the origin.
#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cmath>
#include <string>

#include "ros_conversions/pose_conversion.h"

#include "ekf_slam_ros/calibration/laser_mount.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "calibration_tf_publisher");
  ros::NodeHandle private_node("~");
  std::string file;
  if (!private_node.getParam("file", file) || file.empty()) {
    ROS_FATAL("parameter %s is required: the calibration YAML (config/calibration.yaml)",
              private_node.resolveName("file").c_str());
    return 1;
  }
  ekf_slam::calibration::LaserMount mount;
  const std::string error = ekf_slam::calibration::loadLaserMount(file, &mount);
  if (!error.empty()) {
    ROS_FATAL("%s", error.c_str());
    return 1;
  }

  geometry_msgs::TransformStamped transform;
  transform.header.stamp = ros::Time::now();
  transform.header.frame_id = mount.parent_frame;
  transform.child_frame_id = mount.child_frame;
  transform.transform.translation.x = mount.x;
  transform.transform.translation.y = mount.y;
  transform.transform.translation.z = mount.z;
  transform.transform.rotation =
      ekf_slam::ros_conversions::quaternionOfRollPitchYaw(mount.roll, mount.pitch, mount.yaw);
  tf2_ros::StaticTransformBroadcaster broadcaster;
  broadcaster.sendTransform(transform);
  ROS_INFO(
      "calibration: %s -> %s at x %.3f m, y %.3f m, z %.3f m, yaw %.4f rad, roll %.4f rad, "
      "pitch %.4f rad (from %s)",
      mount.parent_frame.c_str(), mount.child_frame.c_str(), mount.x, mount.y, mount.z, mount.yaw,
      mount.roll, mount.pitch, file.c_str());
  ros::spin();  // the latched message lives as long as this node
  return 0;
}
