#include "ekf_slam_core/sensors/scan_merge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

using sim::PolygonWorld;
using sim::SweepGeometry;

const double kInf = std::numeric_limits<double>::infinity();

// The P3-DX's lasers: the front one on the standard mount
// (config/calibration.yaml), the rear one facing backwards
// (config/calibration_rear.yaml).
const Pose2 kFrontMount(0.160, 0.0, 0.0);
const Pose2 kRearMount(-0.251, 0.0, kPi);

// An LMS200 in its default variant: 180° at 1°, 8.18 m in mm mode.
SweepGeometry lms200() {
  SweepGeometry sweep;
  sweep.angle_min = -kPi / 2.0;
  sweep.angle_increment = degToRad(1.0);
  sweep.count = 181;
  sweep.max_range = 8.18;
  return sweep;
}

// A convex room (every wall point is seen from anywhere inside), one wall
// oblique, under 8 m across.
PolygonWorld convexRoom() {
  PolygonWorld room;
  room.addPolygon({{-2.5, -2.0}, {3.0, -2.2}, {4.0, 0.5}, {3.2, 2.4}, {-1.8, 2.6}, {-3.0, 0.3}});
  return room;
}

// The range a laser at `origin` with heading `heading` would read anywhere
// within merged beam i, sampled finely: [min, max].
std::pair<double, double> trueRangeSpan(const PolygonWorld& world, const Pose2& origin,
                                        const Scan& merged, int i) {
  double low = kInf, high = 0.0;
  for (int k = -8; k <= 8; ++k) {
    const double bearing = merged.angle(i) + k * merged.angle_increment / 16.0;
    const double r = world.castRay(origin.translation(), origin.theta + bearing, 100.0);
    low = std::min(low, r);
    high = std::max(high, r);
  }
  return {low, high};
}

// Whether the wall point at bearing `bearing` from the robot's origin lies
// inside a laser's 180° field of view, with `margin` (rad) to spare
// (negative: outside by at least -margin).
double fieldOfViewMargin(const PolygonWorld& world, const Pose2& robot, const Pose2& mount,
                         double bearing) {
  const double r = world.castRay(robot.translation(), robot.theta + bearing, 100.0);
  const Vector2 in_base = r * Vector2(std::cos(bearing), std::sin(bearing));
  const Vector2 in_laser = transformTo(mount, in_base);
  return kPi / 2.0 - std::abs(std::atan2(in_laser.y(), in_laser.x()));
}

Scan scanFrom(std::vector<double> ranges, double angle_min, double increment, double stamp = 0.0) {
  Scan scan;
  scan.ranges = std::move(ranges);
  scan.angle_min = angle_min;
  scan.angle_increment = increment;
  scan.range_min = 0.01;
  scan.range_max = 8.18;
  scan.stamp = stamp;
  return scan;
}

// Counts the beams of `merged` whose reading is not within the range a
// laser at `robot` sees across that beam (plus `tolerance`), checking that
// every range is finite or +inf.
int beamsOffTheTruth(const PolygonWorld& world, const Pose2& robot, const Scan& merged,
                     double tolerance, int* valid) {
  int off = 0;
  *valid = 0;
  for (int i = 0; i < merged.size(); ++i) {
    const double r = merged.ranges[i];
    EXPECT_TRUE(std::isfinite(r) || r == kInf) << "beam " << i << ": " << r;
    if (!merged.isValid(i)) continue;
    ++*valid;
    const auto [low, high] = trueRangeSpan(world, robot, merged, i);
    if (r < low - tolerance || r > high + tolerance) ++off;
  }
  return off;
}

