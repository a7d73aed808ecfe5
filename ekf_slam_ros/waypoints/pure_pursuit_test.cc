#include "ekf_slam_ros/waypoints/pure_pursuit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace ekf_slam {
namespace waypoints {
namespace {

// Moves a unicycle by (v, w) for dt along the exact arc.
Pose2 drive(const Pose2& pose, const VelocityCommand& command, double dt) {
  const double distance = command.linear * dt, turn = command.angular * dt;
  return compose(pose,
                 Pose2(distance * std::cos(turn / 2.0), distance * std::sin(turn / 2.0), turn));
}

TEST(PursuitCurvatureTest, PointStraightAheadIsAStraightLine) {
  EXPECT_DOUBLE_EQ(pursuitCurvature(Pose2(0, 0, 0), Vector2(2.0, 0.0)), 0.0);
  EXPECT_NEAR(pursuitCurvature(Pose2(1, 1, kPi / 2), Vector2(1.0, 3.0)), 0.0, 1e-12);
}

TEST(PursuitCurvatureTest, LeftIsPositiveRightIsNegative) {
  // (1, 1) from the origin facing +x: the circle through both points tangent
  // to the x axis has radius 1 (centre (0, 1)), so kappa = 2·1 / 2 = 1.
  EXPECT_NEAR(pursuitCurvature(Pose2(0, 0, 0), Vector2(1.0, 1.0)), 1.0, 1e-12);
  EXPECT_NEAR(pursuitCurvature(Pose2(0, 0, 0), Vector2(1.0, -1.0)), -1.0, 1e-12);
  // The same in a rotated, shifted robot frame: facing +y at (2, 3), a point
  // at (1, 4) is ahead-left.
  EXPECT_NEAR(pursuitCurvature(Pose2(2, 3, kPi / 2), Vector2(1.0, 4.0)), 1.0, 1e-12);
  // Straight to the left at distance 0.5: a half circle of radius 0.25.
  EXPECT_NEAR(pursuitCurvature(Pose2(0, 0, 0), Vector2(0.0, 0.5)), 4.0, 1e-12);
  EXPECT_EQ(pursuitCurvature(Pose2(1, 1, 0), Vector2(1.0, 1.0)), 0.0);
}

TEST(PursuitCurvatureTest, ArcReallyPassesThroughTheTarget) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> coordinate(-3.0, 3.0);
  for (int i = 0; i < 100; ++i) {
    const Vector2 target(std::abs(coordinate(random)) + 0.1, coordinate(random));
    const double kappa = pursuitCurvature(Pose2(), target);
    // The circle centred at (0, 1/kappa) with radius |1/kappa| contains the target.
    if (std::abs(kappa) < 1e-9) continue;
    const Vector2 centre(0.0, 1.0 / kappa);
    EXPECT_NEAR((target - centre).norm(), std::abs(1.0 / kappa), 1e-9);
  }
}

TEST(ExpandLapsTest, ClosedLoopsReturnToTheFirstWaypointEachLap) {
  const std::vector<Vector2> points{{1, 0}, {1, 1}, {0, 1}};
  const std::vector<Vector2> two = expandLaps(points, 2, true);
  ASSERT_EQ(two.size(), 7u);  // 1 0 | 1 1 | 0 1 | 1 0 | 1 1 | 0 1 | 1 0
  EXPECT_EQ(two[3], points[0]);
  EXPECT_EQ(two[6], points[0]);
  EXPECT_EQ(expandLaps(points, 3, false).size(), 3u) << "an open list is driven once";
  EXPECT_TRUE(expandLaps(points, 0, true).empty());
}

TEST(PurePursuitTest, TurnsTowardsAPointBehindOnTheSpot) {
  PursuitOptions options;
  PurePursuit pursuit({{0, 0}, {-3, 0}}, options);
  VelocityCommand command;
  for (int i = 0; i < 10; ++i) command = pursuit.update(Pose2(0, 0, 0), 0.05);
  EXPECT_EQ(command.linear, 0.0);
  EXPECT_GT(std::abs(command.angular), 0.5);
}

TEST(PurePursuitTest, SpeedAndAccelerationLimitsHoldOnRandomPaths) {
  PursuitOptions options;
  options.max_linear_speed = 0.5;
  options.max_angular_speed = 0.8;
  options.max_linear_acceleration = 0.4;
  options.max_angular_acceleration = 1.2;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-4.0, 4.0);
  const double dt = 0.05;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vector2> path{{0, 0}};
    for (int i = 0; i < 6; ++i) path.emplace_back(coordinate(random), coordinate(random));
    PurePursuit pursuit(path, options);
    Pose2 pose(0, 0, coordinate(random));
    VelocityCommand previous;
    int steps = 0;
    for (; steps < 20000 && !(pursuit.done() && previous.linear == 0.0); ++steps) {
      const VelocityCommand command = pursuit.update(pose, dt);
      ASSERT_LE(std::abs(command.linear), options.max_linear_speed + 1e-12);
      ASSERT_LE(std::abs(command.angular), options.max_angular_speed + 1e-12);
      ASSERT_LE(std::abs(command.linear - previous.linear),
                options.max_linear_acceleration * dt + 1e-12);
      ASSERT_LE(std::abs(command.angular - previous.angular),
                options.max_angular_acceleration * dt + 1e-12);
      ASSERT_GE(command.linear, 0.0) << "the driver never reverses";
      previous = command;
      pose = drive(pose, command, dt);
    }
    // Every random path is finished, at the last point, at rest.
    EXPECT_TRUE(pursuit.done()) << "trial " << trial;
    EXPECT_LE((pose.translation() - path.back()).norm(), options.goal_tolerance + 0.05)
        << "trial " << trial;
    EXPECT_EQ(previous.linear, 0.0);
  }
}

