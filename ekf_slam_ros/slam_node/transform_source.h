// The node's view of tf: the buffer (filled by GuardedTfListener, which
// refuses future-stamped and invalid transforms) and lookups that say what
// is missing when they fail, for the drop messages of the input queue and
// the rear laser's merge.
#pragma once

#include <tf2_ros/buffer.h>

#include <optional>
#include <string>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_ros/slam_node/guarded_tf_listener.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {

class TransformSource {
 public:
  // `cache_time`: s of transforms buffered; `max_future`: s a transform may
  // lie ahead of the clock (the listener's gate).
  TransformSource(double cache_time, double max_future);

  // The transform target → source at `stamp`; false with a description of
  // what is missing (frames, how late) in `why`. `behind` (optional) is set
  // when the transform exists but its newest sample is older than `stamp`:
  // its publisher is alive and the scan waits for the next sample.
  bool lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
              Pose2* pose, std::string* why, bool* behind = nullptr) const;
  // The same for a laser's mount (3-D: upright, inverted, tilt).
  bool lookupMount(const std::string& target, const std::string& source, const ros::Time& stamp,
                   ros_conversions::LaserMount* mount, std::string* why) const;
  // The stamp of the newest target → source, if there is one.
  std::optional<ros::Time> latestStamp(const std::string& target, const std::string& source) const;
  // How far the data has come: the clock, or the newest target → source
  // (the odometry) received where that is ahead. The reference of the
  // scans' future-stamp rule: on a loaded machine the simulated clock lags
  // the log it comes from, and a stamp the odometry has reached is not in
  // the future.
  ros::Time dataTime(const std::string& target, const std::string& source) const;
  // s a stamp may lie ahead of dataTime(): max_future scaled by the clock's
  // rate against the wall clock (1 in real time, r for an r× replay).
  double futureTolerance() const { return listener_.futureTolerance(); }
  // The newest input stamp received, for the transforms' future-stamp rule.
  void noteInputStamp(const ros::Time& stamp) { listener_.noteInputStamp(stamp); }

  // For the message filters that wait on it.
  tf2_ros::Buffer& buffer() { return buffer_; }
  // Runs `f` while no transform enters the buffer (see GuardedTfListener).
  template <class F>
  void withInsertionsPaused(F&& f) {
    listener_.withInsertionsPaused(std::forward<F>(f));
  }
  void clear() { buffer_.clear(); }
  long refusedFuture() const { return listener_.refusedFuture(); }
  long refusedInvalid() const { return listener_.refusedInvalid(); }

 private:
  bool lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
              geometry_msgs::Transform* transform, std::string* why, bool* behind) const;

  double cache_time_;
  tf2_ros::Buffer buffer_;
  GuardedTfListener listener_;  // fills buffer_ from its own thread
};

}  // namespace ekf_slam
