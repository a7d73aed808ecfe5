// ekf_slam_node's input side: the checks each scan or features message
// passes, its wait for the transforms (a tf2_ros::MessageFilter, bounded by
// tf_timeout for a missing transform), the tf lookups, the drop counters,
// and rviz's initial pose.
#include "ekf_slam_ros/slam_node/slam_node.h"

#include <geometry_msgs/TransformStamped.h>
#include <tf2/exceptions.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_ros/conversions/scan_conversion.h"
#include "ekf_slam_ros/slam_node/slam_messages.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace {

using ros_conversions::fromPoseMessage;
using ros_conversions::fromTransformMessage;

std::string withoutLeadingSlash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

}  // namespace

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
    case DropReason::kPaused:
      return "paused";
    case DropReason::kBadFeatures:
      return "bad features";
  }
  return "unknown";
}

void SlamNode::drop(DropReason reason, const std::string& detail) {
  const long count = ++drops_[reason];
  if (reason == DropReason::kPaused) {
    ROS_DEBUG_THROTTLE(5.0, "ekf_slam_node: paused, scan dropped");
    return;
  }
  // Throttled per reason (one flood must not hide another kind of fault),
  // at most one line per reason every log_throttle seconds, with the count
  // of those not printed in between.
  constexpr double kLogThrottle = 2.0;  // s, wall time
  const ros::WallTime now = ros::WallTime::now();
  auto last = last_drop_log_.find(reason);
  if (last != last_drop_log_.end() && (now - last->second.time).toSec() < kLogThrottle) {
    ++last->second.suppressed;
    return;
  }
  const long suppressed = last == last_drop_log_.end() ? 0 : last->second.suppressed;
  last_drop_log_[reason] = {now, 0};
  std::ostringstream line;
  line << "ekf_slam_node: dropped a scan (" << toString(reason) << "): " << detail << " (" << count
       << " dropped so far";
  if (suppressed > 0) line << ", " << suppressed << " not logged since the last line";
  line << ")";
  ROS_WARN("%s", line.str().c_str());
}

bool SlamNode::acceptingInput() {
  ++scans_received_;
  // A bag restarted (or looped) under use_sim_time: the clock runs backwards.
  // The tf buffer would refuse the old-new data; the map is kept (its stamps
  // now lie in the future), so scans are dropped as not increasing until
  // ~reset, which the log says.
  const ros::Time now = ros::Time::now();
  if (now + ros::Duration(1.0) < last_clock_) {
    ROS_WARN(
        "ekf_slam_node: the clock jumped back by %.3f s (bag restarted?): tf buffer "
        "cleared; call ~reset to start a new map from the new data",
        (last_clock_ - now).toSec());
    tf_buffer_.clear();
    clearWaiting();
    last_tf_stamp_ = ros::Time();  // map → odom goes out again with the new data's stamps
  }
  last_clock_ = now;
  if (paused_) {
    drop(DropReason::kPaused, "");
    return false;
  }
  return true;
}

void SlamNode::onScan(const sensor_msgs::LaserScan::ConstPtr& message) {
  if (!acceptingInput()) return;
  PendingInput pending;
  pending.header = message->header;
  pending.scan = ros_conversions::fromLaserScan(*message);
  pending.received = ros::Time::now();
  pending.message = message.get();
  std::ostringstream detail;
  detail.setf(std::ios::fixed);
  detail.precision(3);
  std::string geometry = ros_conversions::rangeCountError(*message);
  if (geometry.empty()) geometry = validateScan(*pending.scan);
  if (!geometry.empty()) {
    detail << "scan at " << message->header.stamp.toSec() << ": " << geometry;
    drop(DropReason::kBadScanGeometry, detail.str());
    return;
  }
  const int valid = countValidReadings(*pending.scan);
  if (valid < params_.min_valid_readings) {
    detail << "scan at " << message->header.stamp.toSec() << " has " << valid << " of "
           << pending.scan->size() << " readings usable (min_valid_readings "
           << params_.min_valid_readings << "); the map is not touched";
    drop(DropReason::kTooFewValidReadings, detail.str());
    return;
  }
  enqueue(std::move(pending), [this, message] { scan_filter_->add(message); });
}

