#include "ros_conversions/pose_conversion.h"

#include <gtest/gtest.h>

#include <random>

#include "ekf_slam_core/geometry/angle.h"

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

}  // namespace
}  // namespace ros_conversions
}  // namespace ekf_slam
