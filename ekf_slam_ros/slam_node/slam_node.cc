#include "ekf_slam_ros/slam_node/slam_node.h"

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/OccupancyGrid.h>
#include <tf2/exceptions.h>

#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "ekf_slam_core/filter/chi_square.h"
#include "ekf_slam_core/io/grid_map_file.h"
#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_ros/conversions/grid_conversion.h"
#include "ekf_slam_ros/conversions/pose_conversion.h"
#include "ekf_slam_ros/conversions/scan_conversion.h"
#include "ekf_slam_ros/slam_node/slam_messages.h"

namespace ekf_slam {
namespace {

constexpr DropReason kAllReasons[] = {
    DropReason::kStampNotIncreasing,   DropReason::kStampInFuture,
    DropReason::kTooFewValidReadings,  DropReason::kBadScanGeometry,
    DropReason::kOdomTransformMissing, DropReason::kLaserTransformMissing,
    DropReason::kQueueOverflow,        DropReason::kPaused,
    DropReason::kBadFeatures,
};

using ros_conversions::fromPoseMessage;
using ros_conversions::fromTransformMessage;
using ros_conversions::toPoseMessage;

// The occupancy grid saved beside a landmark map: "office.yaml" →
// "office_grid.yaml" (+ "office_grid.pgm").
std::string gridPathFor(const std::string& landmark_path) {
  const std::string suffix = ".yaml";
  const bool yaml =
      landmark_path.size() > suffix.size() &&
      landmark_path.compare(landmark_path.size() - suffix.size(), suffix.size(), suffix) == 0;
  return (yaml ? landmark_path.substr(0, landmark_path.size() - suffix.size()) : landmark_path) +
         "_grid.yaml";
}

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

SlamNode::SlamNode(ros::NodeHandle node, ros::NodeHandle private_node, const SlamNodeParams& params,
                   const SlamConfig& config)
    : params_(params),
      config_(config),
      node_(node),
      private_node_(private_node),
      tf_listener_(tf_buffer_, params.max_future_stamp),
      diagnostics_(node, private_node) {
  for (DropReason reason : kAllReasons) drops_[reason] = 0;
  localize_only_ = params_.localize_only;
  paused_ = params_.start_paused;
  if (paused_) ROS_INFO("ekf_slam_node: started paused (start_paused): call ~resume to map");
  path_.header.frame_id = params_.map_frame;

  pose_publisher_ = node_.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", 10);
  path_publisher_ = node_.advertise<nav_msgs::Path>("path", 1, /*latch=*/true);
  odometry_path_publisher_ = node_.advertise<nav_msgs::Path>("odometry_path", 1, /*latch=*/true);
  odometry_path_.header.frame_id = params_.map_frame;
  landmarks_publisher_ = node_.advertise<visualization_msgs::MarkerArray>("landmarks", 1, true);
  landmark_map_publisher_ = node_.advertise<LandmarkMap>("landmark_map", 1, /*latch=*/true);
  association_publisher_ = node_.advertise<AssociationReport>("association", 10);
  smoothed_path_publisher_ = node_.advertise<nav_msgs::Path>("smoothed_path", 1, true);
  map_publisher_ = node_.advertise<nav_msgs::OccupancyGrid>("map", 1, /*latch=*/true);
  loop_closed_path_publisher_ = node_.advertise<nav_msgs::Path>("loop_closed_path", 1, true);
  if (params_.map_update_interval > 0.0 && config_.pipeline.loop_closure.enabled) {
    live_map_ = std::make_unique<LiveMapPublisher>(node_, config_.map);
    map_timer_ =
        node_.createTimer(ros::Duration(params_.map_update_interval), &SlamNode::onMapTimer, this);
  }

  services_.push_back(private_node_.advertiseService("pause", &SlamNode::onPause, this));
  services_.push_back(private_node_.advertiseService("resume", &SlamNode::onResume, this));
  services_.push_back(private_node_.advertiseService("reset", &SlamNode::onReset, this));
  services_.push_back(private_node_.advertiseService("smooth", &SlamNode::onSmooth, this));
  services_.push_back(private_node_.advertiseService("save_map", &SlamNode::onSaveMap, this));
  services_.push_back(private_node_.advertiseService("load_map", &SlamNode::onLoadMap, this));

  if (config_.laser_pose_given) laser_pose_ = config_.pipeline.filter.laser_pose;
  if (!params_.initial_map.empty()) {
    LandmarkMapFile map;
    const std::string error = readLandmarkMap(params_.initial_map, &map);
    if (!error.empty()) throw std::runtime_error("initial_map: " + error);
    seed_map_ = map;
    ROS_INFO("ekf_slam_node: %zu landmarks from %s%s", map.landmarks.size(),
             params_.initial_map.c_str(), localize_only_ ? " (localisation only)" : "");
  }

  diagnostics_.setHardwareID("ekf_slam");
  diagnostics_.add("EKF-SLAM", this, &SlamNode::diagnose);
  last_diagnostic_time_ = ros::WallTime::now();

  if (params_.input == "features") {
    input_subscriber_ = node_.subscribe(params_.features_topic, 50, &SlamNode::onFeatures, this);
  } else {
    input_subscriber_ = node_.subscribe(params_.scan_topic, 50, &SlamNode::onScan, this);
  }
  initial_pose_subscriber_ = node_.subscribe("initialpose", 2, &SlamNode::onInitialPose, this);
  tf_timer_ =
      node_.createTimer(ros::Duration(1.0 / params_.tf_publish_rate), &SlamNode::onTfTimer, this);
  // Scans waiting for a late transform are re-tried even when no new scan
  // arrives (e.g. the laser stops).
  drain_timer_ = node_.createTimer(ros::Duration(std::max(0.01, params_.tf_timeout / 4.0)),
                                   [this](const ros::TimerEvent&) { drainQueue(); });
  diagnostic_timer_ = node_.createTimer(ros::Duration(0.1),
                                        [this](const ros::TimerEvent&) { diagnostics_.update(); });
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
    queue_.clear();
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
  enqueue(std::move(pending));
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
  enqueue(std::move(pending));
}

void SlamNode::enqueue(PendingInput pending) {
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
  queue_.push_back(std::move(pending));
  while (static_cast<int>(queue_.size()) > params_.scan_queue_size) {
    const PendingInput& oldest = queue_.front();
    Pose2 unused;
    std::string why;
    std::ostringstream overflow;
    overflow.setf(std::ios::fixed);
    overflow.precision(3);
    overflow << "scan at " << oldest.header.stamp.toSec() << " still waiting for tf when "
             << params_.scan_queue_size << " newer scans arrived (scan_queue_size)";
    DropReason reason = DropReason::kQueueOverflow;
    if (!lookup(params_.odom_frame, params_.base_frame, oldest.header.stamp, &unused, &why)) {
      overflow << ": the odometry is silent, " << why;
      reason = DropReason::kOdomTransformMissing;
    }
    queue_.pop_front();
    drop(reason, overflow.str());
  }
  drainQueue();
}

bool SlamNode::lookup(const std::string& target, const std::string& source, const ros::Time& stamp,
                      Pose2* pose, std::string* why, bool* behind) const {
  if (behind) *behind = false;
  try {
    const geometry_msgs::TransformStamped t = tf_buffer_.lookupTransform(target, source, stamp);
    *pose = fromTransformMessage(t.transform);
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
        text << ": the scan is older than the transforms still buffered (" << e.what() << ")";
      }
    } catch (const tf2::TransformException&) {
      text << ": never received (" << e.what() << ")";
    }
    *why = text.str();
    return false;
  }
}

