#include "ekf_slam_core/sensors/scan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace ekf_slam {
namespace {

Scan makeScan(std::vector<double> ranges) {
  Scan scan;
  scan.ranges = std::move(ranges);
  scan.angle_min = -1.0;
  scan.angle_increment = 0.5;
  scan.range_min = 0.1;
  scan.range_max = 80.0;
  scan.stamp = 12.5;
  return scan;
}

TEST(Scan, InvalidReadingConvention) {
  const double inf = std::numeric_limits<double>::infinity();
  const Scan scan = makeScan({1.0, std::nan(""), inf, -inf, 81.83, 81.91, 80.0, 0.05, 0.1, 79.99});
  const std::vector<bool> expected = {true,  false, false, false, false,
                                      false, false, false, true,  true};
  for (int i = 0; i < scan.size(); ++i) EXPECT_EQ(scan.isValid(i), expected[i]) << "beam " << i;
  EXPECT_EQ(countValidReadings(scan), 3);
  EXPECT_DOUBLE_EQ(scan.angle(0), -1.0);
  EXPECT_DOUBLE_EQ(scan.angle(3), 0.5);
}

// A beam at bearing α in an inverted laser's frame points at −α seen from
// an upright laser: the mirrored scan's end points are the original's with
// y negated, the bearings still increase, and mirroring twice is the scan.
TEST(Scan, AMirroredScanSeesTheWorldReflectedAcrossTheLaserAxis) {
  const Scan scan = makeScan({1.0, 2.0, std::numeric_limits<double>::quiet_NaN(), 4.0, 5.5});
  const Scan mirrored = mirroredScan(scan);
  ASSERT_EQ(mirrored.size(), scan.size());
  EXPECT_GT(mirrored.angle_increment, 0.0);
  for (int i = 0; i < scan.size(); ++i) {
    const int j = scan.size() - 1 - i;  // the same beam in the mirrored scan
    ASSERT_EQ(mirrored.isValid(j), scan.isValid(i));
    if (!scan.isValid(i)) continue;
    const double r = scan.ranges[i], m = mirrored.ranges[j];
    EXPECT_NEAR(m * std::cos(mirrored.angle(j)), r * std::cos(scan.angle(i)), 1e-12);
    EXPECT_NEAR(m * std::sin(mirrored.angle(j)), -r * std::sin(scan.angle(i)), 1e-12);
  }
  EXPECT_EQ(mirrored.stamp, scan.stamp);
  EXPECT_EQ(mirrored.range_max, scan.range_max);
  const Scan twice = mirroredScan(mirrored);
  EXPECT_NEAR(twice.angle_min, scan.angle_min, 1e-15);
  for (int i = 0; i < scan.size(); ++i) {
    if (scan.isValid(i)) EXPECT_EQ(twice.ranges[i], scan.ranges[i]);
  }
}

TEST(Scan, ValidationNamesTheBadField) {
  EXPECT_EQ(validateScan(makeScan({1.0})), "");
  EXPECT_EQ(validateScan(makeScan({})), "");  // an empty sweep is data, not a bad geometry
  Scan scan = makeScan({1.0});
  scan.angle_increment = 0.0;
  EXPECT_NE(validateScan(scan).find("Scan.angle_increment"), std::string::npos);
  scan = makeScan({1.0});
  scan.range_max = 0.05;
  EXPECT_NE(validateScan(scan).find("Scan.range_max"), std::string::npos);
  scan = makeScan({1.0});
  scan.angle_min = std::nan("");
  EXPECT_NE(validateScan(scan).find("Scan.angle_min"), std::string::npos);
  scan = makeScan({1.0});
  scan.range_min = -1.0;
  EXPECT_NE(validateScan(scan).find("Scan.range_min"), std::string::npos);
  scan = makeScan({1.0});
  scan.stamp = std::numeric_limits<double>::infinity();
  EXPECT_NE(validateScan(scan).find("Scan.stamp"), std::string::npos);
  // Finite fields whose sweep overflows: the last bearing is +inf.
  scan = makeScan(std::vector<double>(181, 1.0));
  scan.angle_increment = 1e307;
  EXPECT_NE(validateScan(scan).find("last bearing"), std::string::npos);
  scan = makeScan({1.0});
  scan.angle_increment = 1e307;
  EXPECT_EQ(validateScan(scan), "");  // one beam has no sweep to overflow
}

}  // namespace
}  // namespace ekf_slam
