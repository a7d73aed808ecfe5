// Trajectory files: one "stamp x y theta" line per pose (s, m, m, rad), the
// format of the offline runner's trajectory_*.txt and of the evaluation
// tools' input.
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/stamped_pose.h"

namespace ekf_slam {

// Reads "stamp x y theta" lines (# comments and blank lines skipped).
// Returns an empty string on success, else "<path>:<line>: <problem>"; on
// an error `out` is left untouched.
std::string readTrajectory(const std::string& path, std::vector<StampedPose>* out);
// Six decimals per value.
std::string writeTrajectory(const std::string& path, const std::vector<StampedPose>& poses);

}  // namespace ekf_slam
