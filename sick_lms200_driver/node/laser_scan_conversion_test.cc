#include "sick_lms200_driver/node/laser_scan_conversion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace sick_lms200 {
namespace {

LaserScanData halfDegreeScan() {
  LaserScanData scan;
  scan.angle_deg = 180;
  scan.resolution_centideg = 50;
  scan.baud = 38400;
  scan.first_beam_time = 1000.25;
  scan.sweep_time = sweepTime(180, 50);
  scan.time_increment = beamTimeIncrement(180, 50);
  scan.values.units = Units::kCentimetres;
  for (int i = 0; i < 361; ++i) scan.values.ranges.push_back(1.0f + 0.01f * i);
  scan.values.ranges[5] = std::numeric_limits<float>::infinity();
  return scan;
}

TEST(LaserScanConversion, FillsGeometryAndTimingForAnUprightScanner) {
  const LaserScanData scan = halfDegreeScan();
  const sensor_msgs::LaserScan msg = toLaserScan(scan, ScanMessageOptions{});
  EXPECT_EQ(msg.header.frame_id, "laser");
  EXPECT_NEAR(msg.header.stamp.toSec(), 1000.25, 1e-6);
  EXPECT_FLOAT_EQ(msg.angle_min, static_cast<float>(-M_PI / 2));
  EXPECT_FLOAT_EQ(msg.angle_max, static_cast<float>(M_PI / 2));
  EXPECT_FLOAT_EQ(msg.angle_increment, static_cast<float>(M_PI / 360));
  // angle_min + (n - 1) * increment == angle_max
  EXPECT_NEAR(msg.angle_min + (msg.ranges.size() - 1) * msg.angle_increment, msg.angle_max, 1e-5);
  // stamp + (n - 1) * time_increment == time of the last beam (two mirror turns, 0.5°)
  EXPECT_NEAR((msg.ranges.size() - 1) * msg.time_increment, 1.5 / 75.0, 1e-7);
  // 732-byte telegram at 38400 baud: 190.6 ms → 8 double turns (213 ms)
  EXPECT_NEAR(msg.scan_time, 16.0 / 75.0, 1e-6);
  EXPECT_FLOAT_EQ(msg.range_max, 81.82f);
  EXPECT_TRUE(std::isinf(msg.ranges[5]));
  EXPECT_FLOAT_EQ(msg.ranges[0], 1.0f);
}

TEST(LaserScanConversion, InvertedMountReversesBeamsAndStampsTheFirstElement) {
  const LaserScanData scan = halfDegreeScan();
  ScanMessageOptions options;
  options.inverted = true;
  options.frame_id = "laser_flipped";
  const sensor_msgs::LaserScan msg = toLaserScan(scan, options);
  ASSERT_EQ(msg.ranges.size(), 361u);
  EXPECT_FLOAT_EQ(msg.ranges[0], scan.values.ranges[360]);
  EXPECT_TRUE(std::isinf(msg.ranges[355]));
  EXPECT_GT(msg.angle_increment, 0.0f);
  EXPECT_LT(msg.time_increment, 0.0f);
  // The first element is the last beam measured; the last element the first.
  EXPECT_NEAR(msg.header.stamp.toSec(), 1000.25 + scan.sweep_time, 1e-6);
  EXPECT_NEAR(msg.header.stamp.toSec() + 360 * msg.time_increment, 1000.25, 1e-6);
}

}  // namespace
}  // namespace sick_lms200
