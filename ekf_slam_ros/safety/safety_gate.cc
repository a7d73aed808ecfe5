#include "ekf_slam_ros/safety/safety_gate.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ekf_slam {
namespace safety {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kPathStep = 0.02;   // m between the poses checked along a stopping path
constexpr double kAngleStep = 0.03;  // rad between them on a turn
constexpr int kMaxPathPoses = 400;

// The pose after driving `length` (m) along an arc that turns by `turn` (rad).
Pose2 arcPose(double length, double turn) {
  if (std::abs(turn) < 1e-9) return Pose2(length, 0.0, turn);
  const double radius = length / turn;
  return Pose2(radius * std::sin(turn), radius * (1.0 - std::cos(turn)), turn);
}

// The speed a stopping path runs at: the commanded one, or the robot's own
// when that is faster the same way (or the command is zero): the brakes,
// not the command, decide how soon the robot stops.
double pathSpeed(double commanded, double measured) {
  if (commanded * measured < 0.0) return commanded;
  return std::abs(measured) > std::abs(commanded) ? measured : commanded;
}

}  // namespace

const char* toString(StopReason reason) {
  switch (reason) {
    case StopReason::kNone:
      return "none";
    case StopReason::kObstacle:
      return "obstacle";
    case StopReason::kFrontBumper:
      return "front bumper";
    case StopReason::kRearBumper:
      return "rear bumper";
    case StopReason::kStall:
      return "wheel stall";
    case StopReason::kNoScan:
      return "no laser data";
  }
  return "unknown";
}

double distanceToFootprint(const Vector2& point, double front, double rear, double half_width) {
  // Box centred at ((front - rear)/2, 0) with half extents ((front + rear)/2, half_width).
  const double cx = 0.5 * (front - rear);
  const double hx = 0.5 * (front + rear);
  const double dx = std::abs(point.x() - cx) - hx;
  const double dy = std::abs(point.y()) - half_width;
  const double outside = std::hypot(std::max(dx, 0.0), std::max(dy, 0.0));
  const double inside = std::min(std::max(dx, dy), 0.0);
  return outside + inside;
}

SafetyGate::SafetyGate(SafetyOptions options) : options_(options) {}

void SafetyGate::setObstacles(std::vector<Vector2> points, double stamp) {
  points_.clear();
  points_.reserve(points.size());
  for (const Vector2& p : points) {
    if (p.allFinite() && p.norm() >= options_.min_range) points_.push_back(p);
  }
  scan_stamp_ = stamp;
}

void SafetyGate::setBumpers(unsigned front, unsigned rear) {
  front_bumpers_ = front;
  rear_bumpers_ = rear;
}

void SafetyGate::setStall(bool stalled, double now) {
  if (stalled_ && !stalled) stall_until_ = now + options_.stall_hold;
  stalled_ = stalled;
}

double SafetyGate::stoppingClearance(const Command& command) const {
  return clearanceAlong(command, Pose2(), Command{});
}

double SafetyGate::clearanceAlong(const Command& requested, const Pose2& start,
                                  const Command& motion) const {
  if (points_.empty()) return kInfinity;
  const SafetyOptions& o = options_;
  const Command command{pathSpeed(requested.linear, motion.linear),
                        pathSpeed(requested.angular, motion.angular)};
  // Length and turn of the stopping path: the command for reaction_time,
  // then braking to rest along the same arc (both speeds fall together,
  // limited by the slower of the two decelerations).
  const double v = std::abs(command.linear), w = std::abs(command.angular);
  double brake_time = 0.0;
  if (v > 0.0) brake_time = std::max(brake_time, v / o.deceleration);
  if (w > 0.0) brake_time = std::max(brake_time, w / o.angular_deceleration);
  const double duration = o.reaction_time + 0.5 * brake_time;  // at the full speeds
  const double length = command.linear * duration;
  const double turn = command.angular * duration;
  const int steps = std::clamp(static_cast<int>(std::ceil(std::max(std::abs(length) / kPathStep,
                                                                   std::abs(turn) / kAngleStep))),
                               1, kMaxPathPoses);
  double closest = kInfinity;
  for (int i = 0; i <= steps; ++i) {
    const double f = static_cast<double>(i) / steps;
    const Pose2 pose = compose(start, arcPose(length * f, turn * f));
    for (const Vector2& p : points_) {
      const double d = distanceToFootprint(transformTo(pose, p), o.footprint_front,
                                           o.footprint_rear, o.footprint_half_width);
      closest = std::min(closest, d);
    }
  }
  return closest;
}

bool SafetyGate::safe(const Command& command, const Pose2& start, double now_clearance) const {
  const double along = clearanceAlong(command, start, motion_);
  // Clear of the margin, or no nearer than now to what is already inside it.
  return along >= options_.clearance || along >= now_clearance - 1e-6;
}

GateDecision SafetyGate::filter(const Command& requested, double now) const {
  GateDecision out;
  out.command = requested;
  if (!std::isfinite(requested.linear) || !std::isfinite(requested.angular)) {
    out.command = Command{};  // the node refuses such a command before it gets here
    return out;
  }
  if (stalled_ || now < stall_until_) {
    out.command = Command{};
    out.reason = StopReason::kStall;
    return out;
  }
  if (front_bumpers_ != 0 && out.command.linear > 0.0) {
    out.command.linear = 0.0;
    out.reason = StopReason::kFrontBumper;
  }
  if (rear_bumpers_ != 0 && out.command.linear < 0.0) {
    out.command.linear = 0.0;
    out.reason = StopReason::kRearBumper;
  }
  if (!options_.use_laser) {
    out.closest = kInfinity;
    return out;
  }
  const bool fresh = scan_stamp_ >= 0.0 && now - scan_stamp_ <= options_.scan_timeout;
  if (!fresh) {
    if (out.command.linear > 0.0) {
      out.command.linear = 0.0;
      out.reason = StopReason::kNoScan;
    }
    out.closest = kInfinity;
    return out;
  }
  // Where the robot is now: the scan's pose moved on at the measured
  // velocity for the scan's age. The clearance of that pose alone is what
  // "no nearer than now" compares with.
  const double age = std::clamp(now - scan_stamp_, 0.0, options_.scan_timeout);
  const Pose2 start = arcPose(motion_.linear * age, motion_.angular * age);
  const double now_clearance = clearanceAlong(Command{}, start, Command{});
  if (safe(out.command, start, now_clearance)) {
    out.closest = clearanceAlong(out.command, start, motion_);
    return out;
  }
  // Slower, on the same turn rate; then a turn on the spot; then nothing.
  Command candidate = out.command;
  for (int tenth = 9; tenth >= 0; --tenth) {
    candidate.linear = out.command.linear * tenth / 10.0;
    if (safe(candidate, start, now_clearance)) break;
    if (tenth == 0) candidate = Command{};
  }
  out.command = candidate;
  out.reason = StopReason::kObstacle;
  out.closest = clearanceAlong(out.command, start, motion_);
  return out;
}

}  // namespace safety
}  // namespace ekf_slam