void SlamNode::drainQueue() {
  while (!queue_.empty()) {
    const PendingInput& pending = queue_.front();
    const ros::Time stamp = pending.header.stamp;
    const std::string& laser_frame = pending.header.frame_id;
    Pose2 odometry, laser;
    std::string odom_why, laser_why;
    bool odometry_behind = false;
    const bool have_odometry = lookup(params_.odom_frame, params_.base_frame, stamp, &odometry,
                                      &odom_why, &odometry_behind);
    const bool have_laser = lookup(params_.base_frame, laser_frame, stamp, &laser, &laser_why);
    if (have_odometry && have_laser) {
      const PendingInput input = std::move(queue_.front());
      queue_.pop_front();
      process(input, odometry, laser);
      continue;
    }
    // Odometry that is alive but paused (a log records only motion; a
    // driver that publishes on change) resumes with the next sample, which
    // the scan needs for its interpolated pose: wait, bounded by the queue.
    if (!have_odometry && odometry_behind && have_laser) return;
    const double waited = (ros::Time::now() - pending.received).toSec();
    if (waited < params_.tf_timeout && waited >= 0.0) return;  // wait for tf; order is kept
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
    queue_.pop_front();
    drop(reason, detail.str());
  }
}

SlamNode::StoredScan::StoredScan(const Scan& scan)
    : ranges(scan.ranges.begin(), scan.ranges.end()),
      angle_min(scan.angle_min),
      angle_increment(scan.angle_increment),
      range_min(scan.range_min),
      range_max(scan.range_max),
      stamp(scan.stamp) {}

