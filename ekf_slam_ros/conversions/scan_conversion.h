// sensor_msgs/LaserScan → ekf_slam::Scan, the one place where a ROS laser
// message enters the core. Ranges are copied as they are: invalid readings
// (NaN, ±inf, values at or above range_max such as the Freiburg logs'
// 81.83/81.91 m "no return") stay in place and the core skips them
// (ekf_slam_core/sensors/scan.h), so beam indices keep their bearings.
#pragma once

#include <sensor_msgs/LaserScan.h>

#include <string>

#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {
namespace ros_conversions {

// The scan in the message's own (laser) frame; stamp = header.stamp in
// seconds (data time, never the time of conversion).
Scan fromLaserScan(const sensor_msgs::LaserScan& message);

// Empty when the number of ranges fits the angle fields, that is
// (angle_max − angle_min) / angle_increment + 1 to within one reading
// (drivers differ on whether angle_max is the last beam's angle), else a
// message naming both numbers. Fields that give no count (a zero or
// non-finite increment) are left to validateScan.
std::string rangeCountError(const sensor_msgs::LaserScan& message);

}  // namespace ros_conversions
}  // namespace ekf_slam
