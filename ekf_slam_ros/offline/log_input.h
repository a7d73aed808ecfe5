// Recorded data for offline SLAM: a ROS bag (rosbag C++ API, no roscore) or
// a CARMEN log, turned into scans in file order, each with the robot's
// odometry pose at the scan's stamp and the laser's mounting pose.
//
// Pitfalls of the real logs handled here (../shared/datasets/README.md):
// - stamps going backwards: scans keep their file order (header.seq), they are
//   never sorted by time; the pipeline decides what a late stamp means.
// - odometry at other instants than the scans: interpolated at each scan's
//   stamp (OdometryTrack); gaps beyond max_odometry_gap use the nearest
//   sample and are counted.
// - "no return" ranges above range_max and an all-zero odometry covariance:
//   passed through; the scan and motion models handle them.
// - the laser mount (base_link → the scans' frame): from /tf_static; from
//   /tf only where /tf_static does not hold it (it is then read whole).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ekf_slam_core/sensors/scan.h"
#include "ekf_slam_ros/offline/slam_config.h"

namespace ekf_slam {

struct LoggedScan {
  uint32_t seq = 0;
  Scan scan;
  Pose2 odometry;        // odom → base_link at scan.stamp
  int64_t stamp_ns = 0;  // the scan's header stamp exactly (ns)
};

struct LogData {
  std::vector<LoggedScan> scans;  // file order
  bool laser_pose_found = false;
  Pose2 laser_pose;             // base_link → laser, when found in the log
  bool laser_inverted = false;  // that laser upside down: its scans have been mirrored
  // rad, that laser's tilt (ros_conversions::LaserMount::scan_roll, scan_pitch): its
  // scans have been levelled (levelledScan).
  double laser_roll = 0.0;
  double laser_pitch = 0.0;
  std::string laser_frame;
  long odometry_samples = 0;
  long odometry_gaps = 0;  // scans whose odometry was not interpolated
  long scans_out_of_time_order = 0;
  // Scans left out because their stamp or odometry pose is not finite (a
  // corrupt log line or message): they never reach the filter or a file.
  long unusable_scans = 0;
  std::string first_unusable;  // which one, for the report
  double first_stamp = 0.0, last_stamp = 0.0;
  double duration() const { return last_stamp - first_stamp; }
};

// Empty string on success; otherwise what is wrong, naming the file and, where
// it applies, the topic or frame ("no odometry: topic /odom has no messages").
std::string readBag(const std::string& path, const InputOptions& options, LogData* out);
std::string readCarmen(const std::string& path, LogData* out);

}  // namespace ekf_slam
