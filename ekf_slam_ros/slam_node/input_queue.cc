#include "ekf_slam_ros/slam_node/input_queue.h"

#include <algorithm>
#include <sstream>

#include "ekf_slam_ros/conversions/scan_conversion.h"
#include "ekf_slam_ros/slam_node/slam_messages.h"

namespace ekf_slam {
namespace {

// The stream the drop messages are written to: three decimals.
std::ostringstream detailStream() {
  std::ostringstream detail;
  detail.setf(std::ios::fixed);
  detail.precision(3);
  return detail;
}

}  // namespace

InputQueue::InputQueue(ros::NodeHandle node, const SlamNodeParams& params,
                       TransformSource& transforms, DropCounter& drops, Hooks hooks)
    : params_(params), transforms_(transforms), drops_(drops), hooks_(std::move(hooks)) {
  // The transform wait: odom → laser at the input's stamp covers both
  // odom → base_link and base_link → laser. The filters' verdicts arrive
  // through node's callback queue, on the thread that runs the callbacks.
  const uint32_t queue_size = static_cast<uint32_t>(params_.scan_queue_size);
  if (params_.input == "features") {
    features_filter_ = std::make_unique<tf2_ros::MessageFilter<Features>>(
        transforms_.buffer(), params_.odom_frame, queue_size, node);
    features_filter_->registerCallback(
        [this](const Features::ConstPtr& m) { onTransformsReady(m.get()); });
    features_filter_->registerFailureCallback(
        [this](const Features::ConstPtr& m, tf2_ros::FilterFailureReason reason) {
          onTransformsFailed(m.get(), reason);
        });
    features_subscriber_ = std::make_unique<WatchedSubscriber<Features>>(
        node, params_.features_topic, params_.subscriber_queue_size,
        [this](const Features::ConstPtr& m) { onFeatures(m); }, [this](long n) { onDiscarded(n); });
  } else {
    scan_filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::LaserScan>>(
        transforms_.buffer(), params_.odom_frame, queue_size, node);
    scan_filter_->registerCallback(
        [this](const sensor_msgs::LaserScan::ConstPtr& m) { onTransformsReady(m.get()); });
    scan_filter_->registerFailureCallback(
        [this](const sensor_msgs::LaserScan::ConstPtr& m, tf2_ros::FilterFailureReason reason) {
          onTransformsFailed(m.get(), reason);
        });
    scan_subscriber_ = std::make_unique<WatchedSubscriber<sensor_msgs::LaserScan>>(
        node, params_.scan_topic, params_.subscriber_queue_size,
        [this](const sensor_msgs::LaserScan::ConstPtr& m) { onScan(m); },
        [this](long n) { onDiscarded(n); });
  }
  // Inputs waiting for a missing transform are given up after tf_timeout
  // even when no new scan arrives (e.g. the laser stops).
  drain_timer_ = node.createTimer(ros::Duration(std::max(0.01, params_.tf_timeout / 4.0)),
                                  [this](const ros::TimerEvent&) { expireWaiting(); });
}

std::string InputQueue::topic() const {
  return scan_subscriber_ ? scan_subscriber_->topic() : features_subscriber_->topic();
}

void InputQueue::onDiscarded(long count) {
  received_ += count;
  for (long i = 0; i < count; ++i) {
    std::ostringstream detail = detailStream();
    detail << "an input on " << topic() << " discarded unseen: " << params_.subscriber_queue_size
           << " newer ones arrived while the node was busy (subscriber_queue_size)";
    drops_.drop(DropReason::kSubscriberQueueFull, detail.str());
  }
}

bool InputQueue::accepting() {
  ++received_;
  // A bag restarted (or looped) under use_sim_time: the clock runs backwards.
  // The tf buffer would refuse the old-new data: it is emptied (the static
  // transforms stay), and the node restarts its map (clock_jump).
  const ros::Time now = ros::Time::now();
  if (now + ros::Duration(1.0) < last_clock_) {
    ROS_WARN(
        "ekf_slam_node: the clock jumped back by %.3f s (a bag restarted or looped?): tf "
        "buffer cleared",
        (last_clock_ - now).toSec());
    transforms_.clear();
    clear();
    hooks_.clock_jumped();
  }
  last_clock_ = now;
  if (hooks_.paused()) {
    drops_.drop(DropReason::kPaused, "");
    return false;
  }
  return true;
}

void InputQueue::onScan(const sensor_msgs::LaserScan::ConstPtr& message) {
  if (!accepting()) return;
  PendingInput pending;
  pending.header = message->header;
  pending.scan = ros_conversions::fromLaserScan(*message);
  pending.received = ros::Time::now();
  pending.message = message.get();
  std::ostringstream detail = detailStream();
  std::string geometry = ros_conversions::rangeCountError(*message);
  if (geometry.empty()) geometry = validateScan(*pending.scan);
  if (!geometry.empty()) {
    detail << "scan at " << message->header.stamp.toSec() << ": " << geometry;
    drops_.drop(DropReason::kBadScanGeometry, detail.str());
    return;
  }
  const int valid = countValidReadings(*pending.scan);
  if (valid < params_.min_valid_readings) {
    detail << "scan at " << message->header.stamp.toSec() << " has " << valid << " of "
           << pending.scan->size() << " readings usable (min_valid_readings "
           << params_.min_valid_readings << "); the map is not touched";
    drops_.drop(DropReason::kTooFewValidReadings, detail.str());
    return;
  }
  enqueue(std::move(pending), [this, message] { scan_filter_->add(message); });
}

void InputQueue::onFeatures(const Features::ConstPtr& message) {
  if (!accepting()) return;
  PendingInput pending;
  pending.header = message->header;
  pending.received = ros::Time::now();
  FeatureSet features;
  std::string error;
  if (fromFeaturesMessage(*message, &features, &error)) error = validateFeatureSet(features);
  if (!error.empty()) {
    std::ostringstream detail = detailStream();
    detail << "features at " << message->header.stamp.toSec() << " on " << topic() << ": " << error
           << "; the map is not touched";
    drops_.drop(DropReason::kBadFeatures, detail.str());
    return;
  }
  pending.features = std::move(features);
  pending.message = message.get();
  enqueue(std::move(pending), [this, message] { features_filter_->add(message); });
}

void InputQueue::enqueue(PendingInput pending, const std::function<void()>& add) {
  const ros::Time stamp = pending.header.stamp;
  // A stamp far ahead of the clock and of the odometry (a driver's clock
  // jump, a corrupt header) must never become the reference later scans
  // are compared with: it would stop mapping until the clock caught up.
  // The odometry's check takes the scans as its reference in turn, so that
  // two streams ahead of a lagging clock confirm each other.
  transforms_.noteInputStamp(stamp);
  // Its own stream counts too, as a transform's does: a scan just after the
  // last accepted one is not in the future.
  ros::Time reached = transforms_.dataTime(params_.odom_frame, params_.base_frame);
  if (last_accepted_stamp_ && *last_accepted_stamp_ > reached) reached = *last_accepted_stamp_;
  const double tolerance = transforms_.futureTolerance();
  if (!reached.isZero() && (stamp - reached).toSec() > tolerance) {
    std::ostringstream detail = detailStream();
    detail << "scan stamp " << stamp.toSec() << " is " << (stamp - reached).toSec()
           << " s ahead of the clock, the odometry and the last scan (" << reached.toSec()
           << "; max_future_stamp × the clock's rate: " << tolerance
           << " s); the map is not touched";
    drops_.drop(DropReason::kStampInFuture, detail.str());
    return;
  }
  if (last_accepted_stamp_ && !(stamp > *last_accepted_stamp_)) {
    std::ostringstream detail = detailStream();
    detail << "scan stamp " << stamp.toSec() << " is " << (*last_accepted_stamp_ - stamp).toSec()
           << " s before or equal to the last accepted scan's " << last_accepted_stamp_->toSec()
           << "; the map is not touched";
    drops_.drop(DropReason::kStampNotIncreasing, detail.str());
    return;
  }
  last_accepted_stamp_ = stamp;
  // The filter drops its oldest input when scan_queue_size are waiting
  // (onTransformsFailed says why it was late).
  waiting_.push_back(std::move(pending));
  transforms_.withInsertionsPaused(add);
}

std::deque<PendingInput>::iterator InputQueue::find(const void* message) {
  return std::find_if(waiting_.begin(), waiting_.end(),
                      [message](const PendingInput& p) { return p.message == message; });
}

void InputQueue::onTransformsReady(const void* message) {
  const auto entry = find(message);
  if (entry == waiting_.end()) return;  // cleared (reset, pause) after the filter let it through
  entry->ready = true;
  releaseInOrder();
}

void InputQueue::releaseInOrder() {
  // The filter answers each input on its own; the map takes them in the
  // order they arrived, so a ready input waits for the older ones.
  while (!waiting_.empty()) {
    if (waiting_.front().expired) {
      waiting_.pop_front();
      continue;
    }
    if (!waiting_.front().ready) return;
    PendingInput pending = std::move(waiting_.front());
    waiting_.pop_front();
    release(std::move(pending));
  }
}

void InputQueue::release(PendingInput pending) {
  const ros::Time stamp = pending.header.stamp;
  std::ostringstream detail = detailStream();
  Pose2 odometry;
  std::string why;
  if (!transforms_.lookup(params_.odom_frame, params_.base_frame, stamp, &odometry, &why)) {
    detail << "scan at " << stamp.toSec() << ": " << why << "; the map is not touched";
    drops_.drop(DropReason::kOdomTransformMissing, detail.str());
    return;
  }
  ros_conversions::LaserMount& mount = pending.mount;
  if (!transforms_.lookupMount(params_.base_frame, pending.header.frame_id, stamp, &mount, &why)) {
    detail << "scan at " << stamp.toSec() << ": " << why << "; the map is not touched";
    drops_.drop(DropReason::kLaserTransformMissing, detail.str());
    return;
  }
  if (mount.inverted && !pending.scan) {
    detail << "features at " << stamp.toSec() << ": " << params_.base_frame << " -> "
           << pending.header.frame_id
           << " is upside down (its z axis points down); features extracted from such a scan "
              "see the world mirrored: use input: scan, which mirrors the scan first";
    drops_.drop(DropReason::kLaserUpsideDown, detail.str());
    return;
  }
  if (mount.inverted) pending.scan = mirroredScan(*pending.scan);
  // A tilted laser's beams, projected into the floor plane (features
  // extracted elsewhere come as they are: level them there).
  if (pending.scan && (mount.scan_roll != 0.0 || mount.scan_pitch != 0.0)) {
    pending.scan = levelledScan(*pending.scan, mount.scan_roll, mount.scan_pitch);
  }
  hooks_.released(pending, odometry, mount.pose);
}

void InputQueue::onTransformsFailed(const void* message, tf2_ros::FilterFailureReason reason) {
  const auto entry = find(message);
  if (entry == waiting_.end()) return;
  if (entry->expired) {  // already dropped and counted
    waiting_.erase(entry);
    releaseInOrder();
    return;
  }
  entry->expired = true;  // dropped below; leaves the queue in order
  const PendingInput& pending = *entry;
  const ros::Time stamp = pending.header.stamp;
  std::ostringstream detail = detailStream();
  detail << "scan at " << stamp.toSec();
  if (reason == tf2_ros::filter_failure_reasons::EmptyFrameID) {
    detail << " has no frame_id; the map is not touched";
    drops_.drop(DropReason::kBadScanGeometry, detail.str());
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
  if (!transforms_.lookup(params_.odom_frame, params_.base_frame, stamp, &unused, &why)) {
    // Too old for the buffer: `why` says so. Overflow: the odometry paused.
    detail << (reason == tf2_ros::filter_failure_reasons::OutTheBack ? ": "
                                                                     : ": the odometry is silent, ")
           << why;
    drop_reason = DropReason::kOdomTransformMissing;
  } else if (!transforms_.lookup(params_.base_frame, pending.header.frame_id, stamp, &unused,
                                 &why)) {
    detail << ": " << why;
    drop_reason = DropReason::kLaserTransformMissing;
  }
  detail << "; the map is not touched";
  drops_.drop(drop_reason, detail.str());
  releaseInOrder();
}

void InputQueue::expireWaiting() {
  for (PendingInput& pending : waiting_) {
    if (pending.expired) continue;
    const double waited = (ros::Time::now() - pending.received).toSec();
    if (waited < params_.tf_timeout && waited >= 0.0) continue;
    const ros::Time stamp = pending.header.stamp;
    Pose2 odometry, laser;
    std::string odom_why, laser_why;
    bool odometry_behind = false;
    const bool have_odometry = transforms_.lookup(params_.odom_frame, params_.base_frame, stamp,
                                                  &odometry, &odom_why, &odometry_behind);
    const bool have_laser =
        transforms_.lookup(params_.base_frame, pending.header.frame_id, stamp, &laser, &laser_why);
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
    std::ostringstream detail = detailStream();
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
    drops_.drop(reason, detail.str());
  }
  releaseInOrder();
}

void InputQueue::clear() {
  if (scan_filter_) scan_filter_->clear();
  if (features_filter_) features_filter_->clear();
  waiting_.clear();
}

}  // namespace ekf_slam
