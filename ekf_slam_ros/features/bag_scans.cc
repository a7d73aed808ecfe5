#include "ekf_slam_ros/features/bag_scans.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>

#include "ekf_slam_ros/conversions/scan_conversion.h"

namespace ekf_slam {
namespace ros_conversions {

int forEachBagScan(const std::string& bag_path, const std::string& topic,
                   const std::function<bool(int, const Scan&)>& on_scan) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View view =
      topic.empty() ? rosbag::View(bag) : rosbag::View(bag, rosbag::TopicQuery(topic));
  int count = 0;
  for (const rosbag::MessageInstance& instance : view) {
    const sensor_msgs::LaserScan::ConstPtr message = instance.instantiate<sensor_msgs::LaserScan>();
    if (!message) continue;
    if (!on_scan(count++, fromLaserScan(*message))) break;
  }
  return count;
}

}  // namespace ros_conversions
}  // namespace ekf_slam