TEST(ScanMerge, FrontAndRearLasersSeeTheRoomAsOneLaserAtTheOrigin) {
  const PolygonWorld room = convexRoom();
  const Pose2 robot(0.4, -0.3, 0.3);
  Scan front = sim::simulateScan(room, compose(robot, kFrontMount), lms200(), 0.0, nullptr, 0.01);
  Scan rear = sim::simulateScan(room, compose(robot, kRearMount), lms200(), 0.0, nullptr, 0.01);
  front.stamp = 10.0;
  rear.stamp = 10.0;

  for (double increment_deg : {0.5, 1.0}) {
    SCOPED_TRACE(increment_deg);
    ScanMergeOptions options;
    options.angle_increment = degToRad(increment_deg);
    Scan merged;
    ASSERT_EQ(mergeScans({&front, kFrontMount}, {&rear, kRearMount}, Pose2(), options, &merged),
              "");
    EXPECT_EQ(validateScan(merged), "");
    EXPECT_EQ(merged.size(), static_cast<int>(std::lround(360.0 / increment_deg)));
    EXPECT_DOUBLE_EQ(merged.angle_min, -kPi);
    EXPECT_NEAR(merged.angle_increment * merged.size(), 2.0 * kPi, 1e-12);
    EXPECT_TRUE(merged.merged);
    EXPECT_DOUBLE_EQ(merged.stamp, 10.0);
    EXPECT_DOUBLE_EQ(merged.range_min, 0.0);
    // The farthest reading the rear laser can give, from the origin.
    EXPECT_NEAR(merged.range_max, 8.18 + 0.251, 1e-12);
    // Every reading is what a laser at the origin reads within its beam
    // (the readings of both lasers land on the same walls).
    int valid = 0;
    EXPECT_EQ(beamsOffTheTruth(room, robot, merged, 1e-3, &valid), 0);
    // Both lasers' readings are in it: every one of 362 at 1°, and at 0.5°
    // all but the few that share a beam with a nearer one.
    EXPECT_GT(valid, increment_deg == 1.0 ? 300 : 340);
    EXPECT_LE(valid, 362);
  }

  // Coverage at 1° (no finer than the lasers, so no beam is skipped
  // between two readings): a beam whose wall point either laser sees is
  // filled, one that neither sees (the wedges beside the robot) is not.
  ScanMergeOptions options;
  options.angle_increment = degToRad(1.0);
  Scan merged;
  ASSERT_EQ(mergeScans({&front, kFrontMount}, {&rear, kRearMount}, Pose2(), options, &merged), "");
  const double margin = degToRad(1.5);
  int seen = 0, blind = 0;
  for (int i = 0; i < merged.size(); ++i) {
    const double m = std::max(fieldOfViewMargin(room, robot, kFrontMount, merged.angle(i)),
                              fieldOfViewMargin(room, robot, kRearMount, merged.angle(i)));
    if (m > margin) {
      ++seen;
      EXPECT_TRUE(merged.isValid(i)) << "beam " << i << " at " << radToDeg(merged.angle(i));
    } else if (m < -margin) {
      ++blind;
      EXPECT_FALSE(merged.isValid(i)) << "beam " << i << " at " << radToDeg(merged.angle(i));
    }
  }
  EXPECT_GT(seen, 320);
  EXPECT_GT(blind, 6);  // two side wedges of several degrees each
  // Straight to the left and right of the axle neither laser sees.
  EXPECT_FALSE(merged.isValid(90));   // -90°
  EXPECT_FALSE(merged.isValid(270));  // +90°
  EXPECT_TRUE(merged.isValid(0));     // -180°: the rear laser's centre
  EXPECT_TRUE(merged.isValid(180));   // 0°: the front laser's centre
}

TEST(ScanMerge, TheRobotsMotionBetweenTheStampsMovesTheSecondScan) {
  const PolygonWorld room = convexRoom();
  const Pose2 robot_at_front(0.4, -0.3, 0.3);
  const Pose2 motion(0.25, 0.05, 0.35);  // base_link at the rear stamp, in base_link at the front's
  const Pose2 robot_at_rear = compose(robot_at_front, motion);
  const Scan front =
      sim::simulateScan(room, compose(robot_at_front, kFrontMount), lms200(), 0.0, nullptr, 0.01);
  const Scan rear =
      sim::simulateScan(room, compose(robot_at_rear, kRearMount), lms200(), 0.0, nullptr, 0.01);
  ScanMergeOptions options;
  options.angle_increment = degToRad(1.0);

  Scan merged;
  ASSERT_EQ(mergeScans({&front, kFrontMount}, {&rear, kRearMount}, motion, options, &merged), "");
  int valid = 0;
  EXPECT_EQ(beamsOffTheTruth(room, robot_at_front, merged, 1e-3, &valid), 0);
  EXPECT_GT(valid, 300);
  // The motion's length widens range_max: a rear reading can lie that much
  // farther from the first scan's origin.
  EXPECT_NEAR(merged.range_max, 8.18 + 0.251 + std::hypot(0.25, 0.05), 1e-12);

  // Without the motion the rear half lands where the robot no longer was.
  Scan uncompensated;
  ASSERT_EQ(
      mergeScans({&front, kFrontMount}, {&rear, kRearMount}, Pose2(), options, &uncompensated), "");
  EXPECT_GT(beamsOffTheTruth(room, robot_at_front, uncompensated, 0.05, &valid), 60);
}