TEST(PurePursuitTest, ReachesTheGoalOnlyOnTheLastSegmentOfALoop) {
  // A closed square driven twice: the start point is passed twice before the
  // end, and must not end the run.
  const std::vector<Vector2> square{{2, 0}, {2, 2}, {0, 2}, {0, 0}};
  std::vector<Vector2> path{{0, 0}};
  const std::vector<Vector2> laps = expandLaps(square, 2, true);
  path.insert(path.end(), laps.begin(), laps.end());
  PursuitOptions options;
  options.lookahead = 0.4;
  PurePursuit pursuit(path, options);
  Pose2 pose;
  double driven = 0.0;
  for (int step = 0; step < 20000 && !pursuit.done(); ++step) {
    const VelocityCommand command = pursuit.update(pose, 0.05);
    driven += command.linear * 0.05;
    pose = drive(pose, command, 0.05);
  }
  ASSERT_TRUE(pursuit.done());
  EXPECT_EQ(pursuit.segment(), path.size() - 2);
  // Two laps of 8 m plus the way to the first corner, less the corners cut.
  EXPECT_GT(driven, 17.0);
  EXPECT_LT(driven, 18.5);
  EXPECT_LE((pose.translation() - Vector2(2, 0)).norm(), options.goal_tolerance);
}

TEST(PurePursuitTest, GoalToleranceDecidesDone) {
  PursuitOptions options;
  options.goal_tolerance = 0.2;
  PurePursuit pursuit({{0, 0}, {1, 0}}, options);
  pursuit.update(Pose2(0.7, 0.0, 0.0), 0.05);
  EXPECT_FALSE(pursuit.done());
  pursuit.update(Pose2(0.85, 0.0, 0.0), 0.05);
  EXPECT_TRUE(pursuit.done());
  // Once done it only brakes.
  VelocityCommand command = pursuit.update(Pose2(0.0, 0.0, 0.0), 0.05);
  EXPECT_EQ(command.linear, 0.0);
}

