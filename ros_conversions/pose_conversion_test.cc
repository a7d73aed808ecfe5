#include "ros_conversions/pose_conversion.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <utility>

#include "ekf_slam_core/geometry/angle.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {
namespace ros_conversions {
namespace {

TEST(PoseConversion, HeadingsRoundTripThroughQuaternions) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-kPi, kPi), coordinate(-50.0, 50.0);
  for (int i = 0; i < 1000; ++i) {
    const Pose2 pose(coordinate(rng), coordinate(rng), angle(rng));
    const geometry_msgs::Pose message = toPoseMessage(pose);
    EXPECT_NEAR(message.orientation.x * message.orientation.x +
                    message.orientation.y * message.orientation.y +
                    message.orientation.z * message.orientation.z +
                    message.orientation.w * message.orientation.w,
                1.0, 1e-15);
    const Pose2 back = fromPoseMessage(message);
    EXPECT_EQ(back.x, pose.x);
    EXPECT_EQ(back.y, pose.y);
    EXPECT_NEAR(wrapAngle(back.theta - pose.theta), 0.0, 1e-14);
  }
  // A quaternion of a rotation about z by 90° built independently.
  geometry_msgs::Quaternion q;
  q.z = std::sqrt(0.5);
  q.w = std::sqrt(0.5);
  EXPECT_NEAR(yawOf(q), kPi / 2.0, 1e-15);
}

geometry_msgs::Transform mountTransform(double roll, double pitch, double yaw) {
  const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  geometry_msgs::Transform t;
  t.translation.x = 0.16;
  t.translation.y = -0.02;
  t.translation.z = 0.3;
  t.rotation.x = q.x();
  t.rotation.y = q.y();
  t.rotation.z = q.z();
  t.rotation.w = q.w();
  return t;
}

// The heading, seen from above, of the beam at bearing `alpha` in the
// laser frame, through the full 3-D rotation.
double beamHeading(const geometry_msgs::Transform& t, double alpha) {
  const Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
  const Eigen::Vector3d beam = q * Eigen::Vector3d(std::cos(alpha), std::sin(alpha), 0.0);
  return std::atan2(beam.y(), beam.x());
}

// A level laser, upright or upside down, at any heading: its beams point
// where the planar pose (and, inverted, the mirrored bearing) says.
TEST(PoseConversion, ALaserMountIsUprightOrInvertedWithTheHeadingOfItsBeams) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (int i = 0; i < 200; ++i) {
    const bool upside_down = i % 2 == 1;
    // Upside down by roll π or by pitch π (the same mount, other yaw).
    const double roll = upside_down && i % 4 == 1 ? kPi : 0.0;
    const double pitch = upside_down && i % 4 == 3 ? kPi : 0.0;
    const geometry_msgs::Transform t = mountTransform(roll, pitch, angle(rng));
    const LaserMount mount = laserMountOf(t);
    EXPECT_EQ(mount.inverted, upside_down);
    EXPECT_NEAR(mount.tilt, 0.0, 1e-7);
    EXPECT_EQ(mount.pose.x, 0.16);
    EXPECT_EQ(mount.pose.y, -0.02);
    for (double alpha : {-1.5, -0.4, 0.0, 0.9, 1.5}) {
      const double seen = upside_down ? -alpha : alpha;
      EXPECT_NEAR(wrapAngle(beamHeading(t, alpha) - (mount.pose.theta + seen)), 0.0, 1e-9)
          << "roll " << roll << " pitch " << pitch << " bearing " << alpha;
    }
  }
}

TEST(PoseConversion, ATiltedMountGivesItsTiltRollAndPitch) {
  const LaserMount pitched = laserMountOf(mountTransform(0.0, degToRad(10.0), 0.3));
  EXPECT_FALSE(pitched.inverted);
  EXPECT_NEAR(pitched.tilt, degToRad(10.0), 1e-12);
  EXPECT_NEAR(pitched.pitch, degToRad(10.0), 1e-12);
  EXPECT_NEAR(pitched.roll, 0.0, 1e-12);
  EXPECT_NEAR(pitched.pose.theta, 0.3, 1e-12);
  const LaserMount rolled = laserMountOf(mountTransform(degToRad(-4.0), 0.0, 0.0));
  EXPECT_NEAR(rolled.tilt, degToRad(4.0), 1e-12);
  EXPECT_NEAR(rolled.roll, degToRad(-4.0), 1e-12);
  // Upside down and 5° off level.
  const LaserMount inverted = laserMountOf(mountTransform(kPi - degToRad(5.0), 0.0, 0.0));
  EXPECT_TRUE(inverted.inverted);
  EXPECT_NEAR(inverted.tilt, degToRad(5.0), 1e-12);
  // A level mount, upright or not, has nothing to level, exactly.
  for (double roll : {0.0, kPi}) {
    const LaserMount level = laserMountOf(mountTransform(roll, 0.0, 0.4));
    EXPECT_EQ(level.scan_roll, 0.0);
    EXPECT_EQ(level.scan_pitch, 0.0);
  }
}

