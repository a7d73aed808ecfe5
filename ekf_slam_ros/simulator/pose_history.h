// A short history of the true robot pose, so that the laser emulator can ask
// for the pose at the instant each mirror turn started (a few ms in the past
// when it builds the scan) and the scan is ray-cast from where the robot
// really was, not from where it is when the telegram is assembled. No ROS.
#pragma once

#include <deque>
#include <utility>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {
namespace sim {

class PoseHistory {
 public:
  explicit PoseHistory(double span = 1.0) : span_(span) {}

  // Appends the pose at time t (s); times must not decrease (older entries
  // than the newest are ignored). Entries older than `span` s are dropped.
  void add(double t, const Pose2& pose);
  // The robot was put elsewhere at t (carried): the poses before are
  // forgotten, so that no pose is interpolated between the two places.
  void jump(double t, const Pose2& pose);

  // The pose at t, linearly interpolated (angle along the shorter arc);
  // clamped to the oldest / newest entry outside the stored interval.
  // Identity when empty.
  Pose2 at(double t) const;

  bool empty() const { return entries_.empty(); }

 private:
  double span_;
  std::deque<std::pair<double, Pose2>> entries_;
};

}  // namespace sim
}  // namespace ekf_slam