TEST(ScanMerge, OneReadingLandsWhereTheMountAndMotionPutIt) {
  // The rear laser reads 1 m straight behind it; the robot then turned a
  // quarter left and moved (0.5, 0.2) between the stamps.
  const Scan first = scanFrom({}, 0.0, degToRad(1.0), 3.0);
  const Scan second = scanFrom({1.0}, 0.0, degToRad(1.0), 3.05);
  const Pose2 motion(0.5, 0.2, kPi / 2.0);
  ScanMergeOptions options;
  options.angle_increment = degToRad(0.5);
  Scan merged;
  ASSERT_EQ(mergeScans({&first, kFrontMount}, {&second, Pose2(-0.25, 0.0, kPi)}, motion, options,
                       &merged),
            "");
  // In base_link at the rear stamp (-1.25, 0); at the front stamp
  // (0.5, 0.2) + R(90°) (-1.25, 0) = (0.5, -1.05).
  const double range = std::hypot(0.5, -1.05), bearing = std::atan2(-1.05, 0.5);
  const int beam =
      static_cast<int>(std::floor((bearing + kPi) / merged.angle_increment + 0.5)) % merged.size();
  EXPECT_EQ(countValidReadings(merged), 1);
  EXPECT_NEAR(merged.ranges[beam], range, 1e-12);
  EXPECT_LE(std::abs(merged.angle(beam) - bearing), merged.angle_increment / 2.0 + 1e-12);
  EXPECT_DOUBLE_EQ(merged.stamp, 3.0);  // the first scan's stamp
}

TEST(ScanMerge, TheNearestReadingOfABeamWins) {
  const Scan far = scanFrom({3.0}, 0.0, degToRad(1.0));
  const Scan near = scanFrom({2.0}, 0.0, degToRad(1.0));
  ScanMergeOptions options;
  options.angle_increment = degToRad(1.0);
  Scan merged;
  ASSERT_EQ(mergeScans({&far, Pose2()}, {&near, Pose2()}, Pose2(), options, &merged), "");
  EXPECT_DOUBLE_EQ(merged.ranges[180], 2.0);
  ASSERT_EQ(mergeScans({&near, Pose2()}, {&far, Pose2()}, Pose2(), options, &merged), "");
  EXPECT_DOUBLE_EQ(merged.ranges[180], 2.0);
  EXPECT_EQ(countValidReadings(merged), 1);
  // +π and −π are one beam.
  const Scan behind = scanFrom({1.5, 2.5}, kPi - 1e-9, 2e-9);
  ASSERT_EQ(mergeScans({&behind, Pose2()}, {&near, Pose2()}, Pose2(), options, &merged), "");
  EXPECT_DOUBLE_EQ(merged.ranges[0], 1.5);
  EXPECT_EQ(countValidReadings(merged), 2);
}

TEST(ScanMerge, NonFiniteReadingsAreSkippedAndNeverReachTheOutput) {
  const double nan = std::nan("");
  // Of each: NaN, +inf, -inf, beyond range_max (a no-return code), below
  // range_min, and one good reading.
  const Scan first =
      scanFrom({nan, kInf, -kInf, 81.83, 0.001, 2.0}, -kPi / 2.0, degToRad(36.0), 1.0);
  const Scan second = scanFrom({1.0, nan, kInf, -kInf, 8.18, 0.0}, -kPi / 2.0, degToRad(36.0), 1.0);
  ScanMergeOptions options;
  Scan merged;
  ASSERT_EQ(mergeScans({&first, kFrontMount}, {&second, kRearMount}, Pose2(), options, &merged),
            "");
  EXPECT_EQ(countValidReadings(merged), 2);
  for (double r : merged.ranges) EXPECT_TRUE(std::isfinite(r) || r == kInf) << r;
  EXPECT_TRUE(std::isfinite(merged.range_max));
  EXPECT_EQ(validateScan(merged), "");

  // Scans of nothing but invalid readings: a merged scan of no returns.
  const Scan blank = scanFrom({nan, nan, kInf}, 0.0, 0.1);
  ASSERT_EQ(mergeScans({&blank, kFrontMount}, {&blank, kRearMount}, Pose2(), options, &merged), "");
  EXPECT_EQ(countValidReadings(merged), 0);
  for (double r : merged.ranges) EXPECT_EQ(r, kInf);

  // A laser whose range_max is +inf: range_max still bounds the readings.
  Scan unbounded = scanFrom({5.0}, 0.0, 0.1);
  unbounded.range_max = kInf;
  ASSERT_EQ(mergeScans({&unbounded, kFrontMount}, {&blank, kRearMount}, Pose2(), options, &merged),
            "");
  EXPECT_TRUE(std::isfinite(merged.range_max));
  EXPECT_EQ(countValidReadings(merged), 1);
}

