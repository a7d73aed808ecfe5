// The laser mount from simulated drives: scans ray-cast from the true
// (mis-mounted) laser in a room with cartons, odometry with wheel noise.
#include "ekf_slam_core/extrinsics/laser_extrinsics.h"

#include <gtest/gtest.h>

#include <random>

#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_core/sim/drive.h"

namespace ekf_slam {
namespace {

// The mount the robot really has: 5 cm further forward than the nominal
// 16 cm, 3 cm to the left, turned by 3 degrees.
const Pose2 kTrueLaser(0.21, 0.03, 3.0 * kPi / 180.0);
const Pose2 kNominalLaser(0.16, 0.0, 0.0);

sim::SimulatedDrive simulate(const std::vector<sim::DriveSegment>& segments, uint32_t seed) {
  sim::DriveOptions options;
  options.start = Pose2(sim::kMixedDriveStartX, sim::kMixedDriveStartY, sim::kMixedDriveStartYaw);
  options.laser = kTrueLaser;
  options.seed = seed;
  return sim::simulateDrive(sim::roomWithCartons(), segments, options);
}

TEST(LaserExtrinsics, RecoversAMisMountedLaserFromAMixedDrive) {
  const sim::SimulatedDrive drive = simulate(sim::mixedDrive(), 11);
  int refused = 0;
  const std::vector<MotionPair> pairs =
      motionPairs(drive.scans, drive.odometry, kNominalLaser, {}, &refused);
  ASSERT_GT(pairs.size(), 30u);
  const ExtrinsicsResult result = estimateLaserPose(pairs);
  ASSERT_TRUE(result.ok) << result.message;
  EXPECT_NEAR(result.laser_pose.x, kTrueLaser.x, 0.02);
  EXPECT_NEAR(result.laser_pose.y, kTrueLaser.y, 0.02);
  EXPECT_NEAR(result.laser_pose.theta, kTrueLaser.theta, 0.5 * kPi / 180.0);
  // The reported uncertainty covers the error (3 sigma).
  EXPECT_LT(std::abs(result.laser_pose.x - kTrueLaser.x),
            3.0 * std::sqrt(result.covariance(0, 0)) + 0.005);
  EXPECT_LT(std::abs(result.laser_pose.theta - kTrueLaser.theta),
            3.0 * std::sqrt(result.covariance(2, 2)) + 0.002);
  RecordProperty("pairs", std::to_string(result.pairs_used) + " used, " +
                              std::to_string(result.pairs_dropped) + " dropped, " +
                              std::to_string(refused) + " refused, rms " +
                              std::to_string(result.residual_rms) + ", sigma x " +
                              std::to_string(std::sqrt(result.covariance(0, 0))) + ", sigma yaw " +
                              std::to_string(std::sqrt(result.covariance(2, 2))));
  RecordProperty("x", std::to_string(result.laser_pose.x));
  RecordProperty("y", std::to_string(result.laser_pose.y));
  RecordProperty("yaw", std::to_string(result.laser_pose.theta));
}

TEST(LaserExtrinsics, HoldsAcrossNoiseSeeds) {
  for (uint32_t seed = 20; seed < 30; ++seed) {
    const sim::SimulatedDrive drive = simulate(sim::mixedDrive(), seed);
    const ExtrinsicsResult result =
        estimateLaserPose(motionPairs(drive.scans, drive.odometry, kNominalLaser));
    ASSERT_TRUE(result.ok) << "seed " << seed << ": " << result.message;
    EXPECT_NEAR(result.laser_pose.x, kTrueLaser.x, 0.02) << "seed " << seed;
    EXPECT_NEAR(result.laser_pose.y, kTrueLaser.y, 0.02) << "seed " << seed;
    EXPECT_NEAR(result.laser_pose.theta, kTrueLaser.theta, 0.5 * kPi / 180.0) << "seed " << seed;
  }
}

TEST(LaserExtrinsics, ExactPairsGiveTheExactMount) {
  // Pairs built from the model itself: the solver must return the mount.
  std::vector<MotionPair> pairs;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 40; ++k) {
    const Pose2 robot(0.3 * u(rng), 0.1 * u(rng), 0.4 * u(rng));
    pairs.push_back({robot, compose(compose(inverse(kTrueLaser), robot), kTrueLaser)});
  }
  const ExtrinsicsResult result = estimateLaserPose(pairs);
  ASSERT_TRUE(result.ok) << result.message;
  EXPECT_NEAR(result.laser_pose.x, kTrueLaser.x, 1e-6);
  EXPECT_NEAR(result.laser_pose.y, kTrueLaser.y, 1e-6);
  EXPECT_NEAR(result.laser_pose.theta, kTrueLaser.theta, 1e-6);
  EXPECT_LT(result.residual_rms, 1e-6);
}

TEST(LaserExtrinsics, WrongMatchesAreDropped) {
  std::vector<MotionPair> pairs;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 60; ++k) {
    const Pose2 robot(0.3 * u(rng), 0.1 * u(rng), 0.4 * u(rng));
    Pose2 laser = compose(compose(inverse(kTrueLaser), robot), kTrueLaser);
    if (k % 10 == 3) laser.x += 0.3;  // a match that slid along a corridor
    pairs.push_back({robot, laser});
  }
  const ExtrinsicsResult result = estimateLaserPose(pairs);
  ASSERT_TRUE(result.ok) << result.message;
  EXPECT_EQ(result.pairs_dropped, 6);
  EXPECT_NEAR(result.laser_pose.x, kTrueLaser.x, 1e-6);
  EXPECT_NEAR(result.laser_pose.theta, kTrueLaser.theta, 1e-6);
}

