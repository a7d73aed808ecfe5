// Scan matcher on synthetic scans of known motion: ray-cast sweeps of a
// room with cartons (sim::PolygonWorld), LMS200-like noise, clutter.
#include "ekf_slam_core/scan_matching/scan_matcher.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <random>

#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

// A 12 m × 8 m room with three cartons: enough structure in every direction.
sim::PolygonWorld room() {
  sim::PolygonWorld world;
  world.addPolygon({{-6, -4}, {6, -4}, {6, 4}, {-6, 4}});
  world.addBox({2.0, 1.5}, 0.6, 0.4, 0.3);
  world.addBox({-2.5, -1.0}, 0.8, 0.8);
  world.addBox({1.0, -2.5}, 1.0, 0.5, -0.4);
  return world;
}

Scan sweep(const sim::RayCaster& world, const Pose2& robot, const Pose2& laser, std::mt19937* rng,
           double sigma = 0.01) {
  sim::SweepGeometry geometry;
  geometry.angle_increment = kPi / 179;
  geometry.count = 180;
  geometry.max_range = 30.0;
  return sim::simulateScan(world, compose(robot, laser), geometry, sigma, rng);
}

PointCloudReference referenceOf(const Scan& scan, const Pose2& pose, const Pose2& laser,
                                const ScanMatcherOptions& options) {
  std::vector<Vector2> points;
  for (const Vector2& p : scanPointsInRobotFrame(scan, laser, options)) {
    points.push_back(transformFrom(pose, p));
  }
  return PointCloudReference(points, options.normal_radius,
                             options.initial_correspondence_distance);
}

TEST(PointCloudReference, NormalsOfAStraightWallArePerpendicularToIt) {
  std::vector<Vector2> wall;
  for (int i = 0; i <= 40; ++i) wall.push_back(Vector2(-1.0 + 0.05 * i, 2.0));
  const PointCloudReference reference(wall, 0.25, 0.5);
  ASSERT_GT(reference.size(), 30u);
  for (const Vector2& n : reference.normals()) {
    EXPECT_NEAR(std::abs(n.y()), 1.0, 1e-9);
    EXPECT_NEAR(n.x(), 0.0, 1e-6);
  }
  EXPECT_EQ(reference.nearest(Vector2(0.02, 2.1), 0.2) >= 0, true);
  EXPECT_EQ(reference.nearest(Vector2(0.0, 3.0), 0.2), -1);  // beyond the gate
}

// The sliding local map keeps, as key scans enter and leave, the normals a
// reference fitted over the window's points at once would have.
TEST(SlidingNormals, KeepsTheNormalsOfTheWholeWindow) {
  const sim::PolygonWorld world = room();
  const Pose2 laser(0.1, 0.0, 0.0);
  const ScanMatcherOptions options;
  std::mt19937 rng(7);
  constexpr int kWindow = 4;
  SlidingNormals sliding(options.normal_radius);
  std::vector<std::vector<Vector2>> window;
  for (int i = 0; i < 9; ++i) {
    const Pose2 robot(-3.0 + 0.3 * i, 0.2 * std::sin(i), 0.15 * i);
    std::vector<Vector2> placed;
    for (const Vector2& p :
         scanPointsInRobotFrame(sweep(world, robot, laser, &rng), laser, options)) {
      placed.push_back(transformFrom(robot, p));
    }
    sliding.push(placed);
    window.push_back(placed);
    if (window.size() > kWindow) {
      sliding.popOldest();
      window.erase(window.begin());
    }
    ASSERT_EQ(sliding.scanCount(), window.size());
    std::vector<Vector2> all;
    for (const auto& scan : window) all.insert(all.end(), scan.begin(), scan.end());
    const PointCloudReference whole(all, options.normal_radius, 0.5);
    std::vector<Vector2> points, normals;
    sliding.fitted(&points, &normals);
    ASSERT_EQ(points.size(), whole.size()) << "key scan " << i;
    ASSERT_GT(points.size(), 100u);
    for (size_t k = 0; k < points.size(); ++k) {
      EXPECT_EQ(points[k], whole.points()[k]);
      // A normal's sign is arbitrary.
      EXPECT_NEAR(std::abs(normals[k].dot(whole.normals()[k])), 1.0, 1e-9) << "point " << k;
    }
  }
}

