#include "ekf_slam_ros/waypoints/pure_pursuit.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace ekf_slam {
namespace waypoints {

double pursuitCurvature(const Pose2& robot, const Vector2& target) {
  const Vector2 local = transformTo(robot, target);
  const double distance_squared = local.squaredNorm();
  if (distance_squared < 1e-12) return 0.0;
  return 2.0 * local.y() / distance_squared;
}

std::vector<Vector2> expandLaps(const std::vector<Vector2>& waypoints, int laps, bool closed) {
  std::vector<Vector2> path;
  if (waypoints.empty() || laps < 1) return path;
  if (!closed) laps = 1;
  for (int lap = 0; lap < laps; ++lap) {
    // Later laps start where the previous one closed: at waypoint 0.
    path.insert(path.end(), waypoints.begin() + (lap == 0 ? 0 : 1), waypoints.end());
    if (closed) path.push_back(waypoints.front());
  }
  return path;
}

PurePursuit::PurePursuit(std::vector<Vector2> path, PursuitOptions options)
    : path_(std::move(path)), options_(options) {
  assert(path_.size() >= 2);
  cumulative_.assign(path_.size(), 0.0);
  for (size_t i = 1; i < path_.size(); ++i) {
    cumulative_[i] = cumulative_[i - 1] + (path_[i] - path_[i - 1]).norm();
  }
  remaining_ = cumulative_.back();
  lookahead_point_ = path_.front();
}

double PurePursuit::project(size_t i, const Vector2& p, double* distance) const {
  const Vector2 a = path_[i], b = path_[i + 1];
  const double length_squared = (b - a).squaredNorm();
  const double t =
      length_squared > 1e-12 ? std::clamp((p - a).dot(b - a) / length_squared, 0.0, 1.0) : 1.0;
  *distance = (p - (a + t * (b - a))).norm();
  return t;
}

Vector2 PurePursuit::pointAt(double arc_length) const {
  if (arc_length >= cumulative_.back()) return path_.back();
  const size_t i =
      static_cast<size_t>(std::upper_bound(cumulative_.begin(), cumulative_.end(), arc_length) -
                          cumulative_.begin() - 1);
  const double length = cumulative_[i + 1] - cumulative_[i];
  const double t = length > 1e-12 ? (arc_length - cumulative_[i]) / length : 0.0;
  return path_[i] + t * (path_[i + 1] - path_[i]);
}

VelocityCommand PurePursuit::limit(VelocityCommand wanted, double dt) const {
  wanted.linear = std::clamp(wanted.linear, -options_.max_linear_speed, options_.max_linear_speed);
  wanted.angular =
      std::clamp(wanted.angular, -options_.max_angular_speed, options_.max_angular_speed);
  const double dv = options_.max_linear_acceleration * dt;
  const double dw = options_.max_angular_acceleration * dt;
  VelocityCommand limited;
  limited.linear = std::clamp(wanted.linear, last_.linear - dv, last_.linear + dv);
  limited.angular = std::clamp(wanted.angular, last_.angular - dw, last_.angular + dw);
  return limited;
}

VelocityCommand PurePursuit::update(const Pose2& pose, double dt) {
  dt = std::max(dt, 0.0);
  const Vector2 position = pose.translation();
  if (done_) {
    last_ = limit(VelocityCommand{}, dt);
    return last_;
  }
  // Progress along the path: move to the next segment once the robot is past
  // the end of this one or nearer to the next (cutting a corner). Looking
  // one segment ahead only, so that a loop's later laps, which pass the same
  // places, are never skipped to.
  const size_t last_segment = path_.size() - 2;
  double distance = 0.0;
  double t = project(segment_, position, &distance);
  while (segment_ < last_segment) {
    double next_distance = 0.0;
    const double next_t = project(segment_ + 1, position, &next_distance);
    if (t < 1.0 && next_distance >= distance) break;
    ++segment_;
    t = next_t;
    distance = next_distance;
  }
  const double along =
      cumulative_[segment_] + t * (cumulative_[segment_ + 1] - cumulative_[segment_]);
  remaining_ = cumulative_.back() - along;
  const double to_goal = (path_.back() - position).norm();
  if (segment_ == last_segment && to_goal <= options_.goal_tolerance) {
    done_ = true;
    last_ = limit(VelocityCommand{}, dt);
    return last_;
  }

  // The goal point; near the end it is the last point itself.
  lookahead_point_ = pointAt(along + options_.lookahead);
  if (segment_ == last_segment && to_goal < options_.lookahead) lookahead_point_ = path_.back();
  const Vector2 local = transformTo(pose, lookahead_point_);
  const double bearing = std::atan2(local.y(), local.x());

  VelocityCommand wanted;
  if (std::abs(bearing) > options_.rotate_in_place_angle) {
    // Turn on the spot, slowing as the bearing closes (no overshoot at the
    // angular acceleration limit: w ≤ sqrt(2 a |bearing|)).
    const double w =
        std::min(options_.max_angular_speed,
                 std::sqrt(2.0 * options_.max_angular_acceleration * std::abs(bearing)));
    wanted.angular = std::copysign(w, bearing);
  } else {
    const double kappa = pursuitCurvature(pose, lookahead_point_);
    double v = options_.max_linear_speed;
    // On tight arcs the angular limit sets the speed.
    if (std::abs(kappa) * v > options_.max_angular_speed) {
      v = options_.max_angular_speed / std::abs(kappa);
    }
    // Brake so as to stop at the last point: v ≤ sqrt(2 a s).
    const double left = std::max(remaining_, to_goal);
    v = std::min(v, std::sqrt(2.0 * options_.max_linear_acceleration * left));
    wanted.linear = v;
    wanted.angular = kappa * v;
  }
  last_ = limit(wanted, dt);
  return last_;
}

void BlockageRecovery::watch(const Pose2& pose, double now) {
  watching_ = true;
  steps_.clear();
  made_ = asked_ = 0.0;
  watch_start_ = last_time_ = now;
  last_pose_ = pose;
}

bool BlockageRecovery::heldBack(const Pose2& pose, double now) {
  // A command counts for at most a second (the P3-DX driver's command
  // timeout stops the robot sooner): a long gap between calls asks for nothing.
  const double dt = std::clamp(now - last_time_, 0.0, 1.0);
  Step step{now, 0.0, 0.0};
  step.made = (pose.translation() - last_pose_.translation()).norm() / options_.stuck_distance +
              std::abs(wrapAngle(pose.theta - last_pose_.theta)) / options_.stuck_angle;
  step.asked = std::abs(last_command_.linear) * dt / options_.stuck_distance +
               std::abs(last_command_.angular) * dt / options_.stuck_angle;
  steps_.push_back(step);
  made_ += step.made;
  asked_ += step.asked;
  while (!steps_.empty() && steps_.front().time <= now - options_.stuck_time) {
    made_ -= steps_.front().made;
    asked_ -= steps_.front().asked;
    steps_.pop_front();
  }
  last_pose_ = pose;
  last_time_ = now;
  if (now - watch_start_ < options_.stuck_time) return false;
  // Asked for enough that its share is at least one unit (a robot at rest,
  // or told to wait, is not blocked), and short of that share.
  const double share = options_.stuck_fraction * asked_;
  return share >= 1.0 && made_ < share;
}

VelocityCommand BlockageRecovery::update(const Pose2& pose, double now,
                                         const VelocityCommand& pursuit, double remaining) {
  last_command_ = step(pose, now, pursuit, remaining);
  return last_command_;
}

VelocityCommand BlockageRecovery::step(const Pose2& pose, double now,
                                       const VelocityCommand& pursuit, double remaining) {
  const VelocityCommand rest;
  if (state_ == RecoveryState::kGaveUp) return rest;
  if (state_ == RecoveryState::kBackingOff) {
    // Back far enough, or as far as it goes in three times the time it
    // should take (something behind it as well).
    const double backed = (pose.translation() - backoff_start_.translation()).norm();
    const double allowed = 3.0 * options_.backoff_distance / options_.backoff_speed;
    if (backed < backoff_length_ && now - backoff_time_ < allowed) return reverse();
    state_ = RecoveryState::kDriving;
    watching_ = false;
    return rest;  // the pursuit starts again from rest
  }
  if (state_ == RecoveryState::kTurningAround) {
    // Until the pursuit drives on, or turns this way itself (its target
    // came round to this side), or stops.
    if (pursuit.linear != 0.0 || pursuit.angular * turn_sign_ >= 0.0) {
      state_ = RecoveryState::kDriving;
      watching_ = false;
      return rest;
    }
    if (!heldBack(pose, now)) return turn();
    return blocked(pose, now, pursuit, remaining);  // this way is blocked as well
  }
  if ((backoffs_ > 0 || turned_around_) &&
      remaining < remaining_at_backoff_ - options_.progress_distance) {
    backoffs_ = 0;
    turned_around_ = false;
  }
  if (options_.stuck_time <= 0.0) return pursuit;
  if (!watching_) {
    watch(pose, now);
    return pursuit;
  }
  if (!heldBack(pose, now)) return pursuit;
  return blocked(pose, now, pursuit, remaining);
}

VelocityCommand BlockageRecovery::blocked(const Pose2& pose, double now,
                                          const VelocityCommand& pursuit, double remaining) {
  remaining_at_backoff_ = remaining;
  if (state_ == RecoveryState::kDriving && !turned_around_ && pursuit.linear == 0.0 &&
      pursuit.angular != 0.0) {
    turned_around_ = true;
    turn_sign_ = pursuit.angular > 0.0 ? -1.0 : 1.0;
    state_ = RecoveryState::kTurningAround;
    watch(pose, now);
    return turn();
  }
  watching_ = false;
  if (backoffs_ >= options_.max_backoffs) {
    state_ = RecoveryState::kGaveUp;
    return VelocityCommand{};
  }
  ++backoffs_;
  state_ = RecoveryState::kBackingOff;
  backoff_start_ = pose;
  backoff_time_ = now;
  backoff_length_ = options_.backoff_distance;
  return reverse();
}

}  // namespace waypoints
}  // namespace ekf_slam
