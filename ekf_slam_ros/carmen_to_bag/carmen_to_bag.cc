#include "ekf_slam_ros/carmen_to_bag/carmen_to_bag.h"

#include <nav_msgs/Odometry.h>
#include <ros/message_traits.h>
#include <rosbag/bag.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>
#include <boost/make_shared.hpp>

#include <cmath>
#include <cstdio>

#include "ekf_slam_core/io/carmen_log.h"

namespace ekf_slam {
namespace {

geometry_msgs::Quaternion yawQuaternion(double yaw) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(yaw / 2.0);
  q.w = std::cos(yaw / 2.0);
  return q;
}

// The connection header of a latched publisher of `msg`'s type.
template <class M>
boost::shared_ptr<ros::M_string> latchedHeader(const M& msg) {
  auto header = boost::make_shared<ros::M_string>();
  (*header)["callerid"] = "/carmen_to_bag";
  (*header)["latching"] = "1";
  (*header)["type"] = ros::message_traits::datatype(msg);
  (*header)["md5sum"] = ros::message_traits::md5sum(msg);
  (*header)["message_definition"] = ros::message_traits::definition(msg);
  return header;
}

geometry_msgs::TransformStamped transformOf(const std::string& parent, const std::string& child,
                                            const ros::Time& stamp, const Pose2& pose) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = pose.x;
  t.transform.translation.y = pose.y;
  t.transform.rotation = yawQuaternion(pose.theta);
  return t;
}

sensor_msgs::LaserScan laserScanOf(const Scan& scan, uint32_t seq, const ros::Time& stamp) {
  sensor_msgs::LaserScan msg;
  msg.header.seq = seq;
  msg.header.stamp = stamp;
  msg.header.frame_id = "laser";
  msg.angle_min = static_cast<float>(scan.angle_min);
  msg.angle_increment = static_cast<float>(scan.angle_increment);
  msg.angle_max = static_cast<float>(scan.angle(scan.size() - 1));
  msg.range_min = static_cast<float>(scan.range_min);
  msg.range_max = static_cast<float>(scan.range_max);
  msg.ranges.reserve(scan.ranges.size());
  for (double r : scan.ranges) msg.ranges.push_back(static_cast<float>(r));
  return msg;
}

}  // namespace

std::string convertCarmenToBag(const std::string& carmen_path, const std::string& bag_path,
                               CarmenToBagSummary* summary) {
  CarmenLog log;
  const std::string error = readCarmenLog(carmen_path, &log);
  if (!error.empty()) return error;
  if (log.lasers.empty()) return carmen_path + ": no laser scans (FLASER or ROBOTLASER1 lines)";
  for (size_t i = 0; i < log.lasers.size(); ++i) {
    // rosbag cannot store times at or before the epoch.
    if (!(log.lasers[i].scan.stamp > 0.0)) {
      return carmen_path + ": laser line " + std::to_string(i + 1) +
             " has a non-positive ipc_timestamp, which a bag cannot store";
    }
  }
  const std::string partial = bag_path + ".partial";
  try {
    rosbag::Bag bag;
    bag.open(partial, rosbag::bagmode::Write);
    bag.setCompression(rosbag::compression::BZ2);
    const CarmenLaser& first = log.lasers.front();
    tf2_msgs::TFMessage statics;
    statics.transforms.push_back(
        transformOf("base_link", "laser", ros::Time(first.scan.stamp), first.laser_in_robot));
    // Written once at the start: latched, as tf2's static broadcaster
    // publishes it, so that `rosbag play` hands it to every subscriber that
    // comes later (rviz, a node restarted) and not only to those present
    // at the start.
    bag.write("/tf_static", ros::Time(first.scan.stamp), statics, latchedHeader(statics));
    for (size_t i = 0; i < log.lasers.size(); ++i) {
      const CarmenLaser& laser = log.lasers[i];
      const ros::Time stamp(laser.scan.stamp);
      nav_msgs::Odometry odom;
      odom.header.seq = static_cast<uint32_t>(i);
      odom.header.stamp = stamp;
      odom.header.frame_id = "odom";
      odom.child_frame_id = "base_link";
      odom.pose.pose.position.x = laser.robot_odometry.x;
      odom.pose.pose.position.y = laser.robot_odometry.y;
      odom.pose.pose.orientation = yawQuaternion(laser.robot_odometry.theta);
      bag.write("/odom", stamp, odom);
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(transformOf("odom", "base_link", stamp, laser.robot_odometry));
      bag.write("/tf", stamp, tf);
      bag.write("/scan", stamp, laserScanOf(laser.scan, static_cast<uint32_t>(i), stamp));
    }
    bag.close();
  } catch (const std::exception& e) {
    std::remove(partial.c_str());
    return bag_path + ": cannot write the bag: " + e.what();
  }
  if (std::rename(partial.c_str(), bag_path.c_str()) != 0) {
    std::remove(partial.c_str());
    return bag_path + ": cannot move the finished bag into place";
  }
  if (summary) {
    summary->scans = static_cast<long>(log.lasers.size());
    summary->skipped_lines = log.skipped_lines;
  }
  return "";
}

}  // namespace ekf_slam