TEST(PurePursuitTest, BrakesToStopAtTheGoal) {
  PursuitOptions options;
  options.max_linear_acceleration = 0.3;
  PurePursuit pursuit({{0, 0}, {5, 0}}, options);
  Pose2 pose;
  const double dt = 0.05;
  double fastest = 0.0;
  for (int step = 0; step < 2000 && !pursuit.done(); ++step) {
    const VelocityCommand command = pursuit.update(pose, dt);
    const double to_goal = 5.0 - pose.x;
    // Never faster than the speed from which the robot can still stop at
    // the goal (one control step of lag allowed).
    EXPECT_LE(command.linear, std::sqrt(2.0 * 0.3 * to_goal) + 0.3 * dt + 1e-9)
        << "at x = " << pose.x;
    fastest = std::max(fastest, command.linear);
    pose = drive(pose, command, dt);
  }
  EXPECT_TRUE(pursuit.done());
  EXPECT_NEAR(fastest, options.max_linear_speed, 1e-12) << "cruises at the speed limit";
  EXPECT_NEAR(pose.y, 0.0, 1e-9);
}

TEST(PurePursuitTest, AngularLimitSetsTheSpeedOnTightArcs) {
  PursuitOptions options;
  options.max_angular_speed = 0.3;
  // From the origin the goal point, 0.6 m along the first segment, is at
  // (0.46, 0.38): kappa ≈ 2.1 1/m, so v = 0.3 / 2.1 ≈ 0.14 m/s, not 0.4.
  PurePursuit tight({{0, 0}, {0.6, 0.5}, {5, 5}}, options);
  VelocityCommand command;
  for (int i = 0; i < 100; ++i) command = tight.update(Pose2(0, 0, 0), 0.05);
  const double kappa = pursuitCurvature(Pose2(0, 0, 0), tight.lookaheadPoint());
  EXPECT_NEAR(kappa, 2.13, 0.01);
  EXPECT_NEAR(command.angular, 0.3, 1e-9);
  EXPECT_NEAR(command.linear, 0.3 / kappa, 1e-9);
}

// A wall 2 m ahead across the path that stops the robot 0.3 m before it
// (as the safety gate would): the pursuit keeps asking for forward motion.
// The recovery backs off 0.3 m after stuck_time, tries again, and after
// max_backoffs fruitless back-offs gives up with the robot at rest.
TEST(BlockageRecoveryTest, BacksOffFromABlockedPathAndGivesUpAfterTheLastTry) {
  RecoveryOptions options;
  PurePursuit pursuit({{0, 0}, {5, 0}}, PursuitOptions());
  BlockageRecovery recovery(options);
  const double dt = 0.05, stop_x = 1.7;
  Pose2 pose;
  int backoffs_started = 0;
  double gave_up_at = -1.0;
  RecoveryState previous = RecoveryState::kDriving;
  for (int i = 0; i < 4000; ++i) {
    const double now = i * dt;
    const VelocityCommand wanted = pursuit.update(pose, dt);
    const VelocityCommand command = recovery.update(pose, now, wanted, pursuit.remaining());
    if (recovery.state() == RecoveryState::kBackingOff && previous != RecoveryState::kBackingOff) {
      ++backoffs_started;
      EXPECT_NEAR(pose.x, stop_x, 1e-9) << "backs off only where it is blocked";
    }
    if (previous == RecoveryState::kBackingOff && recovery.state() == RecoveryState::kDriving) {
      EXPECT_NEAR(pose.x, stop_x - options.backoff_distance, 0.01);
      pursuit.resetCommand();
    }
    if (recovery.state() == RecoveryState::kBackingOff) {
      EXPECT_EQ(command.linear, -options.backoff_speed);
      EXPECT_EQ(command.angular, 0.0);
    }
    if (recovery.state() == RecoveryState::kGaveUp) {
      if (gave_up_at < 0.0) gave_up_at = now;
      EXPECT_EQ(command.linear, 0.0);
      EXPECT_EQ(command.angular, 0.0);
    }
    previous = recovery.state();
    pose = drive(pose, command, dt);
    pose.x = std::min(pose.x, stop_x);  // the wall
  }
  EXPECT_EQ(backoffs_started, options.max_backoffs);
  EXPECT_EQ(recovery.state(), RecoveryState::kGaveUp);
  // Each try: blocked for stuck_time, 3 s backing off, and the drive back.
  EXPECT_GT(gave_up_at, (options.max_backoffs + 1) * options.stuck_time);
  EXPECT_LT(gave_up_at, 80.0);
}