Scan SlamNode::StoredScan::toScan() const {
  Scan scan;
  scan.ranges.assign(ranges.begin(), ranges.end());
  scan.angle_min = angle_min;
  scan.angle_increment = angle_increment;
  scan.range_min = range_min;
  scan.range_max = range_max;
  scan.stamp = stamp;
  return scan;
}

void SlamNode::createPipeline(const Pose2& laser_pose) {
  config_.pipeline.filter.laser_pose = laser_pose;
  laser_pose_ = laser_pose;
  PipelineOptions options = config_.pipeline;
  if (start_pose_) {
    options.initial_pose = *start_pose_;
    options.initial_pose_covariance = start_covariance_;
    start_pose_.reset();
  }
  pipeline_ = std::make_unique<SlamPipeline>(options);
  if (seed_map_) {
    int refused = 0;
    for (const LandmarkRecord& r : seed_map_->landmarks) {
      const FilterStatus status =
          pipeline_->mutableFilter().addLandmark(r.id, r.position, r.covariance, r.observations);
      if (status != FilterStatus::kOk) ++refused;
    }
    if (refused > 0) ROS_WARN("ekf_slam_node: %d landmarks of the loaded map refused", refused);
    seed_map_.reset();
  }
  pipeline_->mutableFilter().setMappingEnabled(!localize_only_);
}