void SlamNode::onFeatures(const Features::ConstPtr& message) {
  if (!acceptingInput()) return;
  PendingInput pending;
  pending.header = message->header;
  pending.received = ros::Time::now();
  FeatureSet features;
  std::string error;
  if (fromFeaturesMessage(*message, &features, &error)) error = validateFeatureSet(features);
  if (!error.empty()) {
    std::ostringstream detail;
    detail.setf(std::ios::fixed);
    detail.precision(3);
    detail << "features at " << message->header.stamp.toSec() << " on "
           << input_subscriber_.getTopic() << ": " << error << "; the map is not touched";
    drop(DropReason::kBadFeatures, detail.str());
    return;
  }
  pending.features = std::move(features);
  pending.message = message.get();
  enqueue(std::move(pending), [this, message] { features_filter_->add(message); });
}

void SlamNode::enqueue(PendingInput pending, const std::function<void()>& add) {
  const ros::Time stamp = pending.header.stamp;
  // A stamp far ahead of the clock (a driver's clock jump, a corrupt
  // header) must never become the reference later scans are compared
  // with: it would stop mapping until the clock caught up.
  const ros::Time now = ros::Time::now();
  if (!now.isZero() && (stamp - now).toSec() > params_.max_future_stamp) {
    std::ostringstream detail;
    detail.setf(std::ios::fixed);
    detail.precision(3);
    detail << "scan stamp " << stamp.toSec() << " is " << (stamp - now).toSec()
           << " s ahead of the clock " << now.toSec() << " (max_future_stamp "
           << params_.max_future_stamp << " s); the map is not touched";
    drop(DropReason::kStampInFuture, detail.str());
    return;
  }
  if (last_accepted_stamp_ && !(stamp > *last_accepted_stamp_)) {
    std::ostringstream detail;
    detail.setf(std::ios::fixed);
    detail.precision(3);
    detail << "scan stamp " << stamp.toSec() << " is " << (*last_accepted_stamp_ - stamp).toSec()
           << " s before or equal to the last accepted scan's " << last_accepted_stamp_->toSec()
           << "; the map is not touched";
    drop(DropReason::kStampNotIncreasing, detail.str());
    return;
  }
  last_accepted_stamp_ = stamp;
  // The filter drops its oldest input when scan_queue_size are waiting
  // (onTransformsFailed says why it was late).
  waiting_.push_back(std::move(pending));
  tf_listener_.withInsertionsPaused(add);
}

bool SlamNode::lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
                      Pose2* pose, std::string* why, bool* behind) const {
  if (behind) *behind = false;
  const auto attempt = [&]() {
    *pose = fromTransformMessage(tf_buffer_.lookupTransform(target, source, stamp).transform);
  };
  try {
    attempt();
    return true;
  } catch (const tf2::TransformException& e) {
    std::ostringstream text;
    text.setf(std::ios::fixed);
    text.precision(3);
    text << target << " -> " << source << " at " << stamp.toSec();
    // How late: the newest transform there is, if any.
    try {
      const ros::Time latest =
          tf_buffer_.lookupTransform(target, source, ros::Time(0)).header.stamp;
      if (latest.isZero()) {
        text << " (only a static transform? " << e.what() << ")";
      } else if (latest < stamp) {
        text << ": the newest is " << (stamp - latest).toSec() << " s older than the scan";
        if (behind) *behind = true;
      } else {
        // The tf listener runs on its own thread: the sample the first
        // attempt lacked (odometry resuming after a pause) may have arrived
        // since. Then the transform is there and nothing is missing.
        try {
          attempt();
          return true;
        } catch (const tf2::TransformException&) {
        }
        text << ": the scan is older than the transforms still buffered (" << e.what()
             << "); the buffer keeps tf_cache_time = " << params_.tf_cache_time
             << " s before the newest transform: a node that falls further behind (a replay at "
                "a high rate on a loaded machine) needs a longer one";
      }
    } catch (const tf2::TransformException&) {
      text << ": never received (" << e.what() << ")";
    }
    *why = text.str();
    return false;
  }
}