// The path's first point lies behind the robot on its right: the pursuit
// turns clockwise on the spot, which the safety gate refuses there (an
// obstacle by the footprint's corner). The recovery turns the robot the
// other way round, the long way, until the target is on that side; then
// the pursuit drives the path, with no back-off.
TEST(BlockageRecoveryTest, ATurnBlockedOneWayIsMadeTheOtherWayRound) {
  RecoveryOptions options;
  PurePursuit pursuit({{0, 0}, {-0.5, -1.5}, {-0.5, -4}}, PursuitOptions());
  BlockageRecovery recovery(options);
  const double dt = 0.05;
  Pose2 pose;
  double turned_around_at = -1.0;
  for (int i = 0; i < 4000 && !pursuit.done(); ++i) {
    const double now = i * dt;
    const VelocityCommand wanted = pursuit.update(pose, dt);
    const RecoveryState before = recovery.state();
    const VelocityCommand command = recovery.update(pose, now, wanted, pursuit.remaining());
    ASSERT_NE(recovery.state(), RecoveryState::kBackingOff) << "at " << now << " s";
    if (recovery.state() == RecoveryState::kTurningAround) {
      if (turned_around_at < 0.0) turned_around_at = now;
      EXPECT_EQ(command.linear, 0.0);
      EXPECT_EQ(command.angular, options.turn_speed);  // anticlockwise
    }
    if (before != RecoveryState::kDriving && recovery.state() == RecoveryState::kDriving) {
      pursuit.resetCommand();
    }
    VelocityCommand allowed = command;
    const bool clockwise_on_the_spot = command.linear == 0.0 && command.angular < 0.0;
    if (pose.translation().norm() < 0.05 && clockwise_on_the_spot) allowed = VelocityCommand();
    pose = drive(pose, allowed, dt);
  }
  EXPECT_NEAR(turned_around_at, options.stuck_time, 0.2);
  EXPECT_TRUE(pursuit.done());
  EXPECT_EQ(recovery.backoffs(), 0);
}

// Blocked in a turn on the spot either way: the recovery turns the other
// way round, is blocked there too, and backs off.
TEST(BlockageRecoveryTest, ATurnBlockedBothWaysEndsInABackOff) {
  RecoveryOptions options;
  PurePursuit pursuit({{0, 0}, {-0.5, -1.5}, {-0.5, -4}}, PursuitOptions());
  BlockageRecovery recovery(options);
  const double dt = 0.05;
  Pose2 pose;
  std::vector<RecoveryState> states{RecoveryState::kDriving};
  for (int i = 0; i < 1000 && recovery.state() != RecoveryState::kBackingOff; ++i) {
    const VelocityCommand wanted = pursuit.update(pose, dt);
    recovery.update(pose, i * dt, wanted, pursuit.remaining());
    if (recovery.state() != states.back()) states.push_back(recovery.state());
    // The robot does not move: the gate holds every turn.
  }
  EXPECT_EQ(states,
            (std::vector<RecoveryState>{RecoveryState::kDriving, RecoveryState::kTurningAround,
                                        RecoveryState::kBackingOff}));
  EXPECT_EQ(recovery.backoffs(), 1);
}