TEST(PointCloudReference, IsolatedPointsGetNoNormalAndAreDropped) {
  const PointCloudReference reference({Vector2(0, 0), Vector2(5, 5), Vector2(-3, 2)}, 0.25, 0.5);
  EXPECT_EQ(reference.size(), 0u);
}

// The grid search skips cells that cannot hold the answer; it must still
// find the same distance as looking at every point, for gates of less and
// more than a cell, near cell edges and far from every point.
// The flat cell table numbers keys in the order they first came, finds
// every one again through its growth, and finds no key it was not given;
// neighbouring cells, negative indices and keys that differ only in one
// half are the cases a hash of the key must spread.
TEST(CellIndex, NumbersKeysInOrderAndFindsThemThroughGrowth) {
  CellIndex index;
  std::map<long long, int> reference;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> coordinate(-60, 60);
  for (int k = 0; k < 5000; ++k) {
    const long long key =
        (static_cast<long long>(coordinate(rng)) << 32) ^ static_cast<uint32_t>(coordinate(rng));
    const auto known = reference.find(key);
    const int expected =
        known == reference.end() ? static_cast<int>(reference.size()) : known->second;
    ASSERT_EQ(index.findOrAdd(key), expected) << "key " << key;
    reference.emplace(key, expected);
  }
  EXPECT_EQ(index.size(), static_cast<int>(reference.size()));
  EXPECT_GT(reference.size(), 4000u);
  for (const auto& [key, number] : reference) EXPECT_EQ(index.find(key), number);
  for (int k = 0; k < 1000; ++k) {
    const long long key = (static_cast<long long>(100 + k) << 32) | 5u;  // never added
    EXPECT_EQ(index.find(key), -1);
  }
  index.clear();
  EXPECT_EQ(index.find(reference.begin()->first), -1);
  EXPECT_EQ(index.findOrAdd(7), 0);
}

TEST(PointCloudReference, NearestAndAnyWithinAgreeWithLookingAtEveryPoint) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-3.0, 3.0);
  std::uniform_real_distribution<double> heading(-kPi, kPi);
  std::vector<Vector2> points;
  for (int wall = 0; wall < 12; ++wall) {  // short walls, so that normals survive
    const Vector2 start(coordinate(rng), coordinate(rng));
    const double a = heading(rng);
    for (int i = 0; i < 30; ++i) {
      points.push_back(start + 0.03 * i * Vector2(std::cos(a), std::sin(a)));
    }
  }
  const double cell = 0.5;
  const PointCloudReference reference(points, 0.25, cell);
  ASSERT_GT(reference.size(), 200u);
  std::uniform_real_distribution<double> query(-4.0, 4.0);
  int found = 0;
  for (int k = 0; k < 20000; ++k) {
    Vector2 q(query(rng), query(rng));
    if (k % 4 == 0) q.x() = cell * std::round(q.x() / cell);  // on a cell edge
    const double gate = k % 3 == 0 ? 0.15 : (k % 3 == 1 ? 0.5 : 1.2);
    double best = gate * gate;
    bool any = false;
    for (const Vector2& p : reference.points()) {
      const double d2 = (p - q).squaredNorm();
      if (d2 <= best) {
        best = d2;
        any = true;
      }
    }
    const int j = reference.nearest(q, gate);
    ASSERT_EQ(j >= 0, any) << "query " << q.transpose() << " gate " << gate;
    ASSERT_EQ(reference.anyWithin(q, gate), any) << "query " << q.transpose() << " gate " << gate;
    if (!any) continue;
    ++found;
    EXPECT_EQ((reference.points()[j] - q).squaredNorm(), best);
  }
  EXPECT_GT(found, 5000);
}