void SlamNode::process(const PendingInput& pending, const Pose2& odometry, const Pose2& laser) {
  if (!pipeline_) {
    createPipeline(laser_pose_ ? *laser_pose_ : laser);
    laser_frame_ = pending.header.frame_id;
    ROS_INFO("ekf_slam_node: started; laser pose %s -> %s: %.3f m, %.3f m, %.2f deg%s",
             params_.base_frame.c_str(), laser_frame_.c_str(), laser_pose_->x, laser_pose_->y,
             radToDeg(laser_pose_->theta), config_.laser_pose_given ? " (configuration)" : " (tf)");
  } else if (!config_.laser_pose_given) {
    const Pose2 d = between(*laser_pose_, laser);
    if (std::hypot(d.x, d.y) > params_.laser_pose_tolerance ||
        std::abs(d.theta) > params_.laser_pose_tolerance) {
      ++laser_pose_changes_;
      ROS_WARN_THROTTLE(10.0,
                        "ekf_slam_node: %s -> %s changed by (%.3f m, %.3f m, %.2f deg) since "
                        "start; the filter keeps the pose it started with (reset to adopt it)",
                        params_.base_frame.c_str(), pending.header.frame_id.c_str(), d.x, d.y,
                        radToDeg(d.theta));
    }
  }

  const size_t records_before = pipeline_->scans().size();
  const ScanResult result = pending.scan ? pipeline_->processScan(*pending.scan, odometry)
                                         : pipeline_->processFeatures(pending.header.stamp.toSec(),
                                                                      *pending.features, odometry);
  if (pending.scan && pipeline_->scans().size() > records_before) {
    stored_scans_.emplace_back(*pending.scan);
  }
  if (!result.message.empty()) {
    ROS_WARN_THROTTLE(2.0, "ekf_slam_node: scan at %.3f %s: %s", pending.header.stamp.toSec(),
                      toString(result.outcome), result.message.c_str());
  }
  if (!odometry.allFinite()) return;

  const ros::Time stamp = pending.header.stamp;
  last_scan_stamp_ = stamp;
  // The causal estimate: with loop closure on, the loop-closed graph as it
  // stands after this scan (the filter is re-anchored to it after each
  // loop); otherwise the filter's.
  map_to_odom_ = compose(result.causal_pose, inverse(odometry));
  have_map_to_odom_ = true;
  publishMapToOdom(stamp);
  if (pipeline_->backEndOptimisations() != optimisations_published_) {
    optimisations_published_ = pipeline_->backEndOptimisations();
    publishLoopClosedPath(stamp);
  }

  std_msgs::Header map_header;
  map_header.stamp = stamp;
  map_header.frame_id = params_.map_frame;

  geometry_msgs::PoseWithCovarianceStamped pose;
  pose.header = map_header;
  pose.pose.pose = toPoseMessage(result.causal_pose);
  // Between iterations the covariance has grown with the motion since the
  // last one.
  ros_conversions::setPlanarCovariance(result.pose_covariance, &pose.pose.covariance);
  pose_publisher_.publish(pose);

  geometry_msgs::PoseStamped path_pose;
  path_pose.header = map_header;
  path_pose.pose = pose.pose.pose;
  path_.header.stamp = stamp;
  path_.poses.push_back(path_pose);
  // A long run's whole path re-sent every scan would cost megabytes per
  // message; the published path keeps the newest poses.
  if (params_.path_max_poses > 0 && static_cast<int>(path_.poses.size()) > params_.path_max_poses) {
    path_.poses.erase(path_.poses.begin(), path_.poses.end() - params_.path_max_poses);
  }
  path_publisher_.publish(path_);

  if (!odometry_anchor_) odometry_anchor_ = compose(result.causal_pose, inverse(odometry));
  geometry_msgs::PoseStamped odometry_pose;
  odometry_pose.header = map_header;
  odometry_pose.pose = toPoseMessage(compose(*odometry_anchor_, odometry));
  odometry_path_.header.stamp = stamp;
  odometry_path_.poses.push_back(odometry_pose);
  if (params_.path_max_poses > 0 &&
      static_cast<int>(odometry_path_.poses.size()) > params_.path_max_poses) {
    odometry_path_.poses.erase(odometry_path_.poses.begin(),
                               odometry_path_.poses.end() - params_.path_max_poses);
  }
  odometry_path_publisher_.publish(odometry_path_);

  if (result.outcome != ScanOutcome::kIterated) return;
  for (double nis : result.iteration.nis) {
    nis_window_.push_back(nis);
    if (static_cast<int>(nis_window_.size()) > params_.nis_window) nis_window_.pop_front();
  }
  if (landmarks_publisher_.getNumSubscribers() > 0) {
    landmarks_publisher_.publish(landmarkMarkers(pipeline_->filter(), &result.iteration, map_header,
                                                 params_.ellipse_probability));
  }
  publishLandmarkMap(map_header);
  std_msgs::Header laser_header = pending.header;
  association_publisher_.publish(
      toAssociationReport(result.observations, result.iteration, laser_header));
}

void SlamNode::publishLandmarkMap(const std_msgs::Header& header) {
  if (pipeline_) {
    landmark_map_publisher_.publish(toLandmarkMapMessage(pipeline_->filter(), header));
    return;
  }
  // No filter yet (before the first scan): the map waiting to seed it, or none.
  LandmarkMap message;
  message.header = header;
  if (seed_map_) {
    for (const LandmarkRecord& r : seed_map_->landmarks) {
      Landmark m;
      m.id = r.id;
      m.x = r.position.x();
      m.y = r.position.y();
      m.covariance = {r.covariance(0, 0), r.covariance(0, 1), r.covariance(1, 0),
                      r.covariance(1, 1)};
      m.observations = r.observations;
      m.tentative = r.observations <= 1;
      message.landmarks.push_back(m);
    }
  }
  landmark_map_publisher_.publish(message);
}

