#include "ekf_slam_ros/simulator/pose_history.h"

#include <algorithm>

namespace ekf_slam {
namespace sim {

void PoseHistory::add(double t, const Pose2& pose) {
  if (!entries_.empty() && t < entries_.back().first) return;
  entries_.emplace_back(t, pose);
  while (entries_.size() > 2 && entries_.front().first < t - span_) entries_.pop_front();
}

void PoseHistory::jump(double t, const Pose2& pose) {
  entries_.clear();
  entries_.emplace_back(t, pose);
}

Pose2 PoseHistory::at(double t) const {
  if (entries_.empty()) return Pose2();
  if (t <= entries_.front().first) return entries_.front().second;
  if (t >= entries_.back().first) return entries_.back().second;
  // First entry later than t; its predecessor is at or before t.
  const auto later = std::upper_bound(
      entries_.begin(), entries_.end(), t,
      [](double time, const std::pair<double, Pose2>& entry) { return time < entry.first; });
  const auto& [t1, p1] = *later;
  const auto& [t0, p0] = *(later - 1);
  const double f = t1 > t0 ? (t - t0) / (t1 - t0) : 1.0;
  return Pose2(p0.x + f * (p1.x - p0.x), p0.y + f * (p1.y - p0.y),
               p0.theta + f * wrapAngle(p1.theta - p0.theta));
}

}  // namespace sim
}  // namespace ekf_slam
