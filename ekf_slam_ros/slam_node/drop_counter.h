// Why the node did not use an input, and how often: one counter per
// DropReason (the `dropped: <reason>` keys on /diagnostics) and the
// warning logged for each drop, rate-limited per reason so that a flood
// of one kind of fault (a laser without tf) never hides another.
#pragma once

#include <ros/time.h>

#include <map>
#include <string>

namespace ekf_slam {

// Why an input was not used; each reason is a counter on /diagnostics.
enum class DropReason {
  kStampNotIncreasing,     // stamp not after the last accepted scan's
  kStampInFuture,          // stamp more than max_future_stamp ahead of the clock
  kTooFewValidReadings,    // NaN / no-return scan
  kBadScanGeometry,        // angle_increment 0, NaN angles, ...
  kOdomTransformMissing,   // odom → base_link never received within tf_timeout, or silent
                           // while scan_queue_size newer scans arrived
  kLaserTransformMissing,  // base_link → laser not available at the stamp within tf_timeout
  kQueueOverflow,          // more scans waiting for tf than scan_queue_size
  kSubscriberQueueFull,    // more than subscriber_queue_size arrived before the node took them
  kPaused,                 // the pause service was called
  kBadFeatures,            // a features message with unknown kinds or unusable values
  kLaserUpsideDown,        // features (input: features) from a laser mounted upside down
};
constexpr DropReason kAllDropReasons[] = {
    DropReason::kStampNotIncreasing,
    DropReason::kStampInFuture,
    DropReason::kTooFewValidReadings,
    DropReason::kBadScanGeometry,
    DropReason::kOdomTransformMissing,
    DropReason::kLaserTransformMissing,
    DropReason::kQueueOverflow,
    DropReason::kSubscriberQueueFull,
    DropReason::kPaused,
    DropReason::kBadFeatures,
    DropReason::kLaserUpsideDown,
};
const char* toString(DropReason reason);

class DropCounter {
 public:
  DropCounter();

  // Counts the drop and logs `detail` (paused: a debug line only).
  void drop(DropReason reason, const std::string& detail);
  // Every reason with its count, in the enum's order.
  const std::map<DropReason, long>& counts() const { return counts_; }
  // Drops of every reason but kPaused (a pause is asked for, not a fault).
  long faults() const;

 private:
  struct LastLine {
    ros::WallTime time;   // of the last line logged for the reason
    long suppressed = 0;  // drops not logged since
  };
  std::map<DropReason, long> counts_;
  std::map<DropReason, LastLine> last_line_;
};

}  // namespace ekf_slam
