// Ground-truth messages of the simulator (ROS adapter, no logic of its own).
//
// Frames: the simulator's world is the frame `ground_truth` (the world
// image's coordinates). The SLAM `map` frame is the robot's start pose in
// that world (the filter starts at the origin of its map), so
//   T_world_map = start_pose   and   pose_in_map = start_pose⁻¹ ∘ pose_in_world.
// The odometry and its tf stay in `ground_truth` (a tree of its own, never
// connected to map/odom); the path and the world grid, meant as rviz
// overlays on the SLAM map, are converted into `map`.
#pragma once

#include <geometry_msgs/Pose.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/time.h>
#include <tf2_ros/transform_broadcaster.h>

#include <string>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sim/grid_world.h"

namespace ekf_slam {
namespace sim {

// The true pose and body velocities (m/s, rad/s) as odometry in `frame`.
nav_msgs::Odometry toOdometry(const Pose2& pose, double velocity, double rotational_velocity,
                              const ros::Time& stamp, const std::string& frame,
                              const std::string& child_frame);

// The world's occupancy (100 occupied, 0 free) with its origin expressed in
// the frame whose pose in the world is `frame_in_world` (the start pose for
// the SLAM map frame).
nav_msgs::OccupancyGrid toOccupancyGrid(const GridWorld& world, const Pose2& frame_in_world,
                                        const ros::Time& stamp, const std::string& frame);

// The simulator's ground-truth topics: ground_truth/odom + tf in the truth
// frame, ground_truth/path and the latched ground_truth/world in the map
// frame (T_world_map = start pose).
class GroundTruthPublisher {
 public:
  struct Frames {
    std::string truth = "ground_truth";
    std::string truth_child = "base_link_truth";
    std::string map = "map";
  };

  // Publishes the world grid (latched) at once.
  GroundTruthPublisher(ros::NodeHandle& node, const GridWorld& world, const Pose2& start,
                       Frames frames, double path_spacing);

  // One ground-truth sample: the true pose in the world and the body
  // velocities (m/s, rad/s). The path grows every path_spacing metres and
  // is republished at most every 0.5 s.
  void publish(const Pose2& truth, double velocity, double rotational_velocity,
               const ros::Time& stamp);

 private:
  Pose2 start_;
  Frames frames_;
  double path_spacing_;
  ros::Publisher odom_publisher_, path_publisher_, world_publisher_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  nav_msgs::Path path_;
  ros::Time last_path_publish_;
};

}  // namespace sim
}  // namespace ekf_slam
