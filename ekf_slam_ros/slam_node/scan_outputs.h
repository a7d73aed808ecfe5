// What the node publishes per processed scan, in this order: the
// loop-closed path and the pose graph's markers (when the back end
// optimised since the last scan), the
// pose, the path, the odometry path, and, after an iteration, the landmark
// markers, the landmark map and the association report. Every output is
// stamped with the scan's stamp (data time). Also the paths the services
// publish: the landmark map after a reset or a load, and ~smooth's path.
//
// Owns those publishers and the published paths (with the odometry path's
// anchor in the map frame).
#pragma once

#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>

#include <optional>

#include "ekf_slam_core/io/landmark_map.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"

namespace ekf_slam {

class ScanOutputs {
 public:
  // Advertises the topics; `params` must outlive the outputs.
  ScanOutputs(ros::NodeHandle node, const SlamNodeParams& params);

  // The outputs of one scan (`header`: the scan's), given its result and
  // the robot's odometry at it; `pipeline` has processed it.
  void publishScan(const ScanResult& result, const Pose2& odometry, const SlamPipeline& pipeline,
                   const std_msgs::Header& header);
  void publishLandmarkMap(const LandmarkMapFile& map, const std_msgs::Header& header);
  // The path as it stands (after a reset: empty), stamped `stamp`.
  void republishPath(const ros::Time& stamp);
  void publishSmoothedPath(const nav_msgs::Path& path) { smoothed_path_publisher_.publish(path); }
  // A new map: the paths start again.
  void clear();

 private:
  // The loop-closed path and the pose graph's markers.
  void publishLoopClosedPath(const SlamPipeline& pipeline, const ros::Time& stamp);
  // Appends a pose to `path` (kept to path_max_poses) and publishes it.
  void extend(nav_msgs::Path* path, const geometry_msgs::PoseStamped& pose,
              const ros::Publisher& publisher);

  const SlamNodeParams& params_;
  ros::Publisher pose_publisher_, path_publisher_, odometry_path_publisher_, landmarks_publisher_,
      landmark_map_publisher_, association_publisher_, smoothed_path_publisher_,
      loop_closed_path_publisher_, pose_graph_publisher_;
  nav_msgs::Path path_;
  // The robot's own odometry drawn in the map frame, tied to the SLAM pose at
  // the first scan: where the robot would believe it is without SLAM.
  nav_msgs::Path odometry_path_;
  std::optional<Pose2> odometry_anchor_;  // map → odom at the first scan
  long optimisations_published_ = 0;      // back-end optimisations seen by the path
};

}  // namespace ekf_slam