TEST(MatchPoints, RecoversAKnownMotionFromAWrongGuess) {
  std::mt19937 rng(7);
  const sim::PolygonWorld world = room();
  const Pose2 laser(0.1, 0.0, 0.0);
  const ScanMatcherOptions options;
  const Pose2 first(0.0, 0.0, 0.1);
  const Pose2 second(0.35, 0.12, 0.18);  // the true motion between the two scans
  const PointCloudReference reference =
      referenceOf(sweep(world, first, laser, &rng), first, laser, options);
  const std::vector<Vector2> points =
      scanPointsInRobotFrame(sweep(world, second, laser, &rng), laser, options);
  // Odometry off by 12 cm and 4 degrees.
  const Pose2 guess = compose(second, Pose2(0.08, -0.09, degToRad(4.0)));
  const MatchResult result = matchPoints(points, reference, guess, options);
  ASSERT_TRUE(result.ok) << result.message;
  EXPECT_LT(std::hypot(result.pose.x - second.x, result.pose.y - second.y), 0.01);
  EXPECT_LT(std::abs(wrapAngle(result.pose.theta - second.theta)), degToRad(0.2));
  EXPECT_LT(result.rms_residual, 0.03);
  EXPECT_GT(result.inlier_fraction, 0.8);
}

TEST(MatchPoints, ToleratesClutterThatIsNotInTheReference) {
  std::mt19937 rng(11);
  const sim::PolygonWorld world = room();
  sim::PolygonWorld cluttered = room();
  // People walking by: small objects seen only in the second scan.
  cluttered.addBox({1.2, 0.6}, 0.3, 0.3);
  cluttered.addBox({-1.0, 1.0}, 0.3, 0.3);
  cluttered.addBox({0.5, -1.2}, 0.4, 0.3);
  const Pose2 laser;
  const ScanMatcherOptions options;
  const Pose2 first(0.0, 0.0, 0.0), second(-0.2, 0.1, -0.1);
  const PointCloudReference reference =
      referenceOf(sweep(world, first, laser, &rng), first, laser, options);
  const std::vector<Vector2> points =
      scanPointsInRobotFrame(sweep(cluttered, second, laser, &rng), laser, options);
  const MatchResult result =
      matchPoints(points, reference, compose(second, Pose2(0.1, 0.05, 0.03)), options);
  ASSERT_TRUE(result.ok) << result.message;
  EXPECT_LT(std::hypot(result.pose.x - second.x, result.pose.y - second.y), 0.015);
  EXPECT_LT(std::abs(wrapAngle(result.pose.theta - second.theta)), degToRad(0.3));
}

TEST(MatchPoints, ALongCorridorKeepsTheGuessAlongItsAxis) {
  // Two parallel walls, no end in range: motion along the corridor is not
  // observable, so the matcher must not invent one; across it, it corrects.
  sim::PolygonWorld corridor;
  corridor.addSegment({-100, 1.0}, {100, 1.0});
  corridor.addSegment({-100, -1.2}, {100, -1.2});
  std::mt19937 rng(3);
  const Pose2 laser;
  ScanMatcherOptions options;
  const Pose2 first(0, 0, 0), second(0.3, 0.05, 0.02);
  const PointCloudReference reference =
      referenceOf(sweep(corridor, first, laser, &rng), first, laser, options);
  const std::vector<Vector2> points =
      scanPointsInRobotFrame(sweep(corridor, second, laser, &rng), laser, options);
  const Pose2 guess(0.25, 0.0, 0.0);  // 5 cm short along x, 5 cm off across
  const MatchResult result = matchPoints(points, reference, guess, options);
  ASSERT_TRUE(result.ok) << result.message;
  EXPECT_NEAR(result.pose.y, second.y, 0.01);
  EXPECT_NEAR(result.pose.theta, second.theta, degToRad(0.3));
  EXPECT_NEAR(result.pose.x, guess.x, 0.05);  // stays near the guess, no runaway
}

TEST(MatchPoints, RefusesWhenTooFewPointsPair) {
  std::mt19937 rng(5);
  const sim::PolygonWorld world = room();
  const ScanMatcherOptions options;
  const PointCloudReference reference =
      referenceOf(sweep(world, Pose2(), Pose2(), &rng), Pose2(), Pose2(), options);
  const std::vector<Vector2> few = {Vector2(1, 0), Vector2(2, 0)};
  const MatchResult result = matchPoints(few, reference, Pose2(), options);
  EXPECT_FALSE(result.ok);
  EXPECT_FALSE(result.message.empty());
}

