// ekf_slam_node's outputs: map → odom and its re-publication timer, the
// landmark map, the loop-closed path and the live occupancy grid.
#include "ekf_slam_ros/slam_node/slam_node.h"

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/OccupancyGrid.h>

#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_ros/conversions/grid_conversion.h"
#include "ekf_slam_ros/slam_node/slam_messages.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace {

using ros_conversions::toPoseMessage;

}  // namespace

const std::unordered_map<int, LineSupport>& SlamNode::lineSupport() const {
  static const std::unordered_map<int, LineSupport> kNone;
  return pipeline_ ? pipeline_->lineSupport() : kNone;
}

void SlamNode::publishLandmarkMap(const std_msgs::Header& header) {
  // No filter yet (before the first scan): the map waiting to seed it, or none.
  LandmarkMapFile map;
  if (pipeline_) {
    map = toLandmarkMapFile(pipeline_->filter(), lineSupport(), header.frame_id);
  } else if (seed_map_) {
    map = *seed_map_;
  }
  landmark_map_publisher_.publish(toLandmarkMapMessage(map, header));
}

void SlamNode::publishMapToOdom(const ros::Time& data_stamp, bool new_estimate) {
  // Each stamp once (tf2 listeners warn about repeated data); stamped with
  // data time, future-dated by transform_tolerance so that consumers can
  // look up map → base_link until the next update (as amcl and gmapping do).
  if (!have_map_to_odom_) return;
  ros::Time stamp = data_stamp;
  if (stamp <= last_tf_stamp_) {
    // The timer has already re-sent the previous estimate stamped with
    // newer odometry (the scan waited for it). A new estimate (a loop's
    // correction among them) goes out now, just after that stamp, rather
    // than at the timer's next tick.
    if (!new_estimate) return;
    stamp = last_tf_stamp_ + ros::Duration(0, 1000);
  }
  last_tf_stamp_ = stamp;
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp + ros::Duration(params_.transform_tolerance);
  t.header.frame_id = params_.map_frame;
  t.child_frame_id = params_.odom_frame;
  t.transform.translation.x = map_to_odom_.x;
  t.transform.translation.y = map_to_odom_.y;
  t.transform.rotation = ros_conversions::quaternionOfYaw(map_to_odom_.theta);
  tf_broadcaster_.sendTransform(t);
}

void SlamNode::onTfTimer(const ros::TimerEvent&) {
  // Between scans map → odom is constant; re-sent with the stamp of the
  // newest odom → base_link (data time), so map → base_link stays
  // available at the odometry's rate.
  if (!have_map_to_odom_) return;
  try {
    const ros::Time latest =
        tf_buffer_.lookupTransform(params_.odom_frame, params_.base_frame, ros::Time(0))
            .header.stamp;
    publishMapToOdom(latest);
  } catch (const tf2::TransformException&) {
    // No odometry at all right now: nothing newer to stamp with.
  }
}

void SlamNode::publishLoopClosedPath(const ros::Time& data_stamp) {
  nav_msgs::Path path;
  path.header.stamp = data_stamp;
  path.header.frame_id = params_.map_frame;
  for (const SlamPipeline::KeyScan& key : pipeline_->keyScans(/*with_points=*/false)) {
    geometry_msgs::PoseStamped p;
    p.header.stamp = ros::Time(key.stamp);
    p.header.frame_id = params_.map_frame;
    p.pose = toPoseMessage(key.pose);
    path.poses.push_back(p);
  }
  loop_closed_path_publisher_.publish(path);
}

// A new grid when the key scans changed (a new key scan or a new
// optimisation) and the worker is free; it never blocks the scans.
void SlamNode::onMapTimer(const ros::TimerEvent&) {
  if (!pipeline_ || !live_map_ || !laser_pose_ || hold_loaded_grid_) return;
  const long optimisations = pipeline_->backEndOptimisations();
  std::vector<SlamPipeline::KeyScan> keys = pipeline_->keyScans(/*with_points=*/true);
  if (keys.empty() ||
      (optimisations == optimisations_mapped_ && static_cast<int>(keys.size()) == keys_mapped_)) {
    return;
  }
  std_msgs::Header header;
  header.stamp = last_scan_stamp_;
  header.frame_id = params_.map_frame;
  const int count = static_cast<int>(keys.size());
  if (live_map_->submit(std::move(keys), *laser_pose_, header)) {
    optimisations_mapped_ = optimisations;
    keys_mapped_ = count;
  }
}

bool SlamNode::currentGrid(nav_msgs::OccupancyGrid* map) const {
  nav_msgs::OccupancyGrid live;
  std::chrono::steady_clock::time_point live_time;
  const bool have_live = live_map_ && live_map_->latest(&live, &live_time);
  if (node_grid_ && (!have_live || node_grid_time_ >= live_time)) {
    *map = *node_grid_;
    return true;
  }
  if (have_live) {
    *map = std::move(live);
    return true;
  }
  return false;
}

void SlamNode::publishNodeGrid(const nav_msgs::OccupancyGrid& map) {
  map_publisher_.publish(map);
  node_grid_ = map;
  node_grid_time_ = std::chrono::steady_clock::now();
}

}  // namespace ekf_slam
