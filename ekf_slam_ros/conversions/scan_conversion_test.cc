#include "ekf_slam_ros/conversions/scan_conversion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace ekf_slam {
namespace {

TEST(ScanConversion, CopiesGeometryStampAndEveryReading) {
  sensor_msgs::LaserScan message;
  message.header.stamp = ros::Time(976052857, 340000000);
  message.angle_min = -1.5707963f;
  message.angle_increment = 0.0175485f;
  message.range_min = 0.0f;
  message.range_max = 80.0f;
  message.ranges = {1.25f, std::numeric_limits<float>::quiet_NaN(), 81.83f,
                    std::numeric_limits<float>::infinity(), 79.5f};
  const Scan scan = ros_conversions::fromLaserScan(message);
  ASSERT_EQ(scan.size(), 5);
  EXPECT_NEAR(scan.stamp, 976052857.34, 1e-6);
  EXPECT_FLOAT_EQ(scan.angle_min, -1.5707963f);
  EXPECT_FLOAT_EQ(scan.angle_increment, 0.0175485f);
  EXPECT_FLOAT_EQ(scan.range_max, 80.0f);
  EXPECT_FLOAT_EQ(scan.ranges[0], 1.25f);
  EXPECT_TRUE(std::isnan(scan.ranges[1]));
  // Invalid readings are kept in place and classified by the core.
  EXPECT_TRUE(scan.isValid(0));
  EXPECT_FALSE(scan.isValid(1));
  EXPECT_FALSE(scan.isValid(2));
  EXPECT_FALSE(scan.isValid(3));
  EXPECT_TRUE(scan.isValid(4));
  EXPECT_EQ(validateScan(scan), "");
}

// 181 beams over ±90°: the count fits whether angle_max is the last beam's
// angle or one increment beyond; ten readings short or long it does not,
// and the message names both numbers.
TEST(ScanConversion, ARangeCountThatDisagreesWithTheAnglesIsNamed) {
  sensor_msgs::LaserScan message;
  message.angle_min = -M_PI / 2;
  message.angle_increment = M_PI / 180;
  message.angle_max = M_PI / 2;
  message.ranges.assign(181, 2.0f);
  EXPECT_EQ(ros_conversions::rangeCountError(message), "");
  message.ranges.assign(180, 2.0f);
  EXPECT_EQ(ros_conversions::rangeCountError(message), "");
  message.ranges.assign(171, 2.0f);
  const std::string error = ros_conversions::rangeCountError(message);
  EXPECT_NE(error.find("171 ranges"), std::string::npos) << error;
  EXPECT_NE(error.find("give 181"), std::string::npos) << error;
  message.ranges.assign(191, 2.0f);
  EXPECT_NE(ros_conversions::rangeCountError(message), "");
  message.angle_increment = 0.0f;  // no count to compare: validateScan's case
  EXPECT_EQ(ros_conversions::rangeCountError(message), "");
}

}  // namespace
}  // namespace ekf_slam
