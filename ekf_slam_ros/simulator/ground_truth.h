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
#include <ros/time.h>

#include <string>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sim/grid_world.h"

namespace ekf_slam {
namespace sim {

geometry_msgs::Pose toPoseMessage(const Pose2& pose);

// The true pose and body velocities (m/s, rad/s) as odometry in `frame`.
nav_msgs::Odometry toOdometry(const Pose2& pose, double velocity, double rotational_velocity,
                              const ros::Time& stamp, const std::string& frame,
                              const std::string& child_frame);

// The world's occupancy (100 occupied, 0 free) with its origin expressed in
// the frame whose pose in the world is `frame_in_world` (the start pose for
// the SLAM map frame).
nav_msgs::OccupancyGrid toOccupancyGrid(const GridWorld& world, const Pose2& frame_in_world,
                                        const ros::Time& stamp, const std::string& frame);

}  // namespace sim
}  // namespace ekf_slam