TEST(ScanMerge, BadGeometryMountOrMotionIsAnErrorThatLeavesTheOutputAlone) {
  const Scan good = scanFrom({2.0, 2.0}, 0.0, 0.1, 5.0);
  Scan merged = scanFrom({7.0}, 0.0, 0.1, -1.0);
  const Scan untouched = merged;
  ScanMergeOptions options;
  auto expectError = [&](const std::string& error, const std::string& names) {
    EXPECT_NE(error.find(names), std::string::npos) << error;
    EXPECT_EQ(merged.ranges, untouched.ranges);
    EXPECT_EQ(merged.stamp, untouched.stamp);
  };

  Scan bad = good;
  bad.angle_min = std::nan("");
  expectError(mergeScans({&good, kFrontMount}, {&bad, kRearMount}, Pose2(), options, &merged),
              "second scan: Scan.angle_min");
  bad = good;
  bad.angle_increment = kInf;
  expectError(mergeScans({&bad, kFrontMount}, {&good, kRearMount}, Pose2(), options, &merged),
              "first scan: Scan.angle_increment");
  Pose2 nan_mount = kRearMount;
  nan_mount.theta = std::nan("");
  expectError(mergeScans({&good, kFrontMount}, {&good, nan_mount}, Pose2(), options, &merged),
              "second scan: its mount must be finite");
  Pose2 inf_motion;
  inf_motion.x = kInf;
  expectError(mergeScans({&good, kFrontMount}, {&good, kRearMount}, inf_motion, options, &merged),
              "motion between the scans must be finite");
  expectError(mergeScans({nullptr, kFrontMount}, {&good, kRearMount}, Pose2(), options, &merged),
              "first scan: missing");
  for (double increment : {0.0, -0.01, std::nan(""), kInf, 1.0}) {
    options.angle_increment = increment;
    expectError(mergeScans({&good, kFrontMount}, {&good, kRearMount}, Pose2(), options, &merged),
                "ScanMergeOptions.angle_increment");
  }
}

TEST(ScanMerge, AnEmptySecondScanLeavesTheFirstAlone) {
  // The first laser at the origin: its readings keep their ranges and fall
  // on the merged beams of their own bearings.
  const PolygonWorld room = convexRoom();
  const Pose2 robot(0.4, -0.3, 0.3);
  Scan front = sim::simulateScan(room, robot, lms200(), 0.0, nullptr, 0.01);
  front.stamp = 42.0;
  const Scan empty;  // no beams, no geometry (angle_increment 0)
  ScanMergeOptions options;
  options.angle_increment = degToRad(0.5);
  Scan merged;
  ASSERT_EQ(mergeScans({&front, Pose2()}, {&empty, Pose2(1.0, 2.0, 3.0)}, Pose2(5.0, 0.0, 1.0),
                       options, &merged),
            "");
  EXPECT_EQ(countValidReadings(merged), countValidReadings(front));
  EXPECT_DOUBLE_EQ(merged.stamp, 42.0);
  EXPECT_NEAR(merged.range_max, 8.18, 1e-12);  // the empty scan widens nothing
  for (int i = 0; i < front.size(); ++i) {
    // Beam i at -90° + i° is merged beam 180 + 2i at 0.5°.
    EXPECT_NEAR(merged.ranges[180 + 2 * i], front.ranges[i], 1e-12) << "beam " << i;
  }
}

}  // namespace
}  // namespace ekf_slam