TEST(LaserExtrinsics, StraightDrivingIsRefusedNamingTurns) {
  const sim::SimulatedDrive drive = simulate({{0.3, 0.0, 12.0}, {-0.3, 0.0, 12.0}}, 12);
  const ExtrinsicsResult result =
      estimateLaserPose(motionPairs(drive.scans, drive.odometry, kNominalLaser));
  EXPECT_FALSE(result.ok);
  EXPECT_NE(result.message.find("no turns"), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("x and y are not observable"), std::string::npos);
}

TEST(LaserExtrinsics, TurningOnTheSpotIsRefusedNamingStraights) {
  const sim::SimulatedDrive drive =
      simulate({{0.0, 0.5, 10.0}, {0.0, -0.5, 10.0}, {0.0, 0.4, 10.0}}, 13);
  const ExtrinsicsResult result =
      estimateLaserPose(motionPairs(drive.scans, drive.odometry, kNominalLaser));
  EXPECT_FALSE(result.ok);
  EXPECT_NE(result.message.find("straight"), std::string::npos) << result.message;
}

TEST(LaserExtrinsics, TooShortADriveIsRefused) {
  const sim::SimulatedDrive drive = simulate({{0.3, 0.2, 2.0}}, 14);
  const ExtrinsicsResult result =
      estimateLaserPose(motionPairs(drive.scans, drive.odometry, kNominalLaser));
  EXPECT_FALSE(result.ok);
  EXPECT_NE(result.message.find("record a longer drive"), std::string::npos) << result.message;
}

}  // namespace
}  // namespace ekf_slam

namespace ekf_slam {
namespace {

// Mean, largest and final position error (m) of SLAM's causal poses over
// a drive, against the truth seen from the first pose (the map frame's
// origin).
struct SlamError {
  double mean = 0.0, largest = 0.0, final = 0.0;
  std::string text() const {
    return std::to_string(mean) + " " + std::to_string(largest) + " " + std::to_string(final);
  }
};

SlamError slamError(const sim::SimulatedDrive& drive, const Pose2& laser) {
  PipelineOptions options;
  options.filter.laser_pose = laser;
  SlamPipeline pipeline(options);
  SlamError out;
  for (size_t i = 0; i < drive.scans.size(); ++i) {
    const ScanResult result = pipeline.processScan(drive.scans[i], drive.odometry[i]);
    const Pose2 truth = between(drive.truth.front(), drive.truth[i]);
    out.final = (result.causal_pose.translation() - truth.translation()).norm();
    out.mean += out.final / drive.scans.size();
    out.largest = std::max(out.largest, out.final);
  }
  return out;
}

// The thesis's central lesson (§3.4.1): SLAM with the laser where it really
// is. The mount left at its nominal value against the estimated one.
TEST(LaserExtrinsics, TheEstimatedMountMakesSlamMoreAccurate) {
  sim::DriveOptions options;
  options.start = Pose2(sim::kMixedDriveStartX, sim::kMixedDriveStartY, sim::kMixedDriveStartYaw);
  options.laser = kTrueLaser;
  options.seed = 11;
  const sim::SimulatedDrive drive =
      sim::simulateDrive(sim::roomWithCartons(), sim::mixedDrive(), options);
  const ExtrinsicsResult estimate =
      estimateLaserPose(motionPairs(drive.scans, drive.odometry, kNominalLaser));
  ASSERT_TRUE(estimate.ok) << estimate.message;
  const SlamError nominal = slamError(drive, kNominalLaser);
  const SlamError calibrated = slamError(drive, estimate.laser_pose);
  const SlamError exact = slamError(drive, kTrueLaser);
  RecordProperty("nominal_mean_max_final", nominal.text());
  RecordProperty("calibrated_mean_max_final", calibrated.text());
  RecordProperty("true_mean_max_final", exact.text());
  EXPECT_LT(calibrated.mean, 0.5 * nominal.mean);
  EXPECT_LT(calibrated.final, 0.5 * nominal.final);
  EXPECT_LT(calibrated.mean, exact.mean + 0.01);
}

}  // namespace
}  // namespace ekf_slam
