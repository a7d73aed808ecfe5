// Pure pursuit along a polyline of waypoints, with speed and acceleration
// limits. No ROS: the waypoint_driver node feeds it the robot pose from tf
// and publishes its commands as cmd_vel.
//
// Geometry (Coulter, "Implementation of the Pure Pursuit Path Tracking
// Algorithm", CMU-RI-TR-92-01): the goal point lies `lookahead` metres ahead
// of the robot's projection onto the path; in the robot frame it is (x, y),
// at distance d. The circular arc through the robot, tangent to its
// heading, that reaches it has curvature
//     kappa = 2 y / d²      (1/m, positive = turn left).
// The command is v along that arc and w = kappa v. When the goal point lies
// more than `rotate_in_place_angle` off the heading (behind, at the start
// of a lap, after an overshoot), the robot turns on the spot first.
#pragma once

#include <algorithm>
#include <deque>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {
namespace waypoints {

struct PursuitOptions {
  double lookahead = 0.6;                 // m, distance of the goal point ahead on the path
  double max_linear_speed = 0.4;          // m/s
  double max_angular_speed = 1.0;         // rad/s
  double max_linear_acceleration = 0.3;   // m/s² (also the braking rate before the goal)
  double max_angular_acceleration = 1.5;  // rad/s²
  double goal_tolerance = 0.15;           // m, distance to the last point that ends the run
  double rotate_in_place_angle = 1.2;     // rad, turn on the spot beyond this bearing
};

struct VelocityCommand {
  double linear = 0.0;   // m/s
  double angular = 0.0;  // rad/s
};

// Curvature (1/m) of the arc from `robot` through `target` (same frame),
// 2 y / d²; 0 when the target is at the robot.
double pursuitCurvature(const Pose2& robot, const Vector2& target);

// The waypoints driven `laps` times. With `closed`, each lap ends back at the
// first waypoint (a loop); an open list can only be driven once.
std::vector<Vector2> expandLaps(const std::vector<Vector2>& waypoints, int laps, bool closed);

class PurePursuit {
 public:
  // `path`: at least two points (the driver prepends the robot's position).
  PurePursuit(std::vector<Vector2> path, PursuitOptions options);

  // The command for the robot at `pose`, `dt` s (> 0) after the previous
  // call: limited to the speeds, and changed from the previous command by
  // at most acceleration × dt. Once done(), it brakes to zero.
  VelocityCommand update(const Pose2& pose, double dt);

  // The robot came within goal_tolerance of the last point, on its last
  // segment (so a loop's start, which is also its end, does not count early).
  bool done() const { return done_; }
  // Forget the previous command (the robot was stopped from outside, e.g.
  // while its pose was unknown), so the next one ramps up from rest.
  void resetCommand() { last_ = VelocityCommand{}; }
  // Index of the path segment the robot is on (from path[i] to path[i+1]).
  size_t segment() const { return segment_; }
  // The goal point of the last update (for display).
  Vector2 lookaheadPoint() const { return lookahead_point_; }
  // Path length (m) left from the robot's projection to the last point.
  double remaining() const { return remaining_; }
  const VelocityCommand& lastCommand() const { return last_; }

 private:
  // Closest point of segment i to p: parameter in [0, 1] and distance.
  double project(size_t i, const Vector2& p, double* distance) const;
  Vector2 pointAt(double arc_length) const;
  VelocityCommand limit(VelocityCommand wanted, double dt) const;

