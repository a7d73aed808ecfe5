#include "ekf_slam_core/sensors/scan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/angle.h"

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

// Horizontal distance from the origin along `bearing` to the walls of a
// box 10 m ahead and 4 m to each side: walls taller than any beam.
double distanceToBox(double bearing) {
  const double c = std::cos(bearing), s = std::sin(bearing);
  double d = std::numeric_limits<double>::infinity();
  if (c > 1e-12) d = std::min(d, 10.0 / c);
  if (std::abs(s) > 1e-12) d = std::min(d, 4.0 / std::abs(s));
  return d;
}

// What a laser tilted by roll and pitch reports in that box, 0.5° beams
// over 180°.
Scan tiltedScanOfBox(double roll, double pitch) {
  Scan scan = makeScan(std::vector<double>(361, 0.0));
  scan.angle_min = -kPi / 2.0;
  scan.angle_increment = degToRad(0.5);
  for (int i = 0; i < scan.size(); ++i) {
    const TiltedBeam beam = tiltedBeam(scan.angle(i), roll, pitch);
    scan.ranges[i] = distanceToBox(beam.level_bearing) / beam.horizontal;
  }
  return scan;
}

// A beam's direction: unit length, and level when the mount is.
TEST(Scan, ATiltedBeamIsAUnitVectorSplitIntoFloorAndHeight) {
  for (double bearing : {-1.5, -0.4, 0.0, 0.7, 1.5}) {
    const TiltedBeam beam = tiltedBeam(bearing, degToRad(3.0), degToRad(-2.0));
    EXPECT_NEAR(beam.horizontal * beam.horizontal + beam.rise * beam.rise, 1.0, 1e-12);
    const TiltedBeam level = tiltedBeam(bearing, 0.0, 0.0);
    EXPECT_NEAR(level.level_bearing, bearing, 1e-15);
    EXPECT_EQ(level.rise, 0.0);
  }
  // A positive pitch tips the front down: the beam straight ahead falls, the
  // one to the left is level. A positive roll lifts the left side.
  EXPECT_NEAR(tiltedBeam(0.0, 0.0, degToRad(2.0)).rise, -std::sin(degToRad(2.0)), 1e-15);
  EXPECT_NEAR(tiltedBeam(kPi / 2.0, 0.0, degToRad(2.0)).rise, 0.0, 1e-15);
  EXPECT_NEAR(tiltedBeam(kPi / 2.0, degToRad(2.0), 0.0).rise, std::sin(degToRad(2.0)), 1e-15);
}

// A laser tilted by 2° about either axis, or both, sees a wall 10 m ahead
// 6 mm too far; the levelled scan has every beam where a level laser would,
// to within 0.2 mm, and keeps invalid readings invalid. A beam beside a
// corner is filled along the chord that cuts it: within 4 mm there.
TEST(Scan, ALevelledScanSeesTallWallsWhereALevelLaserWould) {
  const double tilt = degToRad(2.0);
  for (const auto& [roll, pitch] :
       {std::pair<double, double>{0.0, tilt}, {0.0, -tilt}, {tilt, 0.0}, {-tilt, tilt}}) {
    SCOPED_TRACE(testing::Message() << "roll " << roll << " pitch " << pitch);
    Scan tilted = tiltedScanOfBox(roll, pitch);
    tilted.ranges[100] = std::numeric_limits<double>::quiet_NaN();
    const Scan levelled = levelledScan(tilted, roll, pitch);
    ASSERT_EQ(levelled.size(), tilted.size());
    EXPECT_EQ(levelled.angle_min, tilted.angle_min);
    EXPECT_EQ(levelled.angle_increment, tilted.angle_increment);
    double raw_error = 0.0, levelled_error = 0.0;
    for (int i = 0; i < tilted.size(); ++i) {
      const double truth = distanceToBox(tilted.angle(i));
      if (i == 100) {
        EXPECT_FALSE(levelled.isValid(i));
        continue;
      }
      // Beam 100's neighbours were filled from it or across it.
      if (std::abs(i - 100) <= 1) continue;
      const double raw = std::abs(tilted.ranges[i] - truth);
      const double error = std::abs(levelled.ranges[i] - truth);
      const double corner = std::atan2(4.0, 10.0);
      if (std::abs(std::abs(tilted.angle(i)) - corner) < tilted.angle_increment) {
        EXPECT_LT(error, 0.004) << "beam " << i << " beside a corner";
        continue;
      }
      raw_error = std::max(raw_error, raw);
      levelled_error = std::max(levelled_error, error);
    }
    EXPECT_GT(raw_error, 0.0055);
    EXPECT_LT(levelled_error, 2e-4);
  }
  // Level: the same scan, bit for bit.
  const Scan level = tiltedScanOfBox(0.0, 0.0);
  EXPECT_EQ(levelledScan(level, 0.0, 0.0).ranges, level.ranges);
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
