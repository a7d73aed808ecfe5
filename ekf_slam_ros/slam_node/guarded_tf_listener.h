// A tf listener that refuses transforms the buffer must never hold.
//
// tf2's buffer keeps, per frame pair, the transforms of the last cache_time
// seconds before the NEWEST one it was given, and refuses anything older. A
// single odom → base_link stamped 10⁶ s ahead (a driver's clock jump, a
// corrupt header) therefore makes every later, correct transform "old
// data": the odometry is lost for 11 days. This listener is
// tf2_ros::TransformListener with a gate in front of the buffer: a
// transform on /tf stamped more than `max_future` seconds ahead of the
// node's clock (ros::Time::now(), sim time included; `max_future` scaled
// by the clock's rate against the wall clock, ClockRate), of the last
// transform accepted for the same frame pair and of the newest scan the
// node received (noteInputStamp), or with a non-finite or non-unit
// rotation, is refused, counted and logged (throttled) with its frames and
// stamp. The data's own time matters under sim time: on a loaded machine,
// or while a scan is being processed, a bag replayed fast lets the clock
// fall seconds behind transform and scan streams that are perfectly
// continuous; a stamp the other stream has reached is not in the future
// (the scans are checked against the odometry the same way, see
// newestReceived). /tf_static is time-independent and passes the
// finite-value check only.
#pragma once

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>

#include "ekf_slam_ros/slam_node/clock_rate.h"

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace ekf_slam {

class GuardedTfListener {
 public:
  // Subscribes to /tf and /tf_static and fills `buffer` from its own
  // thread, as tf2_ros::TransformListener does.
  GuardedTfListener(tf2_ros::Buffer& buffer, double max_future);
  ~GuardedTfListener();
  GuardedTfListener(const GuardedTfListener&) = delete;
  GuardedTfListener& operator=(const GuardedTfListener&) = delete;

  // Runs `f` while no transform enters the buffer. tf2_ros::MessageFilter::add
  // registers its transformable requests before it files the message; a
  // transform inserted in between (this listener's thread) answers the
  // request for a message the filter does not know yet, and the message
  // then waits until it is dropped. Adding under this lock closes that gap.
  template <class F>
  void withInsertionsPaused(F&& f) {
    const std::lock_guard<std::mutex> lock(insertion_mutex_);
    f();
  }

  // The newest scan (or features) stamp the node received: a reference
  // for the future check. Any thread.
  void noteInputStamp(const ros::Time& stamp) {
    uint64_t ns = stamp.toNSec();
    uint64_t seen = newest_input_ns_.load();
    while (ns > seen && !newest_input_ns_.compare_exchange_weak(seen, ns)) {
    }
  }
  // The newest stamp received for parent → child, accepted or refused
  // (zero: none). Any thread.
  ros::Time newestReceived(const std::string& parent, const std::string& child) const;

  // s a stamp may lie ahead of its references: max_future scaled by the
  // clock's rate (ClockRate). Any thread.
  double futureTolerance() const { return max_future_ * clock_rate_.rate(); }

  long refusedFuture() const { return refused_future_; }
  long refusedInvalid() const { return refused_invalid_; }

  // Empty when the transform may enter a buffer at time `now` (the clock or
  // the newest scan, the later), when
  // the last transform accepted for its frame pair was stamped `last` (zero:
  // none yet), else why not (names the frames and the stamp). The future
  // check is against the later of the two, and skipped while both are zero.
  // `future` (if given) says whether a refusal was for the stamp.
  static std::string check(const geometry_msgs::TransformStamped& transform, const ros::Time& now,
                           const ros::Time& last, double max_future, bool is_static,
                           bool* future = nullptr);

 private:
  void onMessage(const tf2_msgs::TFMessage::ConstPtr& message, bool is_static);

  tf2_ros::Buffer& buffer_;
  const double max_future_;
  ros::NodeHandle node_;
  ros::CallbackQueue queue_;
  ros::Subscriber tf_subscriber_, static_subscriber_;
  std::atomic<bool> running_{true};
  std::thread thread_;
  std::atomic<long> refused_future_{0}, refused_invalid_{0};
  std::mutex insertion_mutex_;  // held while a transform enters the buffer
  // Newest accepted stamp per (parent, child); used on the listener's thread only.
  std::map<std::pair<std::string, std::string>, ros::Time> last_accepted_;
  std::atomic<uint64_t> newest_input_ns_{0};
  mutable ClockRate clock_rate_;
  mutable std::mutex received_mutex_;
  std::map<std::pair<std::string, std::string>, ros::Time> last_received_;
};

}  // namespace ekf_slam
