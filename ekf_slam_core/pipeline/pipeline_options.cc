#include "ekf_slam_core/pipeline/pipeline_options.h"

#include <cmath>

namespace ekf_slam {

std::string PipelineOptions::validate() const {
  std::string error = validateFeatureOptions(features);
  if (!error.empty()) return "features: " + error;
  error = filter.validate();
  if (!error.empty()) return "filter: " + error;
  error = association.validate();
  if (!error.empty()) return "association: " + error;
  if (!initial_pose.allFinite() || std::abs(initial_pose.x) > kMaxOdometryCoordinate ||
      std::abs(initial_pose.y) > kMaxOdometryCoordinate) {
    return "initial_pose must be finite and within 1e6 m of the map origin";
  }
  if (!initial_pose_covariance.allFinite() ||
      !initial_pose_covariance.isApprox(initial_pose_covariance.transpose()) ||
      initial_pose_covariance.diagonal().minCoeff() < 0.0) {
    return "initial_pose_covariance must be finite, symmetric, with a non-negative diagonal";
  }
  error = checkFields(*this);
  if (!error.empty()) return error;
  if (min_landmark_range >= max_landmark_range) {
    return "min_landmark_range must be below max_landmark_range (m)";
  }
  error = scan_matching.validate();
  if (!error.empty()) return "scan_matching: " + error;
  error = scan_matched_motion_noise.validate();
  if (!error.empty()) return "scan_matching.motion_noise: " + error;
  error = loop_closure.validate();
  if (!error.empty()) return "loop_closure: " + error;
  error = smoother.validate();
  if (!error.empty()) return "smoother: " + error;
  error = rooms.doorways.validate();
  if (!error.empty()) return "rooms.doorways: " + error;
  error = rooms.map.validate();
  if (!error.empty()) return "rooms.map: " + error;
  if (rooms.enabled && landmarks != LandmarkSet::kPointsAndLines &&
      landmarks != LandmarkSet::kPointsAndLineAngles) {
    return "rooms.enabled needs walls: landmarks points+lines or points+lines_theta";
  }
  if (history_scans < 0) return "history_scans must be >= 0 (0: every scan)";
  if (keep_readings) {
    error = readings_grid.validate();
    if (!error.empty()) return "readings_grid: " + error;
  }
  return "";
}

MotionNoiseOptions PipelineOptions::defaultScanMatchedMotionNoise() {
  MotionNoiseOptions noise;
  noise.rot_per_rot = 0.0004;      // 2 % of the turn (1 sigma)
  noise.rot_per_trans = 0.0001;    // 0.6 deg per m driven
  noise.trans_per_trans = 0.0004;  // 2 % of the distance
  noise.trans_per_rot = 0.0001;    // 1 cm per rad turned
  noise.min_rot_sigma = 0.002;     // rad (0.11 deg) per step: the matcher's own jitter
  noise.min_trans_sigma = 0.005;   // m per step
  return noise;
}

bool usableOdometry(const Pose2& odometry) {
  return odometry.allFinite() && std::abs(odometry.x) <= kMaxOdometryCoordinate &&
         std::abs(odometry.y) <= kMaxOdometryCoordinate;
}

}  // namespace ekf_slam