// A drive around the cartons with odometry that under-reads distance by 5 %
// and drifts 2 deg per metre to the left: the scan-matched track stays within
// centimetres of the truth while the odometry ends decimetres away.
class BothMapModes : public ::testing::TestWithParam<const char*> {};

TEST_P(BothMapModes, CorrectsBiasedOdometryAlongADrive) {
  std::mt19937 rng(21);
  const sim::PolygonWorld world = room();
  const Pose2 laser(0.1, 0.0, 0.0);
  ScanMatcherOptions options;
  options.map_mode = GetParam();
  ScanMatchingOdometry matcher(options);
  Pose2 truth(-4.5, -2.8, 0.0), odometry = truth;
  double worst_matched = 0.0, final_odometry_error = 0.0;
  for (int k = 0; k < 300; ++k) {
    const Scan scan = sweep(world, truth, laser, &rng);
    const Pose2 corrected = matcher.process(scan, odometry, laser);
    // The corrected frame starts at the first odometry pose (= the truth here).
    worst_matched =
        std::max(worst_matched, std::hypot(corrected.x - truth.x, corrected.y - truth.y));
    final_odometry_error = std::hypot(odometry.x - truth.x, odometry.y - truth.y);
    // Next motion: 3 m legs of 5 cm steps, then a quarter turn on the spot.
    const double turn = (k % 75 > 60) ? kPi / 2 / 14 : 0.0;
    const Pose2 step(turn > 0.0 ? 0.0 : 0.05, 0.0, turn);
    truth = compose(truth, step);
    const Pose2 measured(step.x * 0.95, 0.0, step.theta + degToRad(2.0) * step.x);
    odometry = compose(odometry, measured);
  }
  EXPECT_EQ(matcher.counters().refused, 0);
  EXPECT_GT(final_odometry_error, 0.3);
  EXPECT_LT(worst_matched, 0.08);
}

INSTANTIATE_TEST_SUITE_P(ScanMatchingOdometry, BothMapModes, ::testing::Values("local", "global"));

// In the global map a place seen before is matched against the first visit:
// after four laps the pose error is no larger than after the first.
TEST(ScanMatchingOdometry, GlobalMapDoesNotGrowOnRevisits) {
  std::mt19937 rng(4);
  const sim::PolygonWorld world = room();
  ScanMatchingOdometry matcher{ScanMatcherOptions()};
  Pose2 truth(-4.0, 0.0, 0.0);
  size_t after_first_lap = 0;
  for (int k = 0; k < 4 * 72; ++k) {
    matcher.process(sweep(world, truth, Pose2(), &rng), truth, Pose2());
    if (k == 71) after_first_lap = matcher.mapPoints();
    truth = compose(truth, Pose2(0.0, 0.0, 2.0 * kPi / 72));  // turning on the spot
  }
  EXPECT_GT(after_first_lap, 300u);
  // Noise adds a few points where a new reading falls just beyond the spacing.
  EXPECT_LT(matcher.mapPoints(), after_first_lap * 13 / 10);
}

TEST(ScanMatchingOdometry, AnEmptyScanFallsBackToTheOdometryIncrement) {
  std::mt19937 rng(2);
  const sim::PolygonWorld world = room();
  ScanMatchingOdometry matcher{ScanMatcherOptions()};
  matcher.process(sweep(world, Pose2(), Pose2(), &rng), Pose2(), Pose2());
  Scan empty = sweep(world, Pose2(), Pose2(), &rng);
  for (double& r : empty.ranges) r = 81.83;  // "no return" everywhere
  const Pose2 odometry(0.2, 0.0, 0.05);
  MatchResult result;
  const Pose2 corrected = matcher.process(empty, odometry, Pose2(), &result);
  EXPECT_FALSE(result.ok);
  EXPECT_EQ(matcher.counters().refused, 1);
  EXPECT_EQ(matcher.counters().refused_by_fit, 1);  // the reason: nothing to pair
  EXPECT_EQ(matcher.counters().refused_by_correction, 0);
  EXPECT_EQ(matcher.counters().refused_by_odometry, 0);
  EXPECT_NEAR(corrected.x, 0.2, 1e-12);
  EXPECT_NEAR(corrected.theta, 0.05, 1e-12);
}