void SlamNode::publishMapToOdom(const ros::Time& data_stamp) {
  // Each stamp once (tf2 listeners warn about repeated data); stamped with
  // data time, future-dated by transform_tolerance so that consumers can
  // look up map → base_link until the next update (as amcl and gmapping do).
  if (!have_map_to_odom_ || data_stamp <= last_tf_stamp_) return;
  last_tf_stamp_ = data_stamp;
  geometry_msgs::TransformStamped t;
  t.header.stamp = data_stamp + ros::Duration(params_.transform_tolerance);
  t.header.frame_id = params_.map_frame;
  t.child_frame_id = params_.odom_frame;
  t.transform.translation.x = map_to_odom_.x;
  t.transform.translation.y = map_to_odom_.y;
  t.transform.rotation = ros_conversions::quaternionOfYaw(map_to_odom_.theta);
  tf_broadcaster_.sendTransform(t);
}

void SlamNode::onTfTimer(const ros::TimerEvent&) {
  // Between scans map → odom is constant; re-sent with the stamp of the
  // newest odom → base_link (data time), so map → base_link stays
  // available at the odometry's rate.
  if (!have_map_to_odom_) return;
  try {
    const ros::Time latest =
        tf_buffer_.lookupTransform(params_.odom_frame, params_.base_frame, ros::Time(0))
            .header.stamp;
    publishMapToOdom(latest);
  } catch (const tf2::TransformException&) {
    // No odometry at all right now: nothing newer to stamp with.
  }
}

void SlamNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const ros::WallTime now = ros::WallTime::now();
  const double period = (now - last_diagnostic_time_).toSec();
  const long iterations = pipeline_ ? pipeline_->counters().iterations : 0;
  const double rate =
      period > 0.0 ? std::max(0L, iterations - iterations_at_last_diagnostic_) / period : 0.0;
  iterations_at_last_diagnostic_ = iterations;
  last_diagnostic_time_ = now;

  long drops = 0;
  for (const auto& [reason, count] : drops_) {
    if (reason != DropReason::kPaused) drops += count;
  }
  const PipelineCounters counters = pipeline_ ? pipeline_->counters() : PipelineCounters{};
  const long pipeline_rejects = counters.time_not_increasing + counters.odometry_jumps +
                                counters.bad_input + counters.update_failures;
  drops += pipeline_rejects;

  double nis_average = 0.0;
  for (double nis : nis_window_) nis_average += nis;
  const int samples = static_cast<int>(nis_window_.size());
  if (samples > 0) nis_average /= samples;
  bool nis_inside = true;
  if (samples > 0) {
    const ChiSquareBand band = averageChiSquareBand(2.0, samples, 0.95);
    nis_inside = nis_average >= band.lower && nis_average <= band.upper;
    std::ostringstream text;
    text.precision(3);
    text << "[" << band.lower << ", " << band.upper << "]";
    status.add("NIS 95% band", text.str());
  } else {
    status.add("NIS 95% band", "no matches yet");
  }
  status.add("scan matches refused (disagree with the wheels)",
             counters.scan_match_odometry_refusals);
  status.add("scan matches refused (all reasons)", counters.scan_match_refusals);
  if (pipeline_ && pipeline_->loopCloser()) {
    const LoopClosureCounters& loops = pipeline_->loopCloser()->counters();
    status.add("key scans", loops.key_scans);
    status.add("loops accepted", loops.accepted);
    status.add("loop candidates refused", loops.refused);
    status.add("loops refused as inconsistent", loops.inconsistent);
    status.add("wide-window matches never confirmed", loops.unconfirmed);
    status.add("filter re-anchored", counters.reanchors);
  }
  if (live_map_) {
    status.add("maps published", live_map_->published());
    status.add("last map build [s]", live_map_->lastBuildSeconds());
  }

  if (paused_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "paused");
  } else if (drops > drops_at_last_diagnostic_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   std::to_string(drops - drops_at_last_diagnostic_) +
                       " inputs rejected since the last report (see counters)");
  } else if (!nis_inside) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "average NIS outside its 95% band (filter inconsistent)");
  } else if (!pipeline_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "waiting for the first scan");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "mapping");
  }
  drops_at_last_diagnostic_ = drops;

  status.add("paused", paused_);
  status.add("localize only", localize_only_);
  status.add("relocalisations (initialpose)", relocalisations_);
  status.add("scans received", scans_received_);
  status.add("scans processed", pipeline_ ? counters.scans : 0L);
  status.add("iterations", iterations);
  status.addf("iteration rate (Hz)", "%.2f", rate);
  status.add("landmarks", pipeline_ ? pipeline_->filter().landmarkCount() : 0);
  status.add("state size", pipeline_ ? pipeline_->filter().stateDim() : EkfSlam::kPoseDim);
  status.addf("NIS average", "%.3f", nis_average);
  status.add("NIS samples", samples);
  for (const auto& [reason, count] : drops_) {
    status.add(std::string("dropped: ") + toString(reason), count);
  }
  status.add("dropped tf: stamp in the future", tf_listener_.refusedFuture());
  status.add("dropped tf: invalid", tf_listener_.refusedInvalid());
  status.add("rejected by filter: time not increasing", counters.time_not_increasing);
  status.add("rejected by filter: odometry jump", counters.odometry_jumps);
  status.add("rejected by filter: bad input", counters.bad_input);
  status.add("rejected by filter: update refused", counters.update_failures);
  status.add("laser pose changes", laser_pose_changes_);
}

