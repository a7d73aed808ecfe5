#include "ekf_slam_core/sensors/scan.h"

#include <gtest/gtest.h>

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
