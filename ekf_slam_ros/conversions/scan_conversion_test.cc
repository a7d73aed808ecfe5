#include "ekf_slam_ros/conversions/scan_conversion.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace ekf_slam
