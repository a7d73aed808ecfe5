#include "ekf_slam_ros/slam_node/guarded_tf_listener.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace ekf_slam {

GuardedTfListener::GuardedTfListener(tf2_ros::Buffer& buffer, double max_future)
    : buffer_(buffer), max_future_(max_future) {
  node_.setCallbackQueue(&queue_);
  tf_subscriber_ = node_.subscribe<tf2_msgs::TFMessage>(
      "/tf", 100, [this](const tf2_msgs::TFMessage::ConstPtr& m) { onMessage(m, false); },
      ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  static_subscriber_ = node_.subscribe<tf2_msgs::TFMessage>(
      "/tf_static", 100, [this](const tf2_msgs::TFMessage::ConstPtr& m) { onMessage(m, true); });
  thread_ = std::thread([this] {
    while (running_ && node_.ok()) queue_.callAvailable(ros::WallDuration(0.01));
  });
}

GuardedTfListener::~GuardedTfListener() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

std::string GuardedTfListener::check(const geometry_msgs::TransformStamped& t, const ros::Time& now,
                                     const ros::Time& last, double max_future, bool is_static,
                                     bool* future) {
  if (future != nullptr) *future = false;
  const auto& p = t.transform.translation;
  const auto& q = t.transform.rotation;
  std::ostringstream why;
  why.setf(std::ios::fixed);
  why.precision(3);
  const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) &&
                      std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) &&
                      std::isfinite(q.w);
  const double norm2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
  if (!finite || std::abs(norm2 - 1.0) > 1e-3) {
    why << t.header.frame_id << " -> " << t.child_frame_id << " at " << t.header.stamp.toSec()
        << ": " << (finite ? "rotation is not a unit quaternion" : "non-finite value");
    return why.str();
  }
  const ros::Time reference = std::max(now, last);
  if (!is_static && !reference.isZero() && (t.header.stamp - reference).toSec() > max_future) {
    why << t.header.frame_id << " -> " << t.child_frame_id << " stamped " << t.header.stamp.toSec()
        << ", " << (t.header.stamp - now).toSec() << " s ahead of the clock and the scans "
        << now.toSec() << " and " << (t.header.stamp - last).toSec()
        << " s after the last accepted one "
        << "(max_future_stamp × the clock's rate: " << max_future << " s)";
    if (future != nullptr) *future = true;
    return why.str();
  }
  return "";
}

ros::Time GuardedTfListener::newestReceived(const std::string& parent,
                                            const std::string& child) const {
  const std::lock_guard<std::mutex> lock(received_mutex_);
  const auto found = last_received_.find({parent, child});
  return found == last_received_.end() ? ros::Time() : found->second;
}

void GuardedTfListener::onMessage(const tf2_msgs::TFMessage::ConstPtr& message, bool is_static) {
  ros::Time now = ros::Time::now();
  ros::Time newest_input;
  newest_input.fromNSec(newest_input_ns_.load());
  if (newest_input > now) now = newest_input;
  const std::string authority = "guarded listener";
  for (const geometry_msgs::TransformStamped& transform : message->transforms) {
    if (!is_static) {
      const std::lock_guard<std::mutex> lock(received_mutex_);
      ros::Time& received = last_received_[{transform.header.frame_id, transform.child_frame_id}];
      received = std::max(received, transform.header.stamp);
    }
    ros::Time& last = last_accepted_[{transform.header.frame_id, transform.child_frame_id}];
    bool future = false;
    const std::string problem = check(transform, now, last, futureTolerance(), is_static, &future);
    if (problem.empty()) {
      if (!is_static) last = std::max(last, transform.header.stamp);
      try {
        const std::lock_guard<std::mutex> lock(insertion_mutex_);
        buffer_.setTransform(transform, authority, is_static);
      } catch (const tf2::TransformException& e) {
        ROS_WARN_THROTTLE(5.0, "ekf_slam_node: tf refused a transform: %s", e.what());
      }
      continue;
    }
    (future ? refused_future_ : refused_invalid_)++;
    ROS_WARN_THROTTLE(1.0,
                      "ekf_slam_node: dropped a transform (%s): %s; the buffer keeps the "
                      "transforms before it (%ld future, %ld invalid dropped so far)",
                      future ? "tf stamp in the future" : "invalid tf", problem.c_str(),
                      refused_future_.load(), refused_invalid_.load());
  }
}

}  // namespace ekf_slam
