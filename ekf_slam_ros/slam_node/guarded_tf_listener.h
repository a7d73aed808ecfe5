// A tf listener that refuses transforms the buffer must never hold.
//
// tf2's buffer keeps, per frame pair, the transforms of the last cache_time
// seconds before the NEWEST one it was given, and refuses anything older. A
// single odom → base_link stamped 10⁶ s ahead (a driver's clock jump, a
// corrupt header) therefore makes every later, correct transform "old
// data": the odometry is lost for 11 days. This listener is
// tf2_ros::TransformListener with a gate in front of the buffer: a
// transform on /tf stamped more than `max_future` seconds ahead of both the
// node's clock (ros::Time::now(), sim time included) and the last
// transform accepted for the same frame pair, or with a non-finite or
// non-unit rotation, is refused, counted and logged (throttled) with its
// frames and stamp. The frame pair's own history matters under sim time:
// the clock advances only when the node's main thread takes its /clock
// messages, so while a scan is being processed a bag replayed at 10× lets
// the clock fall a second behind a transform stream that is perfectly
// continuous. /tf_static is time-independent and passes the finite-value
// check only.
#pragma once

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>

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

  long refusedFuture() const { return refused_future_; }
  long refusedInvalid() const { return refused_invalid_; }

  // Empty when the transform may enter a buffer at clock time `now`, when
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
};

}  // namespace ekf_slam