void SlamNode::onTransformsReady(const void* message) {
  const auto entry =
      std::find_if(waiting_.begin(), waiting_.end(),
                   [message](const PendingInput& p) { return p.message == message; });
  if (entry == waiting_.end()) return;  // cleared (reset, pause) after the filter let it through
  entry->ready = true;
  releaseInOrder();
}

void SlamNode::releaseInOrder() {
  // The filter answers each input on its own; the map takes them in the
  // order they arrived, so a ready input waits for the older ones.
  while (!waiting_.empty()) {
    if (waiting_.front().expired) {
      waiting_.pop_front();
      continue;
    }
    if (!waiting_.front().ready) return;
    const PendingInput pending = std::move(waiting_.front());
    waiting_.pop_front();
    processReleased(pending);
  }
}

void SlamNode::processReleased(const PendingInput& pending) {
  const ros::Time stamp = pending.header.stamp;
  std::ostringstream detail;
  detail.setf(std::ios::fixed);
  detail.precision(3);
  Pose2 odometry, laser;
  std::string why;
  if (!lookup(params_.odom_frame, params_.base_frame, stamp, &odometry, &why)) {
    detail << "scan at " << stamp.toSec() << ": " << why << "; the map is not touched";
    drop(DropReason::kOdomTransformMissing, detail.str());
    return;
  }
  if (!lookup(params_.base_frame, pending.header.frame_id, stamp, &laser, &why)) {
    detail << "scan at " << stamp.toSec() << ": " << why << "; the map is not touched";
    drop(DropReason::kLaserTransformMissing, detail.str());
    return;
  }
  if (!params_.rear_scan_topic.empty() && pending.scan) {
    processWithRear(pending, odometry, laser);
    return;
  }
  process(pending, odometry, laser);
}

void SlamNode::onTransformsFailed(const void* message, tf2_ros::FilterFailureReason reason) {
  const auto entry =
      std::find_if(waiting_.begin(), waiting_.end(),
                   [message](const PendingInput& p) { return p.message == message; });
  if (entry == waiting_.end()) return;
  if (entry->expired) {  // already dropped and counted
    waiting_.erase(entry);
    releaseInOrder();
    return;
  }
  entry->expired = true;  // dropped below; leaves the queue in order
  const PendingInput& pending = *entry;
  const ros::Time stamp = pending.header.stamp;
  std::ostringstream detail;
  detail.setf(std::ios::fixed);
  detail.precision(3);
  detail << "scan at " << stamp.toSec();
  if (reason == tf2_ros::filter_failure_reasons::EmptyFrameID) {
    detail << " has no frame_id; the map is not touched";
    drop(DropReason::kBadScanGeometry, detail.str());
    releaseInOrder();
    return;
  }
  if (reason == tf2_ros::filter_failure_reasons::OutTheBack) {
    detail << " is older than the transforms still buffered";
  } else {
    detail << " still waiting for tf when " << params_.scan_queue_size
           << " newer scans arrived (scan_queue_size)";
  }
  Pose2 unused;
  std::string why;
  DropReason drop_reason = DropReason::kQueueOverflow;
  if (!lookup(params_.odom_frame, params_.base_frame, stamp, &unused, &why)) {
    // Too old for the buffer: `why` says so. Overflow: the odometry paused.
    detail << (reason == tf2_ros::filter_failure_reasons::OutTheBack ? ": "
                                                                     : ": the odometry is silent, ")
           << why;
    drop_reason = DropReason::kOdomTransformMissing;
  } else if (!lookup(params_.base_frame, pending.header.frame_id, stamp, &unused, &why)) {
    detail << ": " << why;
    drop_reason = DropReason::kLaserTransformMissing;
  }
  detail << "; the map is not touched";
  drop(drop_reason, detail.str());
  releaseInOrder();
}

