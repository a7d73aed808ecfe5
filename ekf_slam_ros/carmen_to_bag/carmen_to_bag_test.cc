// Round trip CARMEN text → bag → read back, against the CARMEN reader itself.
#include "ekf_slam_ros/carmen_to_bag/carmen_to_bag.h"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "ekf_slam_ros/offline/log_input.h"

namespace ekf_slam {
namespace {

class CarmenFiles : public ::testing::Test {
 protected:
  void TearDown() override {
    ::unlink(log_.c_str());
    ::unlink(bag_.c_str());
    ::unlink((bag_ + ".partial").c_str());
  }
  // A FLASER line of 180 beams, laser 0.1 m ahead of the robot.
  static std::string flaser(int i) {
    std::ostringstream line;
    line.setf(std::ios::fixed);
    line.precision(6);
    line << "FLASER 180";
    for (int b = 0; b < 180; ++b) {
      // Walls at a few metres, a "no return" every 17th beam.
      line << ' ' << (b % 17 == 0 ? 81.83 : 2.0 + 0.01 * b + 0.003 * i);
    }
    const double x = 0.05 * i, y = 0.01 * i, theta = -3.1 + 0.3 * i;  // heading crosses ±π
    line << ' ' << x + 0.1 * std::cos(theta) << ' ' << y + 0.1 * std::sin(theta) << ' ' << theta
         << ' ' << x << ' ' << y << ' ' << theta << ' ' << 976052896.784 + 0.2 * i
         << " nuthaus 0.5";
    return line.str();
  }
  std::string log_ = "/tmp/carmen_to_bag_test_" + std::to_string(::getpid()) + ".log";
  std::string bag_ = "/tmp/carmen_to_bag_test_" + std::to_string(::getpid()) + ".bag";
};

TEST_F(CarmenFiles, RoundTripGivesBackTheSameScansOdometryAndMount) {
  {
    std::ofstream out(log_);
    out << "# a comment\nPARAM robot_length 0.5\n";
    for (int i = 0; i < 25; ++i) {
      out << flaser(i) << "\n";
      out << "ODOM 0 0 0 0 0 0 " << 976052896.784 + 0.2 * i + 0.1 << " nuthaus 0.5\n";
    }
    // A stamp that goes backwards must keep its place in file order.
    std::string late = flaser(24);
    const std::string stamp = std::to_string(976052896.784 + 0.2 * 24).substr(0, 13);
    ASSERT_NE(late.find(stamp), std::string::npos) << late;
    late.replace(late.find(stamp), stamp.size(), "976052900.000");
    out << late << "\n";
  }
  LogData from_log;
  ASSERT_EQ(readCarmen(log_, &from_log), "");
  CarmenToBagSummary summary;
  ASSERT_EQ(convertCarmenToBag(log_, bag_, &summary), "");
  EXPECT_EQ(summary.scans, 26);
  EXPECT_EQ(::access((bag_ + ".partial").c_str(), F_OK), -1) << "the temporary file is gone";

  LogData from_bag;
  ASSERT_EQ(readBag(bag_, InputOptions(), &from_bag), "");
  ASSERT_EQ(from_bag.scans.size(), from_log.scans.size());
  EXPECT_TRUE(from_bag.laser_pose_found);
  EXPECT_NEAR(from_bag.laser_pose.x, from_log.laser_pose.x, 1e-9);
  EXPECT_NEAR(from_bag.laser_pose.y, from_log.laser_pose.y, 1e-9);
  EXPECT_NEAR(from_bag.laser_pose.theta, from_log.laser_pose.theta, 1e-9);
  EXPECT_EQ(from_bag.scans_out_of_time_order, 1);
  for (size_t i = 0; i < from_log.scans.size(); ++i) {
    const LoggedScan& a = from_log.scans[i];
    const LoggedScan& b = from_bag.scans[i];
    // LaserScan stores float32 and ros::Time nanoseconds: equal to that precision.
    EXPECT_NEAR(b.scan.stamp, a.scan.stamp, 1e-6) << "scan " << i;
    ASSERT_EQ(b.scan.ranges.size(), a.scan.ranges.size());
    for (size_t k = 0; k < a.scan.ranges.size(); ++k) {
      EXPECT_NEAR(b.scan.ranges[k], a.scan.ranges[k], 1e-5) << "scan " << i << " beam " << k;
      EXPECT_EQ(b.scan.isValid(k), a.scan.isValid(k));
    }
    EXPECT_NEAR(b.scan.angle_min, a.scan.angle_min, 1e-6);
    EXPECT_NEAR(b.scan.angle_increment, a.scan.angle_increment, 1e-6);
    // The odometry at each scan's stamp is the pose written on its line
    // (the backwards stamp lies between two samples: not compared).
    if (i + 1 == from_log.scans.size()) continue;
    EXPECT_NEAR(b.odometry.x, a.odometry.x, 1e-9) << "scan " << i;
    EXPECT_NEAR(b.odometry.y, a.odometry.y, 1e-9) << "scan " << i;
    EXPECT_NEAR(wrapAngle(b.odometry.theta - a.odometry.theta), 0.0, 1e-9) << "scan " << i;
  }
}

// rosbag play republishes a connection latched when its header says so:
// the mount, written once, must reach subscribers that start later.
TEST_F(CarmenFiles, TheMountIsWrittenLatchedAndTheStreamsAreNot) {
  {
    std::ofstream out(log_);
    for (int i = 0; i < 3; ++i) out << flaser(i) << "\n";
  }
  ASSERT_EQ(convertCarmenToBag(log_, bag_), "");
  rosbag::Bag bag(bag_, rosbag::bagmode::Read);
  rosbag::View view(bag);
  int static_connections = 0;
  for (const rosbag::ConnectionInfo* connection : view.getConnections()) {
    ASSERT_TRUE(connection->header) << connection->topic;
    const auto latching = connection->header->find("latching");
    const bool latched = latching != connection->header->end() && latching->second == "1";
    if (connection->topic == "/tf_static") {
      ++static_connections;
      EXPECT_TRUE(latched);
      EXPECT_EQ(connection->datatype, "tf2_msgs/TFMessage");
      EXPECT_EQ(connection->header->at("type"), "tf2_msgs/TFMessage");
      EXPECT_FALSE(connection->header->at("callerid").empty());
      EXPECT_FALSE(connection->header->at("message_definition").empty());
    } else {
      EXPECT_FALSE(latched) << connection->topic;
    }
  }
  EXPECT_EQ(static_connections, 1);
  rosbag::View statics(bag, rosbag::TopicQuery("/tf_static"));
  EXPECT_EQ(statics.size(), 1u);
}

TEST_F(CarmenFiles, AWrongFieldCountIsNamedAndNoBagIsLeft) {
  {
    std::ofstream out(log_);
    out << flaser(0) << "\n" << flaser(1) << "\n";
    out << "FLASER 180 1.0 2.0 3.0 976052896.784 nuthaus 0.5\n";  // 3 ranges for 180 announced
  }
  const std::string error = convertCarmenToBag(log_, bag_);
  EXPECT_NE(error.find(log_ + ":3:"), std::string::npos) << error;
  EXPECT_NE(error.find("FLASER"), std::string::npos) << error;
  EXPECT_EQ(::access(bag_.c_str(), F_OK), -1) << "no bag presented as complete";
  EXPECT_EQ(::access((bag_ + ".partial").c_str(), F_OK), -1);
}

TEST_F(CarmenFiles, ALogWithoutScansIsRefused) {
  std::ofstream(log_) << "ODOM 1 2 0.3 0.1 0 0 1234.5 host 1\n";
  EXPECT_NE(convertCarmenToBag(log_, bag_).find("no laser scans"), std::string::npos);
  EXPECT_EQ(::access(bag_.c_str(), F_OK), -1);
}

}  // namespace
}  // namespace ekf_slam
