// The thesis's calibration procedure (§3.4.1) on simulated scans of a box
// corner, with the laser mounted 5 cm, 3 cm and 3° away from the nominal.
#include "ekf_slam_core/extrinsics/thesis_procedure.h"

#include <gtest/gtest.h>

#include <random>

#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

const Pose2 kTrueLaser(0.21, 0.03, 3.0 * kPi / 180.0);
const Pose2 kNominalLaser(0.16, 0.0, 0.0);

// A 0.6 m box turned by 45°, its nearest corner 1.78 m ahead of the start,
// in a 10 m × 8 m room.
sim::PolygonWorld calibrationRoom() {
  sim::PolygonWorld world;
  world.addPolygon({{-3, -4}, {7, -4}, {7, 4}, {-3, 4}});
  world.addBox({2.2, 0.0}, 0.6, 0.6, kPi / 4.0);
  return world;
}

std::vector<Scan> scansFrom(const Pose2& robot, int count, std::mt19937* rng) {
  const sim::PolygonWorld world = calibrationRoom();
  sim::SweepGeometry sweep;  // 181 beams, 8 m
  std::vector<Scan> scans;
  for (int i = 0; i < count; ++i) {
    scans.push_back(sim::simulateScan(world, compose(robot, kTrueLaser), sweep, 0.01, rng));
  }
  return scans;
}

// Where the corner should appear in the laser frame with the mount believed.
Vector2 expected(const Pose2& robot, const Pose2& laser) {
  return transformTo(compose(robot, laser), Vector2(2.2 - 0.3 * std::sqrt(2.0), 0.0));
}

TEST(ThesisCalibration, PitchFromTwoGrazedObjects) {
  EXPECT_NEAR(beamTilt(0.30, 0.35, 1.0), std::atan(0.05), 1e-12);
  EXPECT_NEAR(beamTilt(0.30, 0.30, 2.0), 0.0, 1e-12);
  EXPECT_LT(beamTilt(0.35, 0.30, 1.0), 0.0);  // the beam falls away from the scanner
}

TEST(ThesisCalibration, RecoversYawAndTranslationOfAMisMountedLaser) {
  std::mt19937 rng(21);
  const int kScans = 50;
  const Pose2 start(0.0, 0.0, 0.0), moved(0.8, 0.0, 0.0);
  const FeatureSighting a =
      sightFeature(scansFrom(start, kScans, &rng), expected(start, kNominalLaser), 0.3);
  const FeatureSighting b =
      sightFeature(scansFrom(moved, kScans, &rng), expected(moved, kNominalLaser), 0.3);
  ASSERT_TRUE(a.ok) << a.message;
  ASSERT_TRUE(b.ok) << b.message;
  const YawCalibration yaw = yawFromStraightMove(a, b, 0.8);
  ASSERT_TRUE(yaw.ok) << yaw.message;
  EXPECT_NEAR(yaw.yaw, kTrueLaser.theta, 0.3 * kPi / 180.0);
  EXPECT_NEAR(yaw.distance, 0.8, 0.01);
  EXPECT_LT(std::abs(yaw.yaw - kTrueLaser.theta), 4.0 * yaw.sigma + 1e-4);

  for (double turn : {0.6, -0.6}) {
    const Pose2 turned(0.8, 0.0, turn);
    const Pose2 believed(0.16, 0.0, yaw.yaw);
    const FeatureSighting c =
        sightFeature(scansFrom(turned, kScans, &rng), expected(turned, believed), 0.3);
    ASSERT_TRUE(c.ok) << c.message;
    const TranslationCalibration t = translationFromTurn(b, c, turn, yaw.yaw, yaw.sigma);
    ASSERT_TRUE(t.ok) << t.message;
    EXPECT_NEAR(t.translation.x(), kTrueLaser.x, 0.01) << "turn " << turn;
    EXPECT_NEAR(t.translation.y(), kTrueLaser.y, 0.01) << "turn " << turn;
    EXPECT_LT(std::sqrt(t.covariance(0, 0)), 0.01);
    RecordProperty(turn > 0 ? "left" : "right",
                   std::to_string(t.translation.x()) + " " + std::to_string(t.translation.y()));
  }
  RecordProperty("yaw_deg", std::to_string(yaw.yaw * 180.0 / kPi) + " +- " +
                                std::to_string(yaw.sigma * 180.0 / kPi));
}

TEST(ThesisCalibration, ExactSightingsGiveTheExactMount) {
  // The model itself: a feature at p in the robot frame.
  const Vector2 p(1.5, 0.4);
  auto sighting = [](const Vector2& z) {
    FeatureSighting s;
    s.ok = true;
    s.mean = z;
    s.covariance = 1e-8 * Matrix2::Identity();
    return s;
  };
  const Vector2 z = transformTo(kTrueLaser, p);
  const Vector2 z_moved = transformTo(kTrueLaser, p - Vector2(0.5, 0.0));
  const YawCalibration yaw = yawFromStraightMove(sighting(z), sighting(z_moved), 0.5);
  ASSERT_TRUE(yaw.ok);
  EXPECT_NEAR(yaw.yaw, kTrueLaser.theta, 1e-12);
  const double turn = 0.7;
  const Vector2 z_turned = transformTo(kTrueLaser, transformTo(Pose2(0, 0, turn), p));
  const TranslationCalibration t =
      translationFromTurn(sighting(z), sighting(z_turned), turn, yaw.yaw, 0.0);
  ASSERT_TRUE(t.ok);
  EXPECT_NEAR(t.translation.x(), kTrueLaser.x, 1e-9);
  EXPECT_NEAR(t.translation.y(), kTrueLaser.y, 1e-9);
  EXPECT_NEAR((t.feature - p).norm(), 0.0, 1e-9);
}

TEST(ThesisCalibration, RefusesWhatCannotGiveAnAnswer) {
  FeatureSighting s;
  s.ok = true;
  s.mean = Vector2(1.5, 0.0);
  FeatureSighting moved = s;
  moved.mean = Vector2(1.0, 0.0);
  // The laser saw 0.5 m, the odometry claims 0.8 m.
  const YawCalibration yaw = yawFromStraightMove(s, moved, 0.8);
  EXPECT_FALSE(yaw.ok);
  EXPECT_NE(yaw.message.find("the odometry says"), std::string::npos) << yaw.message;
  // A turn of 5 degrees cannot give the translation.
  const TranslationCalibration t = translationFromTurn(s, moved, 0.087, 0.0, 0.0);
  EXPECT_FALSE(t.ok);
  EXPECT_NE(t.message.find("too small"), std::string::npos);
  // No corner where one is expected.
  std::mt19937 rng(1);
  const FeatureSighting none = sightFeature(scansFrom(Pose2(), 5, &rng), Vector2(1.0, 2.5), 0.2);
  EXPECT_FALSE(none.ok);
  EXPECT_NE(none.message.find("place a box corner"), std::string::npos) << none.message;
}

}  // namespace
}  // namespace ekf_slam