bool SlamNode::onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  paused_ = true;
  queue_.clear();
  response.success = true;
  response.message = "paused: scans are dropped until resume";
  ROS_INFO("ekf_slam_node: %s", response.message.c_str());
  return true;
}

bool SlamNode::onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  paused_ = false;
  response.success = true;
  response.message = "resumed";
  ROS_INFO("ekf_slam_node: resumed");
  return true;
}

void SlamNode::publishLoopClosedPath(const ros::Time& data_stamp) {
  nav_msgs::Path path;
  path.header.stamp = data_stamp;
  path.header.frame_id = params_.map_frame;
  for (const SlamPipeline::KeyScan& key : pipeline_->keyScans(/*with_points=*/false)) {
    geometry_msgs::PoseStamped p;
    p.header.stamp = ros::Time(key.stamp);
    p.header.frame_id = params_.map_frame;
    p.pose = toPoseMessage(key.pose);
    path.poses.push_back(p);
  }
  loop_closed_path_publisher_.publish(path);
}

// A new grid when the key scans changed (a new key scan or a new
// optimisation) and the worker is free; it never blocks the scans.
void SlamNode::onMapTimer(const ros::TimerEvent&) {
  if (!pipeline_ || !live_map_ || !laser_pose_ || hold_loaded_grid_) return;
  const long optimisations = pipeline_->backEndOptimisations();
  std::vector<SlamPipeline::KeyScan> keys = pipeline_->keyScans(/*with_points=*/true);
  if (keys.empty() ||
      (optimisations == optimisations_mapped_ && static_cast<int>(keys.size()) == keys_mapped_)) {
    return;
  }
  std_msgs::Header header;
  header.stamp = last_scan_stamp_;
  header.frame_id = params_.map_frame;
  const int count = static_cast<int>(keys.size());
  if (live_map_->submit(std::move(keys), *laser_pose_, header)) {
    optimisations_mapped_ = optimisations;
    keys_mapped_ = count;
  }
}

void SlamNode::resetState() {
  pipeline_.reset();
  optimisations_published_ = 0;
  optimisations_mapped_ = -1;
  keys_mapped_ = 0;
  if (!config_.laser_pose_given) laser_pose_.reset();  // looked up again at the next scan
  queue_.clear();
  last_accepted_stamp_.reset();
  stored_scans_.clear();
  path_.poses.clear();
  odometry_path_.poses.clear();
  odometry_anchor_.reset();
  nis_window_.clear();
  have_map_to_odom_ = false;
  iterations_at_last_diagnostic_ = 0;
  // drops_ stay: they count the node's inputs, not the map's history.
}

bool SlamNode::onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  resetState();
  seed_map_.reset();
  start_pose_.reset();
  node_grid_.reset();
  hold_loaded_grid_ = false;
  if (live_map_) live_map_->forget();
  localize_only_ = params_.localize_only;
  std_msgs::Header header;
  header.stamp = last_scan_stamp_;
  header.frame_id = params_.map_frame;
  publishLandmarkMap(header);
  path_.header.stamp = last_scan_stamp_;
  path_publisher_.publish(path_);
  response.success = true;
  response.message = "reset: empty map; the next scan starts a new one";
  ROS_INFO("ekf_slam_node: %s", response.message.c_str());
  return true;
}

