// fit_motion_noise: the odometry's noise model (filter.motion_noise, the
// thesis's control noise) fitted from a recorded drive, against the scan
// matcher's motion through the laser mount. docs/bringup.md, "Motion noise".
//
//   fit_motion_noise --bag square.bag [--calibration config/calibration.yaml]
//
// Drive a square of about 2 m a side, turning on the spot at the corners,
// two or three times round, in a room with structure all around, and
// record it (record.launch). The program prints the fitted coefficients as
// the filter.motion_noise block of the SLAM configuration. Exit status 0
// fitted, 1 the drive does not separate turning from driving, 2 bad input.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "ekf_slam_core/extrinsics/motion_noise_fit.h"
#include "ekf_slam_ros/calibration/laser_mount.h"
#include "ekf_slam_ros/offline/log_input.h"

int main(int argc, char** argv) {
  std::string bag, calibration_file;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if ((arg == "--bag" || arg == "--calibration") && i + 1 < argc) {
      (arg == "--bag" ? bag : calibration_file) = argv[++i];
    } else {
      std::fprintf(
          stderr,
          "usage: fit_motion_noise --bag FILE [--calibration FILE]\n"
          "  --bag FILE          a recorded drive (a square, turning at the corners)\n"
          "  --calibration FILE  the laser mount; default: the bag's base_link -> laser\n");
      return arg == "-h" || arg == "--help" ? 0 : 2;
    }
  }
  if (bag.empty()) {
    std::fprintf(stderr, "fit_motion_noise: --bag is required\n");
    return 2;
  }
  ekf_slam::LogData log;
  std::string error = ekf_slam::readBag(bag, ekf_slam::InputOptions{}, &log);
  if (!error.empty()) {
    std::fprintf(stderr, "fit_motion_noise: %s\n", error.c_str());
    return 2;
  }
  ekf_slam::Pose2 laser = log.laser_pose_found ? log.laser_pose : ekf_slam::Pose2();
  if (!calibration_file.empty()) {
    ekf_slam::calibration::LaserMount mount;
    error = ekf_slam::calibration::loadLaserMount(calibration_file, &mount);
    if (!error.empty()) {
      std::fprintf(stderr, "fit_motion_noise: %s\n", error.c_str());
      return 2;
    }
    laser = mount.pose();
  }
  std::vector<ekf_slam::Scan> scans;
  std::vector<ekf_slam::Pose2> odometry;
  for (const ekf_slam::LoggedScan& s : log.scans) {
    scans.push_back(s.scan);
    odometry.push_back(s.odometry);
  }
  int refused = 0;
  const std::vector<ekf_slam::MotionPair> pairs =
      ekf_slam::motionPairs(scans, odometry, laser, ekf_slam::ExtrinsicsOptions{}, &refused);
  const ekf_slam::MotionNoiseFit fit = ekf_slam::fitMotionNoise(pairs, laser);
  std::printf("# %zu scans, %zu scan pairs (%d not matched); laser mount %.3f %.3f %.4f\n",
              scans.size(), pairs.size(), refused, laser.x, laser.y, laser.theta);
  std::printf("# odometry - scan matcher per pair: rotation rms %.5f rad, translation rms %.5f m\n",
              fit.rotation_rms, fit.translation_rms);
  if (!fit.ok) {
    std::fprintf(stderr, "fit_motion_noise: no fit: %s\n", fit.message.c_str());
    return 1;
  }
  std::printf("# the scan matcher's own error (the fit's constants): %.5f rad, %.5f m\n",
              fit.matcher_rotation_sigma, fit.matcher_translation_sigma);
  std::printf("filter:\n  motion_noise:\n");
  std::printf("    rot_per_rot: %.3g\n    rot_per_trans: %.3g\n", fit.noise.rot_per_rot,
              fit.noise.rot_per_trans);
  std::printf("    trans_per_trans: %.3g\n    trans_per_rot: %.3g\n", fit.noise.trans_per_trans,
              fit.noise.trans_per_rot);
  return 0;
}
