// Reads every sensor_msgs/LaserScan of a bag, in file order (the Freiburg
// logs' stamps go backwards in places, so never sort by time), as core Scans.
#pragma once

#include <functional>
#include <string>

#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {
namespace ros_conversions {

// Calls `on_scan(index, scan)` for each LaserScan on `topic` (any topic when
// empty); stops early when on_scan returns false. Returns the number of scans
// delivered. Throws rosbag::BagException when the bag cannot be read.
int forEachBagScan(const std::string& bag_path, const std::string& topic,
                   const std::function<bool(int, const Scan&)>& on_scan);

}  // namespace ros_conversions
}  // namespace ekf_slam
