#include "ekf_slam_ros/slam_node/scan_outputs.h"

#include <ekf_slam/AssociationReport.h>
#include <ekf_slam/LandmarkMap.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <visualization_msgs/MarkerArray.h>

#include "ekf_slam_core/pipeline/loop_closed_map.h"
#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_ros/slam_node/slam_messages.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {

using ros_conversions::toPoseMessage;

ScanOutputs::ScanOutputs(ros::NodeHandle node, const SlamNodeParams& params) : params_(params) {
  // One pose per scan: a node catching up after a stall (a loaded machine,
  // a replay) publishes them in bursts, which a slower subscriber (a
  // recorder, a Python tool) must still receive whole.
  pose_publisher_ = node.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", 200);
  path_publisher_ = node.advertise<nav_msgs::Path>("path", 1, /*latch=*/true);
  odometry_path_publisher_ = node.advertise<nav_msgs::Path>("odometry_path", 1, /*latch=*/true);
  landmarks_publisher_ = node.advertise<visualization_msgs::MarkerArray>("landmarks", 1, true);
  landmark_map_publisher_ = node.advertise<LandmarkMap>("landmark_map", 1, /*latch=*/true);
  association_publisher_ = node.advertise<AssociationReport>("association", 10);
  smoothed_path_publisher_ = node.advertise<nav_msgs::Path>("smoothed_path", 1, true);
  loop_closed_path_publisher_ = node.advertise<nav_msgs::Path>("loop_closed_path", 1, true);
  pose_graph_publisher_ = node.advertise<visualization_msgs::MarkerArray>("pose_graph", 1, true);
  path_.header.frame_id = params_.map_frame;
  odometry_path_.header.frame_id = params_.map_frame;
}

void ScanOutputs::publishScan(const ScanResult& result, const Pose2& odometry,
                              const SlamPipeline& pipeline, const std_msgs::Header& header) {
  const ros::Time stamp = header.stamp;
  if (pipeline.backEndOptimisations() != optimisations_published_) {
    optimisations_published_ = pipeline.backEndOptimisations();
    publishLoopClosedPath(pipeline, stamp);
  }
  std_msgs::Header map_header;
  map_header.stamp = stamp;
  map_header.frame_id = params_.map_frame;

  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header = map_header;
  pose.pose.pose = toPoseMessage(result.causal_pose);
  // Between iterations the covariance has grown with the motion since the
  // last one.
  ros_conversions::setPlanarCovariance(result.pose_covariance, &pose.pose.covariance);
  pose_publisher_.publish(pose);

  geometry_msgs::PoseStamped path_pose;
  path_pose.header = map_header;
  path_pose.pose = pose.pose.pose;
  extend(&path_, path_pose, path_publisher_);

  if (!odometry_anchor_) odometry_anchor_ = compose(result.causal_pose, inverse(odometry));
  geometry_msgs::PoseStamped odometry_pose;
  odometry_pose.header = map_header;
  odometry_pose.pose = toPoseMessage(compose(*odometry_anchor_, odometry));
  extend(&odometry_path_, odometry_pose, odometry_path_publisher_);

  if (result.outcome != ScanOutcome::kIterated) return;
  if (landmarks_publisher_.getNumSubscribers() > 0) {
    // Drawn where the loop-closed estimate puts them, as the grid and the
    // pose are, not in the filter's frame.
    const LoopClosedMap map = loopClosedMap(pipeline, result.causal_pose);
    landmarks_publisher_.publish(landmarkMarkers(map.filter, map.support, &result.iteration,
                                                 map_header, params_.ellipse_probability));
  }
  publishLandmarkMap(
      toLandmarkMapFile(pipeline.filter(), pipeline.lineSupport(), map_header.frame_id),
      map_header);
  association_publisher_.publish(
      toAssociationReport(result.observations, result.iteration, header));
}

void ScanOutputs::extend(nav_msgs::Path* path, const geometry_msgs::PoseStamped& pose,
                         const ros::Publisher& publisher) {
  path->header.stamp = pose.header.stamp;
  path->poses.push_back(pose);
  // A long run's whole path re-sent every scan would cost megabytes per
  // message; the published path keeps the newest poses.
  if (params_.path_max_poses > 0 && static_cast<int>(path->poses.size()) > params_.path_max_poses) {
    path->poses.erase(path->poses.begin(), path->poses.end() - params_.path_max_poses);
  }
  publisher.publish(*path);
}

void ScanOutputs::publishLandmarkMap(const LandmarkMapFile& map, const std_msgs::Header& header) {
  landmark_map_publisher_.publish(toLandmarkMapMessage(map, header));
}

void ScanOutputs::republishPath(const ros::Time& stamp) {
  path_.header.stamp = stamp;
  path_publisher_.publish(path_);
}

void ScanOutputs::clear() {
  path_.poses.clear();
  odometry_path_.poses.clear();
  odometry_anchor_.reset();
  optimisations_published_ = 0;
}

void ScanOutputs::publishLoopClosedPath(const SlamPipeline& pipeline, const ros::Time& stamp) {
  nav_msgs::Path path;
  path.header.stamp = stamp;
  path.header.frame_id = params_.map_frame;
  std::vector<Pose2> key_poses;
  for (const SlamPipeline::KeyScan& key : pipeline.keyScans(/*with_points=*/false)) {
    geometry_msgs::PoseStamped p;
    p.header.stamp = ros::Time(key.stamp);
    p.header.frame_id = params_.map_frame;
    p.pose = toPoseMessage(key.pose);
    path.poses.push_back(p);
    key_poses.push_back(key.pose);
  }
  loop_closed_path_publisher_.publish(path);
  pose_graph_publisher_.publish(
      poseGraphMarkers(key_poses, pipeline.backEnd().loops(), path.header));
}

}  // namespace ekf_slam
