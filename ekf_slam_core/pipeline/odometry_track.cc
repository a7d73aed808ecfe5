#include "ekf_slam_core/pipeline/odometry_track.h"

#include <algorithm>
#include <cmath>

namespace ekf_slam {

void OdometryTrack::add(double stamp, const Pose2& pose) {
  if (!std::isfinite(stamp) || !pose.allFinite()) {
    ++dropped_;
    return;
  }
  samples_.push_back({stamp, pose});
}

void OdometryTrack::finalize() {
  std::stable_sort(samples_.begin(), samples_.end(),
                   [](const Sample& a, const Sample& b) { return a.stamp < b.stamp; });
}

OdometryTrack::Lookup OdometryTrack::poseAt(double stamp, double max_gap, Pose2* pose,
                                            double* distance) const {
  if (samples_.empty()) return Lookup::kNone;
  const auto upper = std::lower_bound(samples_.begin(), samples_.end(), stamp,
                                      [](const Sample& s, double t) { return s.stamp < t; });
  if (upper != samples_.end() && upper->stamp == stamp) {
    *pose = upper->pose;
    if (distance) *distance = 0.0;
    return Lookup::kInterpolated;
  }
  if (upper == samples_.begin() || upper == samples_.end()) {
    const Sample& only = upper == samples_.end() ? samples_.back() : samples_.front();
    *pose = only.pose;
    if (distance) *distance = std::abs(only.stamp - stamp);
    return Lookup::kNearest;
  }
  const Sample& b = *upper;
  const Sample& a = *(upper - 1);
  const double span = b.stamp - a.stamp;
  if (distance) *distance = std::min(stamp - a.stamp, b.stamp - stamp);
  if (span > max_gap) {
    *pose = (stamp - a.stamp) <= (b.stamp - stamp) ? a.pose : b.pose;
    return Lookup::kNearest;
  }
  const double f = span > 0.0 ? (stamp - a.stamp) / span : 0.0;
  *pose = Pose2(a.pose.x + f * (b.pose.x - a.pose.x), a.pose.y + f * (b.pose.y - a.pose.y),
                a.pose.theta + f * wrapAngle(b.pose.theta - a.pose.theta));
  return Lookup::kInterpolated;
}

}  // namespace ekf_slam
