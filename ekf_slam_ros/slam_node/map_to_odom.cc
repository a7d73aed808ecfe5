#include "ekf_slam_ros/slam_node/map_to_odom.h"

#include <geometry_msgs/TransformStamped.h>

#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {

MapToOdomBroadcaster::MapToOdomBroadcaster(ros::NodeHandle node, const SlamNodeParams& params,
                                           const TransformSource& transforms)
    : params_(params), transforms_(transforms) {
  timer_ = node.createTimer(ros::Duration(1.0 / params_.tf_publish_rate),
                            &MapToOdomBroadcaster::onTimer, this);
}

void MapToOdomBroadcaster::update(const Pose2& map_to_odom, const ros::Time& stamp) {
  map_to_odom_ = map_to_odom;
  have_estimate_ = true;
  publish(stamp, /*new_estimate=*/true);
}

void MapToOdomBroadcaster::publish(const ros::Time& data_stamp, bool new_estimate) {
  // Each stamp once (tf2 listeners warn about repeated data); stamped with
  // data time, future-dated by transform_tolerance so that consumers can
  // look up map → base_link until the next update (as amcl and gmapping do).
  if (!have_estimate_ || !params_.publish_tf) return;
  ros::Time stamp = data_stamp;
  if (stamp <= last_stamp_) {
    // The timer has already re-sent the previous estimate stamped with
    // newer odometry (the scan waited for it). A new estimate (a loop's
    // correction among them) goes out now, just after that stamp, rather
    // than at the timer's next tick.
    if (!new_estimate) return;
    stamp = last_stamp_ + ros::Duration(0, 1000);
  }
  last_stamp_ = stamp;
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp + ros::Duration(params_.transform_tolerance);
  t.header.frame_id = params_.map_frame;
  t.child_frame_id = params_.odom_frame;
  t.transform.translation.x = map_to_odom_.x;
  t.transform.translation.y = map_to_odom_.y;
  t.transform.rotation = ros_conversions::quaternionOfYaw(map_to_odom_.theta);
  broadcaster_.sendTransform(t);
}

void MapToOdomBroadcaster::onTimer(const ros::TimerEvent&) {
  // Between scans map → odom is constant; re-sent with the stamp of the
  // newest odom → base_link (data time). No odometry at all right now:
  // nothing newer to stamp with.
  if (!have_estimate_) return;
  const std::optional<ros::Time> latest =
      transforms_.latestStamp(params_.odom_frame, params_.base_frame);
  if (latest) publish(*latest, /*new_estimate=*/false);
}

}  // namespace ekf_slam
