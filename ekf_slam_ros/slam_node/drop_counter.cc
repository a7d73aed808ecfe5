#include "ekf_slam_ros/slam_node/drop_counter.h"

#include <ros/console.h>

#include <sstream>

namespace ekf_slam {

const char* toString(DropReason reason) {
  switch (reason) {
    case DropReason::kStampNotIncreasing:
      return "stamp not increasing";
    case DropReason::kStampInFuture:
      return "stamp in the future";
    case DropReason::kTooFewValidReadings:
      return "too few valid readings";
    case DropReason::kBadScanGeometry:
      return "bad scan geometry";
    case DropReason::kOdomTransformMissing:
      return "odom transform missing";
    case DropReason::kLaserTransformMissing:
      return "laser transform missing";
    case DropReason::kQueueOverflow:
      return "queue overflow";
    case DropReason::kSubscriberQueueFull:
      return "subscriber queue full";
    case DropReason::kPaused:
      return "paused";
    case DropReason::kBadFeatures:
      return "bad features";
    case DropReason::kLaserUpsideDown:
      return "features from an upside-down laser";
  }
  return "unknown";
}

DropCounter::DropCounter() {
  for (DropReason reason : kAllDropReasons) counts_[reason] = 0;
}

long DropCounter::faults() const {
  long total = 0;
  for (const auto& [reason, count] : counts_) {
    if (reason != DropReason::kPaused) total += count;
  }
  return total;
}

void DropCounter::drop(DropReason reason, const std::string& detail) {
  const long count = ++counts_[reason];
  if (reason == DropReason::kPaused) {
    ROS_DEBUG_THROTTLE(5.0, "ekf_slam_node: paused, scan dropped");
    return;
  }
  // Throttled per reason (one flood must not hide another kind of fault),
  // at most one line per reason every log_throttle seconds, with the count
  // of those not printed in between.
  constexpr double kLogThrottle = 2.0;  // s, wall time
  const ros::WallTime now = ros::WallTime::now();
  auto last = last_line_.find(reason);
  if (last != last_line_.end() && (now - last->second.time).toSec() < kLogThrottle) {
    ++last->second.suppressed;
    return;
  }
  const long suppressed = last == last_line_.end() ? 0 : last->second.suppressed;
  last_line_[reason] = {now, 0};
  std::ostringstream line;
  line << "ekf_slam_node: dropped a scan (" << toString(reason) << "): " << detail << " (" << count
       << " dropped so far";
  if (suppressed > 0) line << ", " << suppressed << " not logged since the last line";
  line << ")";
  ROS_WARN("%s", line.str().c_str());
}

}  // namespace ekf_slam
