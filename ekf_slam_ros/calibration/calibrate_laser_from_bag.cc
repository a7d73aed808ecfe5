// calibrate_laser_from_bag: the laser mount (base_link → laser x, y, yaw)
// from a recorded drive, with its uncertainty; optionally written as a
// calibration file. docs/bringup.md, "The laser mount".
//
//   calibrate_laser_from_bag --bag drive.bag [--calibration config/calibration.yaml]
//                            [--write config/calibration.yaml]
//
// The drive must turn both ways and travel straight (record.launch while
// driving curves, straights and turns on the spot for a minute or two).
// Exit status: 0 estimated (and written), 1 the drive does not determine
// the mount (the message names the motion that is missing), 2 bad input.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "ekf_slam_ros/calibration/laser_from_bag.h"

namespace {

using ekf_slam::kPi;
namespace calibration = ekf_slam::calibration;

int usage(const char* why) {
  std::fprintf(stderr,
               "calibrate_laser_from_bag: %s\n"
               "usage: calibrate_laser_from_bag --bag FILE [--calibration FILE] [--write FILE]\n"
               "  --bag FILE          a recorded drive: scans, odometry (record.launch)\n"
               "  --calibration FILE  the mount in use (seeds the matches; its frames and z are\n"
               "                      kept when writing); default: the bag's base_link -> laser\n"
               "  --write FILE        write the estimate as a calibration file (atomically)\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string bag, calibration_file, write_file;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if ((arg == "--bag" || arg == "--calibration" || arg == "--write") && i + 1 < argc) {
      (arg == "--bag" ? bag : arg == "--calibration" ? calibration_file : write_file) = argv[++i];
    } else if (arg == "-h" || arg == "--help") {
      usage("the laser mount from a recorded drive");
      return 0;
    } else {
      return usage(("unknown or incomplete argument: " + arg).c_str());
    }
  }
  if (bag.empty()) return usage("--bag is required");

  calibration::LaserMount in_use;
  if (!calibration_file.empty()) {
    const std::string error = calibration::loadLaserMount(calibration_file, &in_use);
    if (!error.empty()) {
      std::fprintf(stderr, "calibrate_laser_from_bag: %s\n", error.c_str());
      return 2;
    }
  }
  calibration::BagCalibration run;
  const std::string error = calibration::calibrateFromBag(
      bag, calibration_file.empty() ? nullptr : &in_use, ekf_slam::ExtrinsicsOptions{}, &run);
  if (!error.empty()) {
    std::fprintf(stderr, "calibrate_laser_from_bag: %s\n", error.c_str());
    return 2;
  }
  const ekf_slam::ExtrinsicsResult& r = run.result;
  std::printf("scans: %d; scan pairs used: %d, dropped as outliers: %d, not matched: %d\n",
              run.scans, r.pairs_used, r.pairs_dropped, run.refused_matches);
  std::printf("motion used: %.1f m travelled, %.0f deg turned; residual rms %.4f m\n",
              r.total_travel, r.total_turn * 180.0 / kPi, r.residual_rms);
  if (!r.ok) {
    std::fprintf(stderr, "calibrate_laser_from_bag: no estimate: %s\n", r.message.c_str());
    return 1;
  }
  const double sx = std::sqrt(r.covariance(0, 0)), sy = std::sqrt(r.covariance(1, 1));
  const double syaw = std::sqrt(r.covariance(2, 2));
  const calibration::LaserMount& n = run.nominal;
  std::printf("laser mount (%s -> %s):\n", n.parent_frame.c_str(), n.child_frame.c_str());
  std::printf("  x   %8.4f m   +- %.4f   (was %.4f)\n", r.laser_pose.x, sx, n.x);
  std::printf("  y   %8.4f m   +- %.4f   (was %.4f)\n", r.laser_pose.y, sy, n.y);
  std::printf("  yaw %8.4f rad +- %.4f   (was %.4f) = %.2f +- %.2f deg\n", r.laser_pose.theta, syaw,
              n.yaw, r.laser_pose.theta * 180.0 / kPi, syaw * 180.0 / kPi);
  if (!write_file.empty()) {
    calibration::LaserMount estimate = n;
    estimate.x = r.laser_pose.x;
    estimate.y = r.laser_pose.y;
    estimate.yaw = r.laser_pose.theta;
    char heading[512];
    std::snprintf(heading, sizeof(heading),
                  "The laser mount on the robot (base_link -> laser), estimated by\n"
                  "calibrate_laser_from_bag from %s: 1-sigma x %.4f m, y %.4f m, yaw %.4f rad,\n"
                  "from %d scan pairs. z, roll and pitch are carried over.",
                  bag.c_str(), sx, sy, syaw, r.pairs_used);
    const std::string saved = calibration::saveLaserMount(write_file, estimate, heading);
    if (!saved.empty()) {
      std::fprintf(stderr, "calibrate_laser_from_bag: %s\n", saved.c_str());
      return 2;
    }
    std::printf("written to %s\n", write_file.c_str());
  }
  return 0;
}
