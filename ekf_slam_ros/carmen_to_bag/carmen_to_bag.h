// CARMEN text log → ROS bag, so that the thesis-era logs (FLASER, ODOM,
// ROBOTLASER1 lines) can be replayed with the ROS tools and read by the same
// bag path as the Freiburg bags.
//
// What the bag holds (frames as in ../shared/datasets' bags):
// - /scan       sensor_msgs/LaserScan, frame `laser`, one per laser line in
//               file order, header.seq = its index (file order survives
//               stamps that go backwards), header.stamp = ipc_timestamp.
// - /odom       nav_msgs/Odometry odom → base_link: the robot pose carried by
//               each laser line, stamped like its scan (the pose the offline
//               reader uses for the scan), covariance all zero as in the logs.
// - /tf         the same pose as odom → base_link.
// - /tf_static  base_link → laser, the mount of the first laser line.
// ODOM lines are not copied: the pose on the laser line is the one taken at
// the scan, and mixing both would give two odometry sources on one topic.
//
// The bag is written to "<bag>.partial" and renamed only when complete, so a
// failed conversion never leaves a bag that looks whole.
#pragma once

#include <string>

namespace ekf_slam {

struct CarmenToBagSummary {
  long scans = 0;
  long skipped_lines = 0;  // message types that are not converted
};

// Empty string on success, else the problem ("<log>:<line>: ..." for a bad line).
std::string convertCarmenToBag(const std::string& carmen_path, const std::string& bag_path,
                               CarmenToBagSummary* summary = nullptr);

}  // namespace ekf_slam
