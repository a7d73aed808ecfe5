#include "ekf_slam_ros/conversions/scan_conversion.h"

#include <cmath>
#include <sstream>

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

std::string rangeCountError(const sensor_msgs::LaserScan& message) {
  const double span = static_cast<double>(message.angle_max) - message.angle_min;
  const double increment = message.angle_increment;
  if (!std::isfinite(span) || !std::isfinite(increment) || increment == 0.0) return "";
  const double expected = span / increment + 1.0;
  const double count = static_cast<double>(message.ranges.size());
  if (std::abs(count - expected) <= 1.001) return "";  // float32 angle fields
  std::ostringstream text;
  text.precision(6);
  text << message.ranges.size() << " ranges, but angle_min " << message.angle_min << ", angle_max "
       << message.angle_max << " and angle_increment " << increment << " give "
       << std::lround(expected);
  return text.str();
}

}  // namespace ros_conversions
}  // namespace ekf_slam
