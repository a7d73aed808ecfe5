// The laser's pose on the robot (base_link → laser) from a recorded drive:
// the odometry's motion between two scans and the scan matcher's motion of
// the laser over the same interval must agree through the mount. This is
// the second step of Censi, Franchi, Marchionni and Oriolo, "Simultaneous
// calibration of odometry and sensor parameters for mobile robots" (IEEE
// T-RO 2013), with the odometry taken as given: the P3-DX's controller
// integrates its encoders itself and a bag holds its poses, not the wheel
// rotations, so the wheel radii and the axle length are not estimated.
//
// Model (docs/maths.md, "Laser mount from motion"). With the mount
// ℓ = (ℓx, ℓy, φ), a robot motion o = (t_o, θ_o) and the laser's motion
// s = (t_s, θ_s) over the same interval satisfy ℓ ⊕ s = o ⊕ ℓ:
//     θ_s = θ_o                                   (no information on ℓ)
//     (I − R(θ_o)) ℓ_t + R(φ) t_s = t_o           (2 equations per interval)
// For a fixed φ the translation ℓ_t is a linear least-squares problem, so
// the cost is a function of φ alone, minimised by a search over the circle
// and refined; outlier intervals (wrong matches, wheel slip) are dropped by
// their residual and the problem solved again.
//
// What each parameter needs: ℓ_t needs turns (I − R(θ_o) vanishes on a
// straight line); φ needs translation. Turning on the spot alone leaves φ
// and the direction of ℓ_t indistinguishable (the equation is invariant
// under rotating both by the same angle). Such data are refused with a
// message naming the motion that is missing.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/scan_matching/scan_matcher.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

// One interval seen by both sensors.
struct MotionPair {
  Pose2 robot;  // base_link motion from the odometry
  Pose2 laser;  // laser motion from scan matching
};

struct ExtrinsicsOptions {
  // Scan pairs: the next scan is matched to the last one used once the
  // odometry has moved this far …
  double pair_distance = 0.25;  // m
  double pair_angle = 0.25;     // rad
  // … and an interval whose laser turn differs from the odometry's by more
  // than this is a wrong match or a slip, not used.
  double max_rotation_disagreement = 0.035;  // rad (2 degrees)
  // Intervals whose residual exceeds outlier_sigmas robust sigmas (but at
  // least min_outlier_residual) are dropped before the final solve.
  double outlier_sigmas = 3.0;
  double min_outlier_residual = 0.01;  // m
  // The result is refused when a parameter's 1-sigma exceeds these: the
  // drive did not excite it.
  double max_sigma_translation = 0.02;  // m
  double max_sigma_yaw = 0.0087;        // rad (0.5 degrees)
  int min_pairs = 10;
  ScanMatcherOptions matcher;  // the scan matcher (its shipped defaults)
};

struct ExtrinsicsResult {
  bool ok = false;
  Pose2 laser_pose;                      // base_link → laser
  Matrix3 covariance = Matrix3::Zero();  // of (x, y, yaw)
  int pairs_used = 0;
  int pairs_dropped = 0;      // outliers and disagreeing turns
  double residual_rms = 0.0;  // m, over the pairs used
  double total_turn = 0.0;    // rad, Σ|θ_o| over the pairs used
  double total_travel = 0.0;  // m, Σ|t_o|
  std::string message;        // why it was refused, or a summary
};

// The mount from motion pairs.
ExtrinsicsResult estimateLaserPose(const std::vector<MotionPair>& pairs,
                                   const ExtrinsicsOptions& options = {});

// Motion pairs from a drive: scans in order with the odometry pose
// (odom → base_link) at each one. `nominal_laser` (the mount believed so
// far) only seeds each match's guess. Scans the matcher cannot align are
// skipped; *refused (optional) counts them.
std::vector<MotionPair> motionPairs(const std::vector<Scan>& scans,
                                    const std::vector<Pose2>& odometry, const Pose2& nominal_laser,
                                    const ExtrinsicsOptions& options = {}, int* refused = nullptr);

}  // namespace ekf_slam
