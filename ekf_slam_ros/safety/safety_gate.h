// The last check between whoever drives the robot (teleop, step mode, the
// waypoint driver) and the wheels. No ROS: safety_gate_node feeds it the
// laser points, the bumpers and the stall flag, and passes on the command it
// allows.
//
// A command (v, w) is allowed when the robot, driving it for reaction_time
// and then braking at `deceleration` along the same arc, keeps its
// footprint (a rectangle around base_link, inflated by `clearance`) clear
// of every laser point, or at least does not come nearer to one that is
// already inside that margin (so the robot can always back or turn away).
// The readings are as old as the scan: the path starts where the robot is
// now, after driving at its measured velocity since the scan was measured,
// and runs at least as fast as the robot already moves (it cannot stop
// sooner than its brakes allow, whatever the command says). A late scan
// (a loaded computer, a slow serial line) thus counts for what it is.
// Otherwise the linear speed is scaled down in steps of a tenth until the
// stopping path is clear; a turn on the spot is the last resort before a
// full stop.
// - A pressed front bumper forbids forward motion, a rear one backward.
// - A wheel stall stops the robot, and keeps it stopped for stall_hold
//   after the stall flag clears.
// - With no laser data for scan_timeout, forward motion is refused (the
//   LMS200 looks forward only: backing up relies on the rear bumpers).
// Every stop or slow-down names its reason (StopReason), counted for
// /diagnostics.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {
namespace safety {

struct SafetyOptions {
  // Footprint around base_link (P3-DX with bumpers: 210 mm ahead of the
  // axle, 301 mm behind, 425 mm wide; ARIA's p3dx.p).
  double footprint_front = 0.21;         // m
  double footprint_rear = 0.301;         // m
  double footprint_half_width = 0.2125;  // m
  double clearance = 0.10;               // m kept between the footprint and a reading
  double deceleration = 0.3;             // m/s², the driver's linear_deceleration
  double angular_deceleration = 1.7453;  // rad/s², the driver's angular_acceleration
  double reaction_time = 0.3;            // s: command latency and the SIP period
  double min_range = 0.05;               // m: nearer readings are the scanner's own housing
  double scan_timeout = 0.5;             // s: a scan measured longer ago is no laser data
  double stall_hold = 1.0;               // s the robot stays stopped after a stall clears
  bool use_laser = true;                 // false: bumpers and stall only
};

enum class StopReason { kNone, kObstacle, kFrontBumper, kRearBumper, kStall, kNoScan };
constexpr std::array<StopReason, 5> kAllStopReasons = {
    StopReason::kObstacle, StopReason::kFrontBumper, StopReason::kRearBumper, StopReason::kStall,
    StopReason::kNoScan};
const char* toString(StopReason reason);

struct Command {
  double linear = 0.0;   // m/s
  double angular = 0.0;  // rad/s
};

struct GateDecision {
  Command command;                        // what may be sent to the robot
  StopReason reason = StopReason::kNone;  // why it differs from the request
  // The nearest reading's distance to the footprint (m), along the stopping
  // path of the allowed command; +inf when nothing is in view.
  double closest = 0.0;
};

// Signed distance (m) from `point` (base_link frame) to a rectangle
// [-rear, front] × [-half_width, half_width]: negative inside.
double distanceToFootprint(const Vector2& point, double front, double rear, double half_width);

class SafetyGate {
 public:
  explicit SafetyGate(SafetyOptions options = {});

  // Valid readings of a scan in base_link (m), measured at time `stamp`
  // (s, the scan's own stamp, on the clock filter() is given).
  void setObstacles(std::vector<Vector2> points, double stamp);
  // The robot's velocity as its odometry measures it (zero until given).
  void setMotion(const Command& measured) { motion_ = measured; }
  // Bumper segments pressed (bit masks as the P2OS SIP gives them).
  void setBumpers(unsigned front, unsigned rear);
  void setStall(bool stalled, double now);

  // The command allowed at time `now` for the `requested` one.
  GateDecision filter(const Command& requested, double now) const;

  // The smallest distance (m) between the footprint and the readings over
  // the stopping path of `command` from where the scan was measured, the
  // robot at rest; +inf without readings.
  double stoppingClearance(const Command& command) const;

  const SafetyOptions& options() const { return options_; }

 private:
  // Along the stopping path of `command` from `start` (base_link at the
  // scan → now), at least as fast as `motion`, the robot's velocity.
  double clearanceAlong(const Command& command, const Pose2& start, const Command& motion) const;
  bool safe(const Command& command, const Pose2& start, double now_clearance) const;

  SafetyOptions options_;
  std::vector<Vector2> points_;
  double scan_stamp_ = -1.0;
  Command motion_;
  unsigned front_bumpers_ = 0, rear_bumpers_ = 0;
  bool stalled_ = false;
  double stall_until_ = -1.0;
};

}  // namespace safety
}  // namespace ekf_slam
