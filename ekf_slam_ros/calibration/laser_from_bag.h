// The laser mount estimated from a recorded drive (a bag of scans and
// odometry): the automatic calibration of docs/bringup.md, behind the
// calibrate_laser_from_bag program. ROS types only to read the bag.
#pragma once

#include <string>

#include "ekf_slam_core/extrinsics/laser_extrinsics.h"
#include "ekf_slam_ros/calibration/laser_mount.h"

namespace ekf_slam {
namespace calibration {

struct BagCalibration {
  ExtrinsicsResult result;
  LaserMount nominal;       // the mount the drive was recorded with (the seed)
  int scans = 0;            // scans read
  int refused_matches = 0;  // scan pairs the matcher could not align
};

// Reads `bag_path` (the default topics and frames of InputOptions) and
// estimates the mount. `nominal` (the calibration in use) seeds the matches
// and gives the frames; null: the bag's own base_link → laser. Returns ""
// when the bag could be read (the estimate may still be refused: see
// out->result.ok and .message), else what is wrong with the input.
std::string calibrateFromBag(const std::string& bag_path, const LaserMount* nominal,
                             const ExtrinsicsOptions& options, BagCalibration* out);

}  // namespace calibration
}  // namespace ekf_slam
