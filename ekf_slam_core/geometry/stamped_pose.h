// A pose with the time it holds for: one line of a trajectory.
#pragma once

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

struct StampedPose {
  double stamp = 0.0;  // s
  Pose2 pose;
};

}  // namespace ekf_slam
