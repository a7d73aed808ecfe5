#include "ekf_slam_ros/safety/safety_gate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace ekf_slam {
namespace safety {
namespace {

// Readings of a wall across the robot's path at x = distance (base_link),
// every 2 cm from y = -1 to 1.
std::vector<Vector2> wallAhead(double distance) {
  std::vector<Vector2> points;
  for (double y = -1.0; y <= 1.0; y += 0.02) points.emplace_back(distance, y);
  return points;
}

TEST(SafetyGate, FootprintDistanceIsSignedAndExact) {
  // P3-DX rectangle: x in [-0.301, 0.21], y in [-0.2125, 0.2125].
  EXPECT_NEAR(distanceToFootprint({0.71, 0.0}, 0.21, 0.301, 0.2125), 0.5, 1e-12);
  EXPECT_NEAR(distanceToFootprint({0.0, -0.5125}, 0.21, 0.301, 0.2125), 0.3, 1e-12);
  EXPECT_NEAR(distanceToFootprint({0.51, 0.6125}, 0.21, 0.301, 0.2125), 0.5, 1e-12);  // 3-4-5
  EXPECT_NEAR(distanceToFootprint({0.0, 0.0}, 0.21, 0.301, 0.2125), -0.21,
              1e-12);  // front edge nearest
  EXPECT_NEAR(distanceToFootprint({0.2, 0.0}, 0.21, 0.301, 0.2125), -0.01, 1e-12);
}

TEST(SafetyGate, FarWallLeavesTheCommandAlone) {
  SafetyGate gate;
  gate.setObstacles(wallAhead(1.5), 10.0);
  const GateDecision d = gate.filter({0.4, 0.0}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kNone);
  EXPECT_DOUBLE_EQ(d.command.linear, 0.4);
  EXPECT_GT(d.closest, gate.options().clearance);
}

TEST(SafetyGate, NearWallSlowsToWhatCanStopInTime) {
  SafetyGate gate;
  gate.setObstacles(wallAhead(0.5), 10.0);
  const GateDecision d = gate.filter({0.4, 0.0}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kObstacle);
  EXPECT_GT(d.command.linear, 0.0);
  EXPECT_LT(d.command.linear, 0.4);
  EXPECT_GE(d.closest, gate.options().clearance);
  // One tenth faster would not stop in time.
  EXPECT_LT(gate.stoppingClearance({d.command.linear + 0.04, 0.0}), gate.options().clearance);
}

TEST(SafetyGate, WallInsideTheMarginStopsForwardButNotBackward) {
  SafetyGate gate;
  gate.setObstacles(wallAhead(0.28), 10.0);
  GateDecision d = gate.filter({0.3, 0.0}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kObstacle);
  EXPECT_EQ(d.command.linear, 0.0);
  d = gate.filter({-0.2, 0.0}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kNone);
  EXPECT_DOUBLE_EQ(d.command.linear, -0.2);
  // Turning on the spot would swing the front corners (0.30 m from the
  // axle) into the wall: refused too.
  d = gate.filter({0.0, 1.0}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kObstacle);
  EXPECT_EQ(d.command.angular, 0.0);
}

TEST(SafetyGate, TheArcIsChecked) {
  SafetyGate gate;
  // A post ahead and to the left, off the straight path.
  gate.setObstacles({Vector2(0.35, 0.42)}, 10.0);
  EXPECT_EQ(gate.filter({0.4, 0.0}, 10.1).reason, StopReason::kNone);
  const GateDecision turning = gate.filter({0.4, 1.0}, 10.1);
  EXPECT_EQ(turning.reason, StopReason::kObstacle);
  EXPECT_LT(turning.command.linear, 0.4);
}

TEST(SafetyGate, WallAlongsideDoesNotStopTheRobot) {
  SafetyGate gate;
  std::vector<Vector2> corridor;
  for (double x = -1.0; x <= 3.0; x += 0.02) {
    corridor.emplace_back(x, 0.45);
    corridor.emplace_back(x, -0.45);
  }
  gate.setObstacles(corridor, 10.0);
  const GateDecision d = gate.filter({0.5, 0.0}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kNone);
  EXPECT_DOUBLE_EQ(d.command.linear, 0.5);
}

TEST(SafetyGate, BumpersForbidTheirDirection) {
  SafetyGate gate;
  gate.setObstacles({}, 10.0);
  gate.setBumpers(0x04, 0);
  GateDecision d = gate.filter({0.3, 0.2}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kFrontBumper);
  EXPECT_EQ(d.command.linear, 0.0);
  EXPECT_DOUBLE_EQ(d.command.angular, 0.2);
  EXPECT_EQ(gate.filter({-0.3, 0.0}, 10.1).reason, StopReason::kNone);
  gate.setBumpers(0, 0x10);
  d = gate.filter({-0.3, 0.0}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kRearBumper);
  EXPECT_EQ(d.command.linear, 0.0);
  EXPECT_EQ(gate.filter({0.3, 0.0}, 10.1).reason, StopReason::kNone);
}

TEST(SafetyGate, StallStopsAndHolds) {
  SafetyOptions options;
  options.stall_hold = 1.0;
  SafetyGate gate(options);
  gate.setObstacles({}, 10.0);
  gate.setStall(true, 10.0);
  GateDecision d = gate.filter({0.3, 0.5}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kStall);
  EXPECT_EQ(d.command.linear, 0.0);
  EXPECT_EQ(d.command.angular, 0.0);
  gate.setStall(false, 10.2);
  gate.setObstacles({}, 11.0);
  EXPECT_EQ(gate.filter({0.3, 0.0}, 11.1).reason, StopReason::kStall);  // within the hold
  gate.setObstacles({}, 11.2);
  EXPECT_EQ(gate.filter({0.3, 0.0}, 11.3).reason, StopReason::kNone);
}

TEST(SafetyGate, NoLaserDataNoForwardMotion) {
  SafetyGate gate;
  GateDecision d = gate.filter({0.3, 0.4}, 10.0);  // never a scan
  EXPECT_EQ(d.reason, StopReason::kNoScan);
  EXPECT_EQ(d.command.linear, 0.0);
  EXPECT_DOUBLE_EQ(d.command.angular, 0.4);
  gate.setObstacles(wallAhead(3.0), 10.0);
  EXPECT_EQ(gate.filter({0.3, 0.0}, 10.4).reason, StopReason::kNone);
  EXPECT_EQ(gate.filter({0.3, 0.0}, 10.6).reason, StopReason::kNoScan);  // stale
  EXPECT_EQ(gate.filter({-0.3, 0.0}, 10.6).reason, StopReason::kNone);
}

// The readings are as old as the scan: a robot driving at 0.4 m/s is
// 0.18 m nearer the wall 0.45 s after the scan than the scan shows. The
// same wall that leaves 0.4 m/s alone at once slows it then.
TEST(SafetyGate, ALateScanCountsForTheDistanceDrivenSinceIt) {
  SafetyGate gate;
  gate.setMotion({0.4, 0.0});
  gate.setObstacles(wallAhead(0.85), 10.0);
  EXPECT_EQ(gate.filter({0.4, 0.0}, 10.0).reason, StopReason::kNone);
  const GateDecision late = gate.filter({0.4, 0.0}, 10.45);
  EXPECT_EQ(late.reason, StopReason::kObstacle);
  EXPECT_LT(late.command.linear, 0.4);
  // At rest, the age changes nothing.
  gate.setMotion({0.0, 0.0});
  EXPECT_EQ(gate.filter({0.4, 0.0}, 10.45).reason, StopReason::kNone);
}

// A robot already at 0.4 m/s cannot stop sooner than its brakes allow: a
// slow command does not shorten the stopping path, and the gate stops it
// where a robot at rest could still creep forward.
TEST(SafetyGate, TheRobotsOwnSpeedBoundsTheStoppingPath) {
  SafetyGate gate;
  gate.setObstacles(wallAhead(0.6), 10.0);
  EXPECT_EQ(gate.filter({0.1, 0.0}, 10.0).reason, StopReason::kNone);
  gate.setMotion({0.4, 0.0});
  const GateDecision moving = gate.filter({0.1, 0.0}, 10.0);
  EXPECT_EQ(moving.reason, StopReason::kObstacle);
  EXPECT_EQ(moving.command.linear, 0.0);
  // Backing away is a command against the motion: allowed.
  EXPECT_EQ(gate.filter({-0.2, 0.0}, 10.0).reason, StopReason::kNone);
}

TEST(SafetyGate, HousingAndNonFiniteReadingsAreIgnored) {
  SafetyGate gate;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  gate.setObstacles({Vector2(0.01, 0.0), Vector2(nan, 0.0), Vector2(0.3, nan)}, 10.0);
  const GateDecision d = gate.filter({0.4, 0.0}, 10.1);
  EXPECT_EQ(d.reason, StopReason::kNone);
  EXPECT_TRUE(std::isinf(d.closest));
}

TEST(SafetyGate, LaserCheckCanBeTurnedOff) {
  SafetyOptions options;
  options.use_laser = false;
  SafetyGate gate(options);
  gate.setObstacles(wallAhead(0.25), 10.0);
  EXPECT_EQ(gate.filter({0.4, 0.0}, 10.1).reason, StopReason::kNone);
  EXPECT_EQ(gate.filter({0.4, 0.0}, 20.0).reason, StopReason::kNone);  // no scan needed
}

}  // namespace
}  // namespace safety
}  // namespace ekf_slam