bool SlamNode::onSaveMap(SaveMap::Request& request, SaveMap::Response& response) {
  if (request.path.empty()) {
    response.success = false;
    response.message = "path is empty";
    return true;
  }
  LandmarkMapFile map;
  if (pipeline_) {
    map = toLandmarkMapFile(pipeline_->filter(), params_.map_frame);
  } else if (seed_map_) {
    map = *seed_map_;
  } else {
    map.frame = params_.map_frame;
  }
  // The grid first: a failure leaves the landmark file as it was. Each file
  // is replaced atomically; a map saved without a grid drops the grid an
  // earlier save left at that path, so that a load never pairs the two.
  const std::string grid_path = gridPathFor(request.path);
  nav_msgs::OccupancyGrid grid;
  std::string grid_note;
  if (currentGrid(&grid) && grid.info.width > 0 && grid.info.height > 0) {
    const std::string error = writeGridMap(grid_path, ros_conversions::toGridMapFile(grid));
    if (!error.empty()) {
      response.success = false;
      response.message = error + " (nothing saved)";
      ROS_WARN("ekf_slam_node: save_map: %s", response.message.c_str());
      return true;
    }
    response.grid_path = grid_path;
    grid_note = " and the " + std::to_string(grid.info.width) + " x " +
                std::to_string(grid.info.height) + " occupancy grid to " + grid_path;
  } else {
    std::remove(grid_path.c_str());
    grid_note = "; no occupancy grid yet (nothing published on map)";
  }
  const std::string error = writeLandmarkMap(request.path, map);
  response.success = error.empty();
  response.message = error.empty() ? std::to_string(map.landmarks.size()) +
                                         " landmarks written to " + request.path + grid_note
                                   : error;
  ROS_INFO("ekf_slam_node: save_map: %s", response.message.c_str());
  return true;
}

bool SlamNode::onLoadMap(LoadMap::Request& request, LoadMap::Response& response) {
  response.success = false;
  response.landmarks = 0;
  auto refuse = [&](const std::string& problem) {
    response.message = problem + " (the current map is kept)";
    ROS_WARN("ekf_slam_node: load_map: %s", response.message.c_str());
    return true;
  };
  LandmarkMapFile map;
  std::string error = readLandmarkMap(request.path, &map);
  if (!error.empty()) return refuse(error);
  // The grid saved beside it, if there is one: a broken one refuses the load.
  const std::string grid_path = gridPathFor(request.path);
  std::optional<GridMapFile> grid;
  if (::access(grid_path.c_str(), F_OK) == 0) {
    grid.emplace();
    error = readGridMap(grid_path, &*grid);
    if (!error.empty()) return refuse(error);
  }
  Pose2 start;
  Matrix3 start_covariance = Matrix3::Zero();
  if (request.set_pose) {
    start = fromPoseMessage(request.pose.pose);
    start_covariance = ros_conversions::planarCovariance(request.pose.covariance);
  }
  if (map.frame != params_.map_frame) {
    ROS_WARN("ekf_slam_node: load_map: the file's frame '%s' differs from map_frame '%s'",
             map.frame.c_str(), params_.map_frame.c_str());
  }
  // The filter restarts at the given pose (the map origin by default) with
  // the loaded landmarks as a prior, uncorrelated with the pose.
  error = setStartPose(start, start_covariance);
  if (!error.empty()) return refuse("pose: " + error);
  resetState();
  seed_map_ = map;
  localize_only_ = request.localize_only;
  if (laser_pose_) createPipeline(*laser_pose_);
  std_msgs::Header header;
  header.stamp = last_scan_stamp_;
  header.frame_id = params_.map_frame;
  publishLandmarkMap(header);
  hold_loaded_grid_ = false;
  if (grid) {
    publishNodeGrid(ros_conversions::toOccupancyGridMessage(*grid, header));
    hold_loaded_grid_ = localize_only_;  // mapping on: the live map takes over
  }
  response.success = true;
  response.landmarks = static_cast<int>(map.landmarks.size());
  std::ostringstream text;
  text.setf(std::ios::fixed);
  text.precision(3);
  text << map.landmarks.size() << " landmarks loaded from " << request.path;
  if (grid) text << " and a " << grid->width << " x " << grid->height << " grid from " << grid_path;
  text << "; the robot starts at (" << start.x << ", " << start.y << ", " << radToDeg(start.theta)
       << " deg)" << (localize_only_ ? "; localisation only" : "; mapping continues");
  response.message = text.str();
  ROS_INFO("ekf_slam_node: load_map: %s", response.message.c_str());
  return true;
}

