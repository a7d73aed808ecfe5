// The bag tool on a real rosbag file of a simulated drive with a
// mis-mounted laser: the estimate, the written calibration file, and the
// refusals (straight driving, a bag without scans).
#include "ekf_slam_ros/calibration/laser_from_bag.h"

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>

#include <cmath>
#include <string>

#include "ekf_slam_core/sim/drive.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace calibration {
namespace {

// 5 cm further forward than the nominal 16 cm, 3 cm left, 3 degrees.
const Pose2 kTrueLaser(0.21, 0.03, 3.0 * kPi / 180.0);

// The drive as record.launch would store it: /scan, /odom, and the nominal
// mount (0.16, 0, 0) on /tf_static.
void writeDrive(const std::string& path, const sim::SimulatedDrive& drive) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (size_t i = 0; i < drive.scans.size(); ++i) {
    const Scan& s = drive.scans[i];
    const ros::Time t(1000.0 + s.stamp);
    sensor_msgs::LaserScan scan;
    scan.header.stamp = t;
    scan.header.seq = static_cast<uint32_t>(i);
    scan.header.frame_id = "laser";
    scan.angle_min = s.angle_min;
    scan.angle_increment = s.angle_increment;
    scan.angle_max = s.angle_min + s.angle_increment * (s.size() - 1);
    scan.range_min = 0.0;
    scan.range_max = 8.18;
    for (double r : s.ranges) scan.ranges.push_back(std::isfinite(r) ? r : 8.191);
    bag.write("/scan", t, scan);
    nav_msgs::Odometry odom;
    odom.header.stamp = t;
    odom.header.frame_id = "odom";
    odom.child_frame_id = "base_link";
    odom.pose.pose.position.x = drive.odometry[i].x;
    odom.pose.pose.position.y = drive.odometry[i].y;
    odom.pose.pose.orientation = ros_conversions::quaternionOfYaw(drive.odometry[i].theta);
    bag.write("/odom", t, odom);
  }
  tf2_msgs::TFMessage statics;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = ros::Time(1000.0);
  mount.header.frame_id = "base_link";
  mount.child_frame_id = "laser";
  mount.transform.translation.x = 0.16;
  mount.transform.rotation.w = 1.0;
  statics.transforms.push_back(mount);
  bag.write("/tf_static", ros::Time(1000.0), statics);
  bag.close();
}

sim::SimulatedDrive simulate(const std::vector<sim::DriveSegment>& segments) {
  sim::DriveOptions options;
  options.start = Pose2(sim::kMixedDriveStartX, sim::kMixedDriveStartY, sim::kMixedDriveStartYaw);
  options.laser = kTrueLaser;
  options.seed = 4;
  return sim::simulateDrive(sim::roomWithCartons(), segments, options);
}

class LaserFromBag : public ::testing::Test {
 protected:
  void TearDown() override {
    ::unlink(bag_.c_str());
    ::unlink(yaml_.c_str());
  }
  const std::string stem_ = "/tmp/laser_from_bag_test_" + std::to_string(::getpid());
  const std::string bag_ = stem_ + ".bag";
  const std::string yaml_ = stem_ + ".yaml";
};

TEST_F(LaserFromBag, RecoversTheMountAndWritesIt) {
  ros::Time::init();
  writeDrive(bag_, simulate(sim::mixedDrive()));
  BagCalibration run;
  ASSERT_EQ(calibrateFromBag(bag_, nullptr, ExtrinsicsOptions{}, &run), "");
  EXPECT_NEAR(run.nominal.x, 0.16, 1e-9);  // the bag's own mount seeds the matches
  ASSERT_TRUE(run.result.ok) << run.result.message;
  EXPECT_NEAR(run.result.laser_pose.x, kTrueLaser.x, 0.02);
  EXPECT_NEAR(run.result.laser_pose.y, kTrueLaser.y, 0.02);
  EXPECT_NEAR(run.result.laser_pose.theta, kTrueLaser.theta, 0.5 * kPi / 180.0);

  LaserMount estimate = run.nominal;
  estimate.x = run.result.laser_pose.x;
  estimate.y = run.result.laser_pose.y;
  estimate.yaw = run.result.laser_pose.theta;
  ASSERT_EQ(saveLaserMount(yaml_, estimate, "estimated\nby a test"), "");
  LaserMount read;
  ASSERT_EQ(loadLaserMount(yaml_, &read), "");
  EXPECT_NEAR(read.x, estimate.x, 1e-4);
  EXPECT_NEAR(read.y, estimate.y, 1e-4);
  EXPECT_NEAR(read.yaw, estimate.yaw, 1e-5);
  EXPECT_EQ(read.child_frame, "laser");
}

TEST_F(LaserFromBag, StraightDrivingIsRefusedWithWhatIsMissing) {
  ros::Time::init();
  writeDrive(bag_, simulate({{0.3, 0.0, 12.0}, {-0.3, 0.0, 12.0}}));
  BagCalibration run;
  ASSERT_EQ(calibrateFromBag(bag_, nullptr, ExtrinsicsOptions{}, &run), "");
  EXPECT_FALSE(run.result.ok);
  EXPECT_NE(run.result.message.find("no turns"), std::string::npos) << run.result.message;
}

TEST_F(LaserFromBag, AMissingBagIsAnInputError) {
  BagCalibration run;
  const std::string error =
      calibrateFromBag("/nonexistent/drive.bag", nullptr, ExtrinsicsOptions{}, &run);
  EXPECT_NE(error.find("/nonexistent/drive.bag"), std::string::npos) << error;
}

}  // namespace
}  // namespace calibration
}  // namespace ekf_slam