// Held at an obstacle, the gate lets the robot creep a little now and then
// (it turns by 0.03 rad every second), and a new path every 5 s starts the
// pursuit from rest: the robot is still found blocked.
TEST(BlockageRecoveryTest, CreepingAndRestartsDoNotHideABlockage) {
  RecoveryOptions options;
  BlockageRecovery recovery(options);
  const double dt = 0.1;
  Pose2 pose;
  std::unique_ptr<PurePursuit> pursuit;
  double blocked_at = -1.0;
  for (int i = 0; i < 600 && blocked_at < 0.0; ++i) {
    const double now = i * dt;
    if (i % 50 == 0)
      pursuit =
          std::make_unique<PurePursuit>(std::vector<Vector2>{{0, 0}, {3, 1}}, PursuitOptions());
    const VelocityCommand wanted = pursuit->update(pose, i % 50 == 0 ? 0.0 : dt);
    recovery.update(pose, now, wanted, pursuit->remaining());
    if (recovery.state() != RecoveryState::kDriving) blocked_at = now;
    if (i % 10 == 0) pose.theta += 0.03;  // the creep
  }
  EXPECT_GE(blocked_at, options.stuck_time);
  EXPECT_LT(blocked_at, options.stuck_time + 1.0);
}

// A robot that drives, or turns on the spot, or waits at rest is never
// judged blocked, and gets the pursuit's command unchanged.
TEST(BlockageRecoveryTest, ARobotThatMovesOrIsToldToWaitIsNotBlocked) {
  PursuitOptions pursuit_options;
  // A loop with a point behind the start: it turns on the spot first.
  PurePursuit pursuit({{0, 0}, {-1, 0}, {-1, 3}, {2, 3}, {2, 0}, {0, 0}}, pursuit_options);
  BlockageRecovery recovery{RecoveryOptions()};
  const double dt = 0.05;
  Pose2 pose(0.0, 0.0, 0.0);
  double now = 0.0;
  for (int i = 0; i < 4000 && !pursuit.done(); ++i, now += dt) {
    const VelocityCommand wanted = pursuit.update(pose, dt);
    const VelocityCommand command = recovery.update(pose, now, wanted, pursuit.remaining());
    ASSERT_EQ(recovery.state(), RecoveryState::kDriving) << "at step " << i;
    EXPECT_EQ(command.linear, wanted.linear);
    EXPECT_EQ(command.angular, wanted.angular);
    pose = drive(pose, command, dt);
  }
  EXPECT_TRUE(pursuit.done());
  // Standing still for a minute with nothing asked of it.
  for (int i = 0; i < 1200; ++i, now += dt) {
    recovery.update(pose, now, VelocityCommand(), pursuit.remaining());
  }
  EXPECT_EQ(recovery.state(), RecoveryState::kDriving);
  EXPECT_EQ(recovery.backoffs(), 0);
}

// Progress along the path between two blockages starts the count afresh,
// so a long run with a few tight spots never gives up.
TEST(BlockageRecoveryTest, ProgressBetweenBlockagesResetsTheCount) {
  RecoveryOptions options;
  options.max_backoffs = 1;
  BlockageRecovery recovery(options);
  VelocityCommand forward;
  forward.linear = 0.3;
  const double dt = 0.05;
  double now = 0.0;
  Pose2 pose;
  double remaining = 20.0;
  // Blocked at x = 0 until the back-off starts.
  while (recovery.state() == RecoveryState::kDriving && now < 60.0) {
    recovery.update(pose, now, forward, remaining);
    now += dt;
  }
  ASSERT_EQ(recovery.state(), RecoveryState::kBackingOff);
  EXPECT_EQ(recovery.backoffs(), 1);
  pose.x = -options.backoff_distance;
  remaining += options.backoff_distance;
  recovery.update(pose, now, forward, remaining);
  ASSERT_EQ(recovery.state(), RecoveryState::kDriving);
  // It then drives 2 m along the path and is blocked again: a first
  // back-off again, not the end.
  for (int i = 0; i < 100; ++i) {
    now += dt;
    pose.x += 0.02;
    remaining -= 0.02;
    recovery.update(pose, now, forward, remaining);
  }
  while (recovery.state() == RecoveryState::kDriving && now < 200.0) {
    now += dt;
    recovery.update(pose, now, forward, remaining);
  }
  EXPECT_EQ(recovery.state(), RecoveryState::kBackingOff);
  EXPECT_EQ(recovery.backoffs(), 1);
}

}  // namespace
}  // namespace waypoints
}  // namespace ekf_slam