void SlamNode::expireWaiting() {
  for (PendingInput& pending : waiting_) {
    if (pending.expired) continue;
    const double waited = (ros::Time::now() - pending.received).toSec();
    if (waited < params_.tf_timeout && waited >= 0.0) continue;
    const ros::Time stamp = pending.header.stamp;
    Pose2 odometry, laser;
    std::string odom_why, laser_why;
    bool odometry_behind = false;
    const bool have_odometry = lookup(params_.odom_frame, params_.base_frame, stamp, &odometry,
                                      &odom_why, &odometry_behind);
    const bool have_laser =
        lookup(params_.base_frame, pending.header.frame_id, stamp, &laser, &laser_why);
    // Both there for tf_timeout and still no verdict from the filter: take
    // it as ready (its later verdict finds nothing to act on).
    if (have_odometry && have_laser) {
      pending.ready = true;
      continue;
    }
    // Odometry that is alive but paused (a log records only motion; a
    // driver that publishes on change) resumes with the next sample, which
    // the scan needs for its interpolated pose: wait, bounded by the queue.
    if (!have_odometry && odometry_behind && have_laser) continue;
    std::ostringstream detail;
    detail.setf(std::ios::fixed);
    detail.precision(3);
    detail << "scan at " << stamp.toSec() << " dropped after waiting " << waited
           << " s (tf_timeout " << params_.tf_timeout << " s) for ";
    const DropReason reason =
        have_odometry ? DropReason::kLaserTransformMissing : DropReason::kOdomTransformMissing;
    detail << (have_odometry ? laser_why : odom_why);
    if (!have_odometry && !have_laser) detail << "; also " << laser_why;
    detail << "; the map is not touched";
    // It stays in the filter (which cannot give up one message) until the
    // filter lets it go; it is counted now and ignored then.
    pending.expired = true;
    drop(reason, detail.str());
  }
  releaseInOrder();
}

void SlamNode::clearWaiting() {
  if (scan_filter_) scan_filter_->clear();
  if (features_filter_) features_filter_->clear();
  waiting_.clear();
}

void SlamNode::onInitialPose(const geometry_msgs::PoseWithCovarianceStamped& message) {
  if (withoutLeadingSlash(message.header.frame_id) != params_.map_frame) {
    ROS_WARN(
        "ekf_slam_node: initialpose in frame '%s' ignored: it must be given in '%s' (set "
        "rviz's fixed frame to it)",
        message.header.frame_id.c_str(), params_.map_frame.c_str());
    return;
  }
  const Pose2 pose = fromPoseMessage(message.pose.pose);
  const Matrix3 covariance = ros_conversions::planarCovariance(message.pose.covariance);
  // The landmarks mapped so far (or the map loaded and not yet used) stay,
  // as the prior of the restarted filter.
  std::optional<LandmarkMapFile> prior = seed_map_;
  if (pipeline_) prior = toLandmarkMapFile(pipeline_->filter(), lineSupport(), params_.map_frame);
  const std::string error = setStartPose(pose, covariance);
  if (!error.empty()) {
    ROS_WARN("ekf_slam_node: initialpose ignored: %s", error.c_str());
    return;
  }
  const Pose2 start = *start_pose_;
  const Matrix3 start_covariance = start_covariance_;
  resetState();
  seed_map_ = prior;
  if (laser_pose_) createPipeline(*laser_pose_);  // else at the next scan
  ++relocalisations_;
  ROS_INFO(
      "ekf_slam_node: initialpose: the filter restarts at (%.3f m, %.3f m, %.1f deg), "
      "sigma (%.3f m, %.3f m, %.1f deg), with %zu landmarks as its prior",
      start.x, start.y, radToDeg(start.theta), std::sqrt(start_covariance(0, 0)),
      std::sqrt(start_covariance(1, 1)), radToDeg(std::sqrt(start_covariance(2, 2))),
      prior ? prior->landmarks.size() : size_t{0});
}

}  // namespace ekf_slam
