// The odometry's noise fitted from a simulated square drive, at two wheel
// noise levels.
#include "ekf_slam_core/extrinsics/motion_noise_fit.h"

#include <gtest/gtest.h>

#include "ekf_slam_core/sim/drive.h"

namespace ekf_slam {
namespace {

const Pose2 kLaser(0.16, 0.0, 0.0);

// Twice around a 2 m square, turning on the spot at the corners.
std::vector<sim::DriveSegment> square() {
  std::vector<sim::DriveSegment> segments;
  for (int side = 0; side < 8; ++side) {
    segments.push_back({0.3, 0.0, 2.0 / 0.3});
    segments.push_back({0.0, 0.5, kPi / 2.0 / 0.5});
  }
  return segments;
}

MotionNoiseFit fitSquare(double wheel_noise, uint32_t seed) {
  sim::DriveOptions options;
  options.start = Pose2(-1.5, -1.5, 0.0);
  options.laser = kLaser;
  options.wheel_noise = wheel_noise;
  options.seed = seed;
  const sim::SimulatedDrive drive = sim::simulateDrive(sim::roomWithCartons(), square(), options);
  return fitMotionNoise(motionPairs(drive.scans, drive.odometry, kLaser), kLaser);
}

TEST(MotionNoiseFit, ScalesWithTheWheelNoise) {
  const MotionNoiseFit low = fitSquare(0.01, 31);
  const MotionNoiseFit high = fitSquare(0.03, 31);
  ASSERT_TRUE(low.ok) << low.message;
  ASSERT_TRUE(high.ok) << high.message;
  RecordProperty("low", std::to_string(low.noise.rot_per_rot) + " " +
                            std::to_string(low.noise.rot_per_trans) + " " +
                            std::to_string(low.noise.trans_per_trans) + " " +
                            std::to_string(low.noise.trans_per_rot));
  RecordProperty("high", std::to_string(high.noise.rot_per_rot) + " " +
                             std::to_string(high.noise.rot_per_trans) + " " +
                             std::to_string(high.noise.trans_per_trans) + " " +
                             std::to_string(high.noise.trans_per_rot));
  RecordProperty(
      "rms", std::to_string(low.rotation_rms) + " " + std::to_string(low.translation_rms) + " / " +
                 std::to_string(high.rotation_rms) + " " + std::to_string(high.translation_rms));
  // Three times the noise is nine times the variance (within the spread of
  // a two-lap estimate).
  EXPECT_GT(high.noise.trans_per_trans, 3.0 * low.noise.trans_per_trans);
  EXPECT_GT(high.noise.rot_per_rot, 3.0 * low.noise.rot_per_rot);
  EXPECT_GT(high.rotation_rms, 2.0 * low.rotation_rms);
  // What the simulator's model gives at the pairs' size (0.25 m or 0.25
  // rad, ~8 steps of 3 cm or ~5 of 0.05 rad, each off by 3 % at random):
  // trans_per_trans ≈ 8.3 (0.03 · 0.03)² / 0.25² = 1.08e-4 and
  // rot_per_rot ≈ 5 (0.03 · 0.05)² / 0.25² = 1.8e-4. The fit is within a
  // factor of two.
  EXPECT_GT(high.noise.trans_per_trans, 0.5 * 1.08e-4);
  EXPECT_LT(high.noise.trans_per_trans, 2.0 * 1.08e-4);
  EXPECT_GT(high.noise.rot_per_rot, 0.5 * 1.8e-4);
  EXPECT_LT(high.noise.rot_per_rot, 2.0 * 1.8e-4);
}

TEST(MotionNoiseFit, RefusesADriveWithoutTurns) {
  sim::DriveOptions options;
  options.start = Pose2(-1.5, -1.5, 0.0);
  options.laser = kLaser;
  const sim::SimulatedDrive drive = sim::simulateDrive(
      sim::roomWithCartons(), {{0.3, 0.0, 10.0}, {-0.3, 0.0, 10.0}, {0.3, 0.0, 10.0}}, options);
  const MotionNoiseFit fit =
      fitMotionNoise(motionPairs(drive.scans, drive.odometry, kLaser), kLaser);
  EXPECT_FALSE(fit.ok);
  EXPECT_NE(fit.message.find("hardly turns"), std::string::npos) << fit.message;
}

}  // namespace
}  // namespace ekf_slam
