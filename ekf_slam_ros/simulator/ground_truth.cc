#include "ekf_slam_ros/simulator/ground_truth.h"

#include <geometry_msgs/TransformStamped.h>

#include <cmath>

#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace sim {

using ros_conversions::toPoseMessage;

nav_msgs::Odometry toOdometry(const Pose2& pose, double velocity, double rotational_velocity,
                              const ros::Time& stamp, const std::string& frame,
                              const std::string& child_frame) {
  nav_msgs::Odometry message;
  message.header.stamp = stamp;
  message.header.frame_id = frame;
  message.child_frame_id = child_frame;
  message.pose.pose = toPoseMessage(pose);
  // Exact by construction: zero covariance is the truth here, not "unknown".
  message.twist.twist.linear.x = velocity;
  message.twist.twist.angular.z = rotational_velocity;
  return message;
}

nav_msgs::OccupancyGrid toOccupancyGrid(const GridWorld& world, const Pose2& frame_in_world,
                                        const ros::Time& stamp, const std::string& frame) {
  nav_msgs::OccupancyGrid grid;
  grid.header.stamp = stamp;
  grid.header.frame_id = frame;
  grid.info.map_load_time = stamp;
  grid.info.resolution = static_cast<float>(world.resolution());
  grid.info.width = static_cast<uint32_t>(world.width());
  grid.info.height = static_cast<uint32_t>(world.height());
  // Cell (0, 0)'s corner, in the world, then seen from the target frame.
  const Pose2 origin_in_world(world.origin().x(), world.origin().y(), 0.0);
  grid.info.origin = toPoseMessage(between(frame_in_world, origin_in_world));
  grid.data.resize(static_cast<size_t>(world.width()) * world.height());
  for (int iy = 0; iy < world.height(); ++iy) {
    for (int ix = 0; ix < world.width(); ++ix) {
      grid.data[static_cast<size_t>(iy) * world.width() + ix] = world.occupied(ix, iy) ? 100 : 0;
    }
  }
  return grid;
}

GroundTruthPublisher::GroundTruthPublisher(ros::NodeHandle& node, const GridWorld& world,
                                           const Pose2& start, Frames frames, double path_spacing)
    : start_(start), frames_(std::move(frames)), path_spacing_(path_spacing) {
  odom_publisher_ = node.advertise<nav_msgs::Odometry>("ground_truth/odom", 20);
  path_publisher_ = node.advertise<nav_msgs::Path>("ground_truth/path", 2, true);
  world_publisher_ = node.advertise<nav_msgs::OccupancyGrid>("ground_truth/world", 1, true);
  world_publisher_.publish(toOccupancyGrid(world, start_, ros::Time::now(), frames_.map));
  path_.header.frame_id = frames_.map;
}

void GroundTruthPublisher::publish(const Pose2& truth, double velocity, double rotational_velocity,
                                   const ros::Time& stamp) {
  const nav_msgs::Odometry odometry =
      toOdometry(truth, velocity, rotational_velocity, stamp, frames_.truth, frames_.truth_child);
  odom_publisher_.publish(odometry);
  geometry_msgs::TransformStamped transform;
  transform.header = odometry.header;
  transform.child_frame_id = frames_.truth_child;
  transform.transform.translation.x = truth.x;
  transform.transform.translation.y = truth.y;
  transform.transform.rotation = odometry.pose.pose.orientation;
  tf_broadcaster_.sendTransform(transform);

  // The same pose in the SLAM map frame: start⁻¹ ∘ truth.
  const Pose2 in_map = between(start_, truth);
  const bool moved = path_.poses.empty() ||
                     std::hypot(in_map.x - path_.poses.back().pose.position.x,
                                in_map.y - path_.poses.back().pose.position.y) >= path_spacing_;
  if (moved) {
    geometry_msgs::PoseStamped pose;
    pose.header.stamp = stamp;
    pose.header.frame_id = frames_.map;
    pose.pose = toPoseMessage(in_map);
    path_.poses.push_back(pose);
  }
  // The whole path at 2 Hz is plenty for rviz, and cheap for long runs.
  if (last_path_publish_.isZero() || (stamp - last_path_publish_).toSec() >= 0.5) {
    last_path_publish_ = stamp;
    path_.header.stamp = stamp;
    path_publisher_.publish(path_);
  }
}

}  // namespace sim
}  // namespace ekf_slam
