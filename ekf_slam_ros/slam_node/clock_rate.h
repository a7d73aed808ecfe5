// How fast the node's clock runs against the wall clock: 1 in real time,
// about r for a bag replayed at r× real time (use_sim_time). The future-stamp
// rules scale their tolerance by it: a thread the machine holds back for
// 50 ms lets a 20× replay's stamps run a second ahead of the node's view.
// Measured over windows of 2 s of wall time; never below 1; a clock that
// goes back starts a new window. Any thread.
#pragma once

#include <ros/time.h>

#include <algorithm>
#include <mutex>

namespace ekf_slam {

class ClockRate {
 public:
  double rate() {
    const ros::WallTime wall = ros::WallTime::now();
    const ros::Time clock = ros::Time::now();
    const std::lock_guard<std::mutex> lock(mutex_);
    if (window_wall_.isZero() || clock < window_clock_) {
      window_wall_ = wall;
      window_clock_ = clock;
    } else if ((wall - window_wall_).toSec() >= kWindow) {
      rate_ = std::max(1.0, (clock - window_clock_).toSec() / (wall - window_wall_).toSec());
      window_wall_ = wall;
      window_clock_ = clock;
    }
    return rate_;
  }

 private:
  static constexpr double kWindow = 2.0;  // s of wall time
  std::mutex mutex_;
  ros::WallTime window_wall_;
  ros::Time window_clock_;
  double rate_ = 1.0;
};

}  // namespace ekf_slam