// Upside down and tilted: the mirrored scan's beam at −α, bent by the scan's
// roll and pitch, points where the inverted laser's beam at α does.
TEST(PoseConversion, AnInvertedTiltedMountLevelsItsMirroredScan) {
  for (const auto& [roll, pitch] :
       {std::pair<double, double>{kPi - 0.05, 0.03}, {-kPi + 0.04, -0.02}}) {
    const geometry_msgs::Transform t = mountTransform(roll, pitch, 0.8);
    const LaserMount mount = laserMountOf(t);
    ASSERT_TRUE(mount.inverted);
    const Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
    for (double alpha : {-1.2, 0.0, 0.5, 1.4}) {
      const TiltedBeam beam = tiltedBeam(-alpha, mount.scan_roll, mount.scan_pitch);
      const Eigen::Vector3d d = q * Eigen::Vector3d(std::cos(alpha), std::sin(alpha), 0.0);
      EXPECT_NEAR(wrapAngle(beam.level_bearing + mount.pose.theta - beamHeading(t, alpha)), 0.0,
                  1e-12);
      EXPECT_NEAR(beam.horizontal, std::hypot(d.x(), d.y()), 1e-12);
    }
  }
}

// The calibration file's roll, pitch and yaw become the transform's
// rotation, and laserMountOf reads them back; the core's TiltedBeam, which
// levels the scans, bends each beam as that rotation does.
TEST(PoseConversion, RollPitchAndYawMakeTheMountsRotationAndTheBeamsItTilts) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> yaw(-kPi, kPi), tilt(-0.3, 0.3);
  for (int i = 0; i < 100; ++i) {
    const double r = tilt(rng), p = tilt(rng), y = yaw(rng);
    geometry_msgs::Transform t = mountTransform(r, p, y);
    const geometry_msgs::Quaternion q = quaternionOfRollPitchYaw(r, p, y);
    EXPECT_NEAR(q.x, t.rotation.x, 1e-15);
    EXPECT_NEAR(q.y, t.rotation.y, 1e-15);
    EXPECT_NEAR(q.z, t.rotation.z, 1e-15);
    EXPECT_NEAR(q.w, t.rotation.w, 1e-15);
    const LaserMount mount = laserMountOf(t);
    EXPECT_NEAR(mount.roll, r, 1e-12);
    EXPECT_NEAR(mount.pitch, p, 1e-12);
    EXPECT_NEAR(mount.pose.theta, y, 1e-12);
    const Eigen::Quaterniond rotation(q.w, q.x, q.y, q.z);
    for (double alpha : {-1.5, -0.4, 0.0, 0.9, 1.5}) {
      const TiltedBeam beam = tiltedBeam(alpha, mount.roll, mount.pitch);
      const Eigen::Vector3d d = rotation * Eigen::Vector3d(std::cos(alpha), std::sin(alpha), 0.0);
      EXPECT_NEAR(wrapAngle(beam.level_bearing + mount.pose.theta - beamHeading(t, alpha)), 0.0,
                  1e-12);
      EXPECT_NEAR(beam.horizontal, std::hypot(d.x(), d.y()), 1e-12);
      EXPECT_NEAR(beam.rise, d.z(), 1e-12);
    }
  }
  // Level: the quaternion of the yaw alone, bit for bit.
  const geometry_msgs::Quaternion level = quaternionOfRollPitchYaw(0.0, 0.0, 0.7);
  const geometry_msgs::Quaternion yaw_only = quaternionOfYaw(0.7);
  EXPECT_EQ(level.x, 0.0);
  EXPECT_EQ(level.y, 0.0);
  EXPECT_EQ(level.z, yaw_only.z);
  EXPECT_EQ(level.w, yaw_only.w);
}

TEST(PoseConversion, PlanarCovarianceIsTheXYYawBlock) {
  boost::array<double, 36> ros_covariance{};
  for (int i = 0; i < 36; ++i) ros_covariance[i] = 100.0 + i;
  const Matrix3 planar = planarCovariance(ros_covariance);
  EXPECT_EQ(planar(0, 0), 100.0);  // x x
  EXPECT_EQ(planar(0, 1), 101.0);  // x y
  EXPECT_EQ(planar(0, 2), 105.0);  // x yaw
  EXPECT_EQ(planar(2, 0), 130.0);  // yaw x
  EXPECT_EQ(planar(2, 2), 135.0);  // yaw yaw
  boost::array<double, 36> written{};
  setPlanarCovariance(planar, &written);
  for (int i : {0, 1, 5, 6, 7, 11, 30, 31, 35}) EXPECT_EQ(written[i], ros_covariance[i]) << i;
  for (int i : {2, 3, 4, 14, 21, 28, 34}) EXPECT_EQ(written[i], 0.0) << i;
}

TEST(PoseConversion, APolylineBecomesAPathOfItsPointsWithTheHeader) {
  std_msgs::Header header;
  header.frame_id = "map";
  header.stamp = ros::Time(12, 500);
  const nav_msgs::Path path = toPathMessage({Vector2(1.0, 2.0), Vector2(-3.0, 0.5)}, header);
  EXPECT_EQ(path.header.frame_id, "map");
  ASSERT_EQ(path.poses.size(), 2u);
  EXPECT_EQ(path.poses[1].header.stamp, ros::Time(12, 500));
  EXPECT_EQ(path.poses[1].header.frame_id, "map");
  EXPECT_DOUBLE_EQ(path.poses[0].pose.position.x, 1.0);
  EXPECT_DOUBLE_EQ(path.poses[1].pose.position.y, 0.5);
  EXPECT_DOUBLE_EQ(path.poses[1].pose.orientation.w, 1.0);
  EXPECT_TRUE(toPathMessage({}, header).poses.empty());
}

}  // namespace
}  // namespace ros_conversions
}  // namespace ekf_slam