// Everything the laser sees moves with the robot (a lift, a crowd walking
// alongside): the scans do not change while the wheels report 0.25 m per
// scan. The match ("no motion") is far outside what the wheels allow, so
// the check refuses it and the output follows the wheels; without the
// check the scan matcher holds the robot in place.
TEST(ScanMatchingOdometry, AMatchTheWheelsCannotExplainIsRefused) {
  const sim::PolygonWorld world = room();
  for (const bool check : {true, false}) {
    std::mt19937 rng(8);
    ScanMatcherOptions options;
    if (!check) options.odometry_gate_probability = 0.0;
    ScanMatchingOdometry matcher(options);
    Pose2 odometry;
    Pose2 corrected;
    for (int k = 0; k < 8; ++k) {
      Scan scan = sweep(world, Pose2(), Pose2(), &rng);
      scan.stamp = 10.0 * k;  // a slow lift: the stamps leave the wheels no doubt
      corrected = matcher.process(scan, odometry, Pose2());
      odometry = compose(odometry, Pose2(0.25, 0.0, 0.0));
    }
    const Pose2 last_odometry = compose(odometry, Pose2(-0.25, 0.0, 0.0));
    if (check) {
      // Once three scans in a row were refused they join the map where the
      // wheels put them, and a later scan may match that copy: most, not
      // all, of the seven are refused.
      EXPECT_GE(matcher.counters().refused_by_odometry, 5);
      EXPECT_NEAR(corrected.x, last_odometry.x, 0.05);
    } else {
      EXPECT_EQ(matcher.counters().refused, 0);
      EXPECT_LT(std::abs(corrected.x), 0.05);
    }
  }
}

// A log whose clock steps back (Intel's does): the scan is stamped before
// the previous one, so the odometry looked up at its stamp is where the
// robot was earlier, 0.4 m behind, while the robot really stood still. That
// increment is not the step's: the match (no motion) is taken, and counted
// as not checked. The same disagreement with increasing stamps is refused.
TEST(ScanMatchingOdometry, AScanStampedBeforeThePreviousIsNotCheckedAgainstTheWheels) {
  const sim::PolygonWorld world = room();
  for (const bool back : {true, false}) {
    std::mt19937 rng(9);
    ScanMatchingOdometry matcher{ScanMatcherOptions()};
    Scan first = sweep(world, Pose2(), Pose2(), &rng);
    first.stamp = 10.0;
    matcher.process(first, Pose2(0.4, 0.0, 0.0), Pose2());
    Scan second = sweep(world, Pose2(), Pose2(), &rng);
    second.stamp = back ? 8.0 : 12.0;
    MatchResult result;
    const Pose2 corrected = matcher.process(second, Pose2(), Pose2(), &result);
    if (back) {
      EXPECT_TRUE(result.ok) << result.message;
      EXPECT_EQ(matcher.counters().unchecked_by_odometry, 1);
      EXPECT_EQ(matcher.counters().refused_by_odometry, 0);
      EXPECT_NEAR(corrected.x, 0.4, 0.02);  // stood still, where the first scan was
    } else {
      EXPECT_FALSE(result.ok);
      EXPECT_EQ(matcher.counters().unchecked_by_odometry, 0);
      EXPECT_EQ(matcher.counters().refused_by_odometry, 1);
      EXPECT_EQ(matcher.counters().refused, 1);  // that reason alone
      EXPECT_EQ(matcher.counters().refused_by_fit + matcher.counters().refused_by_correction, 0);
      EXPECT_NEAR(corrected.x, 0.0, 1e-9);  // the wheels' increment
    }
  }
}

