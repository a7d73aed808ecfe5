// How fast the node's clock runs against the wall clock: 1 in real time,
// about r for a bag replayed at r× real time (use_sim_time). The future-stamp
// rules scale their tolerance by it: a thread the machine holds back for
// 50 ms lets a 20× replay's stamps run a second ahead of the node's view.
// Measured over windows of 2 s of wall time, between 1 and 1,000; a window
// starts anew while the clock is zero (sim time before the first /clock)
// or when it goes back. Any thread.
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
    if (window_wall_.isZero() || window_clock_.isZero() || clock < window_clock_) {
      window_wall_ = wall;
      window_clock_ = clock;
    } else if ((wall - window_wall_).toSec() >= kWindow) {
      rate_ = std::clamp((clock - window_clock_).toSec() / (wall - window_wall_).toSec(), 1.0,
                         kMaxRate);
      window_wall_ = wall;
      window_clock_ = clock;
    }
    return rate_;
  }

 private:
  static constexpr double kWindow = 2.0;      // s of wall time
  static constexpr double kMaxRate = 1000.0;  // a clock jump forward is not a rate
  std::mutex mutex_;
  ros::WallTime window_wall_;
  ros::Time window_clock_;
  double rate_ = 1.0;
};

}  // namespace ekf_slam
