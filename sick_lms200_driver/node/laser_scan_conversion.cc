#include "sick_lms200_driver/node/laser_scan_conversion.h"

#include <algorithm>
#include <cmath>

namespace sick_lms200 {
namespace {
constexpr double degToRad(double degrees) { return degrees * M_PI / 180.0; }
}  // namespace

sensor_msgs::LaserScan toLaserScan(const LaserScanData& scan, const ScanMessageOptions& options) {
  sensor_msgs::LaserScan msg;
  msg.header.frame_id = options.frame_id;
  const double half_angle = degToRad(scan.angle_deg / 2.0);
  msg.angle_min = static_cast<float>(-half_angle);
  msg.angle_max = static_cast<float>(half_angle);
  msg.angle_increment = static_cast<float>(degToRad(scan.resolution_centideg / 100.0));
  msg.scan_time = static_cast<float>(
      1.0 / expectedScanRate(scan.angle_deg, scan.resolution_centideg, scan.baud));
  msg.range_min = 0.01f;
  msg.range_max = static_cast<float>(maxRange(scan.values.units));
  msg.ranges = scan.values.ranges;
  if (!options.inverted) {
    msg.header.stamp = ros::Time(scan.first_beam_time);
    msg.time_increment = static_cast<float>(scan.time_increment);
  } else {
    std::reverse(msg.ranges.begin(), msg.ranges.end());
    msg.header.stamp = ros::Time(scan.first_beam_time + scan.sweep_time);
    msg.time_increment = static_cast<float>(-scan.time_increment);
  }
  return msg;
}

}  // namespace sick_lms200
