// The odometry's noise, fitted from a drive: each scan pair's robot motion
// as the odometry gives it against the same motion from the scan matcher
// (through the laser mount), in the thesis's control (rot1, trans, rot2)
// and its noise model (docs/maths.md, section 1):
//     var(rot1) = rot_per_rot rot1² + rot_per_trans trans², likewise rot2,
//     var(trans) = trans_per_trans trans² + trans_per_rot (rot1² + rot2²).
// Method of moments: the squared errors of the whole turn (rot1 + rot2) and
// of the translation are regressed on those terms plus a constant, which
// takes the scan matcher's own error (it is reported, not part of the
// odometry's model). A negative coefficient is dropped and the rest refitted.
// The coefficients hold for steps like the pairs' (about pair_distance or
// pair_angle apart, ExtrinsicsOptions); docs/bringup.md says how to drive.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/extrinsics/laser_extrinsics.h"
#include "ekf_slam_core/models/odometry_motion_model.h"

namespace ekf_slam {

struct MotionNoiseFit {
  bool ok = false;
  MotionNoiseOptions noise;                // the four quadratic terms fitted, the rest 0
  double matcher_rotation_sigma = 0.0;     // rad, the constant of the turn's fit
  double matcher_translation_sigma = 0.0;  // m, the constant of the translation's fit
  int pairs = 0;
  double rotation_rms = 0.0;     // rad, odometry − scan matcher over the pairs
  double translation_rms = 0.0;  // m
  std::string message;
};

// `pairs` from motionPairs(); `laser` the mount (base_link → laser).
MotionNoiseFit fitMotionNoise(const std::vector<MotionPair>& pairs, const Pose2& laser,
                              int min_pairs = 20);

}  // namespace ekf_slam