// The wheels report no motion while the robot was carried 0.3 m (or
// slipped): the match finds the 0.3 m. With max_correction_translation
// below it, the match is refused for that reason, counted as such, and the
// output follows the wheels; above it, the match is taken.
TEST(ScanMatchingOdometry, ACorrectionBeyondTheBoundIsRefusedAndCountedAsSuch) {
  const sim::PolygonWorld world = room();
  for (const double bound : {0.1, 0.5}) {
    std::mt19937 rng(4);
    ScanMatcherOptions options;
    options.max_correction_translation = bound;
    options.odometry_gate_probability = 0.0;  // the wheels' check would refuse it too
    ScanMatchingOdometry matcher(options);
    matcher.process(sweep(world, Pose2(), Pose2(), &rng), Pose2(), Pose2());
    MatchResult result;
    const Pose2 corrected = matcher.process(sweep(world, Pose2(0.3, 0.0, 0.0), Pose2(), &rng),
                                            Pose2(), Pose2(), &result);
    const ScanMatcherCounters& c = matcher.counters();
    if (bound < 0.3) {
      EXPECT_FALSE(result.ok);
      EXPECT_NE(result.message.find("max_correction"), std::string::npos) << result.message;
      EXPECT_EQ(c.refused, 1);
      EXPECT_EQ(c.refused_by_correction, 1);
      EXPECT_EQ(c.refused_by_fit, 0);
      EXPECT_NEAR(corrected.x, 0.0, 1e-12);
    } else {
      EXPECT_TRUE(result.ok) << result.message;
      EXPECT_EQ(c.refused, 0);
      EXPECT_NEAR(corrected.x, 0.3, 0.02);
    }
  }
}

// A correction the wheels can explain (a few centimetres and a fraction of a
// degree on a 5 cm step) passes the check: see CorrectsBiasedOdometryAlongADrive,
// which drives with a 5 % scale error and 2 deg/m of heading drift and
// expects no refusal.

TEST(ScanMatcherOptions, ValidationNamesTheBadField) {
  EXPECT_EQ(ScanMatcherOptions().validate(), "");
  ScanMatcherOptions o;
  o.correspondence_distance = 0.0;
  EXPECT_NE(o.validate().find("correspondence_distance"), std::string::npos);
  o = ScanMatcherOptions();
  o.initial_correspondence_distance = 0.1;  // below the final gate
  EXPECT_NE(o.validate().find("initial_correspondence_distance"), std::string::npos);
  o = ScanMatcherOptions();
  o.min_inlier_fraction = 1.5;
  EXPECT_NE(o.validate().find("min_inlier_fraction"), std::string::npos);
  o = ScanMatcherOptions();
  o.map_mode = "everything";
  EXPECT_NE(o.validate().find("map_mode"), std::string::npos);
  o = ScanMatcherOptions();
  o.odometry_gate_probability = 1.0;
  EXPECT_NE(o.validate().find("odometry_gate_probability"), std::string::npos);
}

// A sweep whose bearings overflow (angle_increment 1e308: from beam 2 on the
// bearing lies beyond the range of a double) is refused by the scan's
// geometry check; a caller that matches it anyway finds beams without a
// direction: they give no point, and matching against them neither crashes
// nor moves the guess to NaN.
TEST(ScanMatcher, BeamsWithoutAFiniteBearingGiveNoPoints) {
  const ScanMatcherOptions options;
  Scan scan;
  scan.angle_min = -1.0;
  scan.angle_increment = 1e308;
  scan.range_min = 0.0;
  scan.range_max = 80.0;
  scan.ranges.assign(50, 3.0);
  ASSERT_NE(validateScan(scan).find("last bearing"), std::string::npos);
  const std::vector<Vector2> points = scanPointsInRobotFrame(scan, Pose2(0.1, 0.0, 0.0), options);
  ASSERT_EQ(points.size(), 2u) << "only beams 0 and 1 have a finite bearing";
  for (const Vector2& p : points) EXPECT_TRUE(p.allFinite());

  std::mt19937 rng(3);
  const Pose2 laser(0.1, 0.0, 0.0);
  ScanMatchingOdometry odometry(options, MotionNoiseOptions());
  odometry.process(sweep(room(), Pose2(), laser, &rng), Pose2(), laser, nullptr);
  MatchResult match;
  const Pose2 pose = odometry.process(scan, Pose2(0.05, 0.0, 0.0), laser, &match);
  EXPECT_TRUE(pose.allFinite());
  EXPECT_FALSE(match.ok) << "two points cannot be matched";
}

}  // namespace
}  // namespace ekf_slam
