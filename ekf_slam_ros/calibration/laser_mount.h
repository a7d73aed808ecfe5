// The base_link -> laser mount of config/calibration.yaml: one file read by
// both the tf publisher (what SLAM sees) and the simulator (where the
// simulated scanner really is), so the two can never disagree. No ROS.
#pragma once

#include <string>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {
namespace calibration {

struct LaserMount {
  std::string parent_frame = "base_link";
  std::string child_frame = "laser";
  double x = 0.0;    // m, forward of the centre of rotation
  double y = 0.0;    // m, left
  double z = 0.0;    // m, up (display only; the SLAM is planar)
  double yaw = 0.0;  // rad, counter-clockwise
  // rad, the scan plane's tilt from the floor's (optional keys, 0 when
  // absent): roll lifts the left side, pitch tips the front down (REP-103,
  // rotation yaw · pitch · roll). The SLAM levels each scan with them.
  double roll = 0.0;
  double pitch = 0.0;

  // The planar part: the laser pose in base_link.
  Pose2 pose() const { return Pose2(x, y, yaw); }
};

// Reads `path`. Returns "" on success, else one message per problem, each
// naming the file and the key ("calibration.yaml: yaw: must be in [-3.1416,
// 3.1416], got 7"). Every key is required but roll and pitch (0 when
// absent); unknown keys are errors (a typo must not silently leave the
// laser at the origin).
std::string loadLaserMount(const std::string& path, LaserMount* mount);

// Writes `mount` to `path` in the same format, atomically (a failure leaves
// an earlier file unchanged), with `comment` (one or more lines, may be
// empty) as the file's heading. Returns "" on success, else the problem.
std::string saveLaserMount(const std::string& path, const LaserMount& mount,
                           const std::string& comment);

}  // namespace calibration
}  // namespace ekf_slam
