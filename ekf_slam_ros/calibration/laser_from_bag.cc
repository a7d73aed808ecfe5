#include "ekf_slam_ros/calibration/laser_from_bag.h"

#include <vector>

#include "ekf_slam_ros/offline/log_input.h"

namespace ekf_slam {
namespace calibration {

std::string calibrateFromBag(const std::string& bag_path, const LaserMount* nominal,
                             const ExtrinsicsOptions& options, BagCalibration* out) {
  LogData log;
  const std::string error = readBag(bag_path, InputOptions{}, &log);
  if (!error.empty()) return error;
  if (nominal) {
    out->nominal = *nominal;
  } else {
    out->nominal = LaserMount{};
    if (log.laser_pose_found) {
      out->nominal.x = log.laser_pose.x;
      out->nominal.y = log.laser_pose.y;
      out->nominal.yaw = log.laser_pose.theta;
    }
    if (!log.laser_frame.empty()) out->nominal.child_frame = log.laser_frame;
  }
  std::vector<Scan> scans;
  std::vector<Pose2> odometry;
  scans.reserve(log.scans.size());
  odometry.reserve(log.scans.size());
  for (const LoggedScan& logged : log.scans) {
    scans.push_back(logged.scan);
    odometry.push_back(logged.odometry);
  }
  out->scans = static_cast<int>(scans.size());
  const std::vector<MotionPair> pairs =
      motionPairs(scans, odometry, out->nominal.pose(), options, &out->refused_matches);
  out->result = estimateLaserPose(pairs, options);
  return "";
}

}  // namespace calibration
}  // namespace ekf_slam
