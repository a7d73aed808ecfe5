#include "ekf_slam_core/io/carmen_log.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

namespace ekf_slam {
namespace {

TEST(CarmenLog, ParsesFlaserOdomAndRobotlaser) {
  std::string kind;
  CarmenLaser laser;
  CarmenOdometry odom;
  ASSERT_EQ(parseCarmenLine("FLASER 3 1.0 2.0 81.83 1.1 2.0 0.5 1.0 2.0 0.5 976052896.784 host 0.1",
                            80.0, &kind, &laser, &odom),
            "");
  EXPECT_EQ(kind, "FLASER");
  ASSERT_EQ(laser.scan.size(), 3);
  EXPECT_DOUBLE_EQ(laser.scan.angle_min, -kPi / 2);
  EXPECT_DOUBLE_EQ(laser.scan.angle_increment, kPi / 2);
  EXPECT_FALSE(laser.scan.isValid(2)) << "81.83 m is 'no return' above range_max";
  EXPECT_DOUBLE_EQ(laser.scan.stamp, 976052896.784);
  EXPECT_NEAR(laser.robot_odometry.theta, 0.5, 1e-12);
  // FLASER's laser pose is in the odometry frame: 0.1 m along world x from a
  // robot heading 0.5 rad is (0.1 cos 0.5, −0.1 sin 0.5) in the robot frame.
  EXPECT_NEAR(laser.laser_in_robot.x, 0.1 * std::cos(0.5), 1e-12);
  EXPECT_NEAR(laser.laser_in_robot.y, -0.1 * std::sin(0.5), 1e-12);
  EXPECT_NEAR(laser.laser_in_robot.theta, 0.0, 1e-12);

  ASSERT_EQ(parseCarmenLine("ODOM 1 2 0.3 0.1 0 0 1234.5 host 1", 80.0, &kind, &laser, &odom), "");
  EXPECT_EQ(kind, "ODOM");
  EXPECT_DOUBLE_EQ(odom.stamp, 1234.5);
  EXPECT_DOUBLE_EQ(odom.pose.y, 2.0);

  ASSERT_EQ(parseCarmenLine("ROBOTLASER1 0 -1.5708 3.1416 0.0175 50 0.01 0 2 1.5 2.5 0 "
                            "0.1 0 0 0 0 0 0 0 0.5 0.5 0 77.25 host 1",
                            80.0, &kind, &laser, &odom),
            "");
  EXPECT_EQ(kind, "ROBOTLASER1");
  EXPECT_DOUBLE_EQ(laser.scan.range_max, 50.0);
  EXPECT_DOUBLE_EQ(laser.scan.angle_increment, 0.0175);
  EXPECT_DOUBLE_EQ(laser.scan.stamp, 77.25);
  EXPECT_NEAR(laser.laser_in_robot.x, 0.1, 1e-12);

  ASSERT_EQ(parseCarmenLine("PARAM robot_length 0.5", 80.0, &kind, &laser, &odom), "");
  EXPECT_EQ(kind, "");
}

TEST(CarmenLog, WrongFieldCountIsNamedWithItsLine) {
  const std::string path = "/tmp/carmen_log_test_" + std::to_string(::getpid()) + ".log";
  {
    std::ofstream log(path);
    log << "# comment\nODOM 0 0 0 0 0 0 1.0 host 1\nPARAM x 1\nODOM 0 0 0 0 0 2.0 host 1\n";
  }
  CarmenLog log;
  const std::string error = readCarmenLog(path, &log);
  EXPECT_EQ(error, path + ":4: ODOM line has 9 fields, expected 10");
  EXPECT_TRUE(log.odometry.empty()) << "no partial result on error";
  {
    std::ofstream bad(path);
    bad << "FLASER 2 1.0 abc 0 0 0 0 0 0 1 host 1\n";
  }
  EXPECT_NE(readCarmenLog(path, &log).find(":1: FLASER line: non-numeric range"),
            std::string::npos);
  {
    std::ofstream ok(path);
    ok << "ODOM 0 0 0 0 0 0 1.0 host 1\nFLASER 2 1.0 2.0 0 0 0 0 0 0 1.1 host 1\nSYNC x\n";
  }
  ASSERT_EQ(readCarmenLog(path, &log), "");
  EXPECT_EQ(log.lasers.size(), 1u);
  EXPECT_EQ(log.odometry.size(), 1u);
  EXPECT_EQ(log.skipped_lines, 1);
  EXPECT_NE(readCarmenLog("/nonexistent.log", &log).find("cannot open"), std::string::npos);
  ::unlink(path.c_str());
}

}  // namespace
}  // namespace ekf_slam
