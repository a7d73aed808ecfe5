#include "ekf_slam_ros/conversions/scan_conversion.h"

namespace ekf_slam {
namespace ros_conversions {

Scan fromLaserScan(const sensor_msgs::LaserScan& message) {
  Scan scan;
  scan.ranges.assign(message.ranges.begin(), message.ranges.end());
  scan.angle_min = message.angle_min;
  scan.angle_increment = message.angle_increment;
  scan.range_min = message.range_min;
  scan.range_max = message.range_max;
  scan.stamp = message.header.stamp.toSec();
  return scan;
}

}  // namespace ros_conversions
}  // namespace ekf_slam