std::string SlamNode::setStartPose(const Pose2& pose, const Matrix3& covariance) {
  if (!pose.allFinite()) return "not finite";
  const Matrix3 symmetric = 0.5 * (covariance + covariance.transpose());
  if (!symmetric.allFinite() || !covariance.isApprox(covariance.transpose(), 1e-9) ||
      Eigen::SelfAdjointEigenSolver<Matrix3>(symmetric).eigenvalues().minCoeff() < 0.0) {
    return "the (x, y, yaw) covariance is not finite, symmetric and positive semi-definite";
  }
  PipelineOptions options = config_.pipeline;
  options.initial_pose = pose;
  options.initial_pose_covariance = symmetric;
  const std::string error = options.validate();
  if (!error.empty()) return error;
  start_pose_ = pose;
  start_covariance_ = symmetric;
  return "";
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
  if (pipeline_) prior = toLandmarkMapFile(pipeline_->filter(), params_.map_frame);
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

bool SlamNode::currentGrid(nav_msgs::OccupancyGrid* map) const {
  nav_msgs::OccupancyGrid live;
  std::chrono::steady_clock::time_point live_time;
  const bool have_live = live_map_ && live_map_->latest(&live, &live_time);
  if (node_grid_ && (!have_live || node_grid_time_ >= live_time)) {
    *map = *node_grid_;
    return true;
  }
  if (have_live) {
    *map = std::move(live);
    return true;
  }
  return false;
}

void SlamNode::publishNodeGrid(const nav_msgs::OccupancyGrid& map) {
  map_publisher_.publish(map);
  node_grid_ = map;
  node_grid_time_ = std::chrono::steady_clock::now();
}

bool SlamNode::onSmooth(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  if (!pipeline_ || pipeline_->scans().empty()) {
    response.success = false;
    response.message = "no scans processed yet";
    return true;
  }
  const std::vector<StampedPose> smoothed = pipeline_->smoothedScanPoses();
  std_msgs::Header header;
  header.stamp = last_scan_stamp_;
  header.frame_id = params_.map_frame;
  nav_msgs::Path path;
  path.header = header;
  OccupancyGrid grid(config_.map);
  for (size_t i = 0; i < smoothed.size(); ++i) {
    geometry_msgs::PoseStamped p;
    p.header.stamp = ros::Time(smoothed[i].stamp);
    p.header.frame_id = params_.map_frame;
    p.pose = toPoseMessage(smoothed[i].pose);
    path.poses.push_back(p);
    if (i < stored_scans_.size()) {
      grid.insertScan(compose(smoothed[i].pose, *laser_pose_), stored_scans_[i].toScan());
    }
  }
  smoothed_path_publisher_.publish(path);
  if (stored_scans_.empty()) {
    // input: features: the node never saw the ranges a grid is cast from.
    response.success = true;
    response.message = "smoothed " + std::to_string(smoothed.size()) +
                       " scan poses; no occupancy grid (input is features: no scans stored)";
    ROS_INFO("ekf_slam_node: smooth: %s", response.message.c_str());
    return true;
  }

  publishNodeGrid(toOccupancyGridMessage(grid, header));

  std::ostringstream text;
  text << "smoothed " << smoothed.size() << " scan poses (" << pipeline_->counters().iterations
       << " iterations); map " << grid.width() << " x " << grid.height() << " cells at "
       << grid.resolution() << " m";
  response.success = true;
  response.message = text.str();
  ROS_INFO("ekf_slam_node: smooth: %s", response.message.c_str());
  return true;
}

}  // namespace ekf_slam
