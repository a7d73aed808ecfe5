// map → odom on tf (REP-105): the map frame is a separate estimate, and
// nothing is written back into the robot (thesis §3.4.2). Sent once per
// processed scan, and re-sent between scans by a timer (tf_publish_rate)
// stamped with the newest odom → base_link, so that map → base_link stays
// available at the odometry's rate. Each stamp goes out once, future-dated
// by transform_tolerance. Nothing is sent with publish_tf false.
//
// Owns the broadcaster, the timer and the estimate last sent.
#pragma once

#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"
#include "ekf_slam_ros/slam_node/transform_source.h"

namespace ekf_slam {

class MapToOdomBroadcaster {
 public:
  // `params` and `transforms` must outlive the broadcaster.
  MapToOdomBroadcaster(ros::NodeHandle node, const SlamNodeParams& params,
                       const TransformSource& transforms);

  // A new estimate from the scan stamped `stamp`: sent now, even when the
  // timer already used a newer stamp.
  void update(const Pose2& map_to_odom, const ros::Time& stamp);
  // No estimate (a new map): nothing is sent until the next update.
  void clear() { have_estimate_ = false; }
  // The clock went back: the next stamps may be older than those sent.
  void restartStamps() { last_stamp_ = ros::Time(); }

 private:
  // new_estimate: map_to_odom_ was just updated from a scan.
  void publish(const ros::Time& data_stamp, bool new_estimate);
  void onTimer(const ros::TimerEvent&);

  const SlamNodeParams& params_;
  const TransformSource& transforms_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Timer timer_;
  bool have_estimate_ = false;
  Pose2 map_to_odom_;
  ros::Time last_stamp_;  // map→odom stamp last sent (before the tolerance)
};

}  // namespace ekf_slam