  std::vector<Vector2> path_;
  std::vector<double> cumulative_;  // arc length at each path point
  PursuitOptions options_;
  size_t segment_ = 0;
  bool done_ = false;
  Vector2 lookahead_point_ = Vector2::Zero();
  double remaining_ = 0.0;
  VelocityCommand last_;
};

// A robot that does not move while it is told to: the safety gate holding
// back every forward command at an obstacle the path passes too near (the
// map a little off, or the robot off its line), or wheels that stall. The
// pursuit alone would keep asking for the same blocked motion for ever.
// Blocked means: over the last stuck_time seconds the robot made less than
// stuck_fraction of the motion it was told to make, and that fraction is
// at least one unit (distance and turn are counted in units of
// stuck_distance and stuck_angle): a gate that holds the robot and lets it
// creep now and then does not hide the blockage, nor does a pause in the
// commands (a new path starting from rest); a robot told to wait is not
// blocked. The pose given is the odometry's: a SLAM correction is no
// motion.
// - Blocked in a turn on the spot (a corner of the footprint would come too
//   near an obstacle), the robot first turns the other way round, at
//   turn_speed, until the pursuit's target is on that side or ahead: the
//   gate may allow the turn that swings the corner away. Once per
//   progress_distance of path.
// - Otherwise, or blocked in that turn too, it backs off backoff_distance
//   slowly (the P3-DX's rear bumpers, not the laser, watch behind it) and
//   the pursuit starts again from rest, meeting the path at another angle.
// After max_backoffs back-offs with less than progress_distance of path
// covered in between, it gives up: the robot stays at rest.
struct RecoveryOptions {
  double stuck_time = 8.0;         // s; 0: never judged blocked
  double stuck_distance = 0.05;    // m
  double stuck_angle = 0.1;        // rad
  double stuck_fraction = 0.25;    // of the commanded motion, below which the robot is blocked
  double backoff_distance = 0.3;   // m
  double backoff_speed = 0.1;      // m/s
  double turn_speed = 0.5;         // rad/s, turning the other way round
  int max_backoffs = 3;            // in a row, without progress in between
  double progress_distance = 1.0;  // m of path that count as progress
};

enum class RecoveryState { kDriving, kTurningAround, kBackingOff, kGaveUp };

class BlockageRecovery {
 public:
  explicit BlockageRecovery(RecoveryOptions options) : options_(options) {}
  // One control step at time `now` (s): the robot's pose, the pursuit's
  // command for it and the path it has left (PurePursuit::remaining).
  // Returns the command to send: the pursuit's while driving, a slow turn
  // while turning around, a slow reverse while backing off, zero once it
  // gave up.
  VelocityCommand update(const Pose2& pose, double now, const VelocityCommand& pursuit,
                         double remaining);
  // The pose was lost or the robot stopped from outside: judge afresh.
  void restartWatch() { watching_ = false; }
  // The current back-off ends after `distance` (m) if that is shorter than
  // backoff_distance (the floor known free behind the robot ends there).
  void limitBackoff(double distance) { backoff_length_ = std::min(backoff_length_, distance); }
  RecoveryState state() const { return state_; }
  // Back-offs since the path last made progress_distance of progress.
  int backoffs() const { return backoffs_; }

 private:
  // The slow straight reverse of a back-off.
  VelocityCommand reverse() const {
    VelocityCommand command;
    command.linear = -options_.backoff_speed;
    return command;
  }
  VelocityCommand turn() const {
    VelocityCommand command;
    command.angular = turn_sign_ * options_.turn_speed;
    return command;
  }
  // update() but for remembering the command returned.
  VelocityCommand step(const Pose2& pose, double now, const VelocityCommand& pursuit,
                       double remaining);
  // Starts watching afresh at `pose`.
  void watch(const Pose2& pose, double now);
  // Adds the step to `pose` at `now`: the motion made, and the motion the
  // previous step's command asked for; drops the steps older than
  // stuck_time. Returns whether the robot is blocked: watched for
  // stuck_time, and the motion made in it is short of stuck_fraction of the
  // motion asked for.
  bool heldBack(const Pose2& pose, double now);
  // Blocked: the next recovery step (turn around, back off or give up).
  VelocityCommand blocked(const Pose2& pose, double now, const VelocityCommand& pursuit,
                          double remaining);

  RecoveryOptions options_;
  RecoveryState state_ = RecoveryState::kDriving;
  bool watching_ = false;
  // The watch: per step its time, the motion made and the motion asked
  // for, in units of stuck_distance plus units of stuck_angle.
  struct Step {
    double time, made, asked;
  };
  std::deque<Step> steps_;
  double made_ = 0.0, asked_ = 0.0;  // summed over steps_
  double watch_start_ = 0.0;
  Pose2 last_pose_;  // at the previous step
  double last_time_ = 0.0;
  VelocityCommand last_command_;  // returned at the previous step
  double backoff_length_ = 0.0;   // of the current back-off
  Pose2 backoff_start_;
  double backoff_time_ = 0.0;
  int backoffs_ = 0;
  bool turned_around_ = false;  // since the last progress_distance of path
  double turn_sign_ = 1.0;
  double remaining_at_backoff_ = 0.0;  // at the last recovery step
};

}  // namespace waypoints
}  // namespace ekf_slam
