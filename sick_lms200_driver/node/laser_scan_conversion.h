// LaserScanData (ROS-free) → sensor_msgs/LaserScan: geometry, timing fields,
// REP-117 ranges and the upside-down mounting option.
#pragma once

#include <sensor_msgs/LaserScan.h>

#include <string>

#include "sick_lms200_driver/protocol/scanner_link.h"

namespace sick_lms200 {

struct ScanMessageOptions {
  std::string frame_id = "laser";
  // Scanner mounted upside down: the array is reversed so that angles still
  // increase counter-clockwise in an upright frame; the stamp is then the
  // time of the last beam measured and time_increment is negative.
  bool inverted = false;
};

sensor_msgs::LaserScan toLaserScan(const LaserScanData& scan, const ScanMessageOptions& options);

}  // namespace sick_lms200
