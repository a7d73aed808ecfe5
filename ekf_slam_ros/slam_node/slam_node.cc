// ekf_slam_node: construction, the pipeline and the processing of one input.
// The node's other parts: slam_node_input.cc (the input queue and its tf
// waits), slam_node_outputs.cc (publishers and timers),
// slam_node_services.cc, slam_node_diagnostics.cc.
#include "ekf_slam_ros/slam_node/slam_node.h"

#include <chrono>
#include <cmath>

#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_ros/conversions/pose_conversion.h"
#include "ekf_slam_ros/conversions/scan_conversion.h"
#include "ekf_slam_ros/slam_node/slam_messages.h"

namespace ekf_slam {
namespace {

using ros_conversions::toPoseMessage;

}  // namespace

SlamNode::SlamNode(ros::NodeHandle node, ros::NodeHandle private_node, const SlamNodeParams& params,
                   const SlamConfig& config)
    : params_(params),
      config_(config),
      node_(node),
      private_node_(private_node),
      tf_buffer_(ros::Duration(params.tf_cache_time)),
      tf_listener_(tf_buffer_, params.max_future_stamp),
      diagnostics_(node, private_node) {
  for (DropReason reason : kAllDropReasons) drops_[reason] = 0;
  localize_only_ = params_.localize_only;
  paused_ = params_.start_paused;
  if (paused_) ROS_INFO("ekf_slam_node: started paused (start_paused): call ~resume to map");
  path_.header.frame_id = params_.map_frame;

  // One pose per scan: a node catching up after a stall (a loaded machine,
  // a replay) publishes them in bursts, which a slower subscriber (a
  // recorder, a Python tool) must still receive whole.
  pose_publisher_ = node_.advertise<geometry_msgs::PoseWithCovarianceStamped>("pose", 200);
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
  services_.push_back(private_node_.advertiseService("step", &SlamNode::onStep, this));
  services_.push_back(private_node_.advertiseService("reset", &SlamNode::onReset, this));
  services_.push_back(private_node_.advertiseService("smooth", &SlamNode::onSmooth, this));
  services_.push_back(private_node_.advertiseService("save_map", &SlamNode::onSaveMap, this));
  services_.push_back(private_node_.advertiseService("load_map", &SlamNode::onLoadMap, this));

  if (!params_.rear_scan_topic.empty()) {
    // The pipeline maps merged scans from a virtual laser at base_link; a
    // laser pose in the configuration is then the front laser's mount.
    if (config_.laser_pose_given) front_mount_ = config_.pipeline.filter.laser_pose;
    laser_pose_ = Pose2();
  } else if (config_.laser_pose_given) {
    laser_pose_ = config_.pipeline.filter.laser_pose;
  }
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

  // The transform wait: odom → laser at the input's stamp covers both
  // odom → base_link and base_link → laser. The filters' verdicts arrive
  // through node_'s callback queue, on the thread that runs the callbacks.
  const uint32_t queue_size = static_cast<uint32_t>(params_.scan_queue_size);
  if (params_.input == "features") {
    features_filter_ = std::make_unique<tf2_ros::MessageFilter<Features>>(
        tf_buffer_, params_.odom_frame, queue_size, node_);
    features_filter_->registerCallback(
        [this](const Features::ConstPtr& m) { onTransformsReady(m.get()); });
    features_filter_->registerFailureCallback(
        [this](const Features::ConstPtr& m, tf2_ros::FilterFailureReason reason) {
          onTransformsFailed(m.get(), reason);
        });
    input_subscriber_ = node_.subscribe(params_.features_topic, 50, &SlamNode::onFeatures, this);
  } else {
    scan_filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::LaserScan>>(
        tf_buffer_, params_.odom_frame, queue_size, node_);
    scan_filter_->registerCallback(
        [this](const sensor_msgs::LaserScan::ConstPtr& m) { onTransformsReady(m.get()); });
    scan_filter_->registerFailureCallback(
        [this](const sensor_msgs::LaserScan::ConstPtr& m, tf2_ros::FilterFailureReason reason) {
          onTransformsFailed(m.get(), reason);
        });
    input_subscriber_ = node_.subscribe(params_.scan_topic, 50, &SlamNode::onScan, this);
    if (!params_.rear_scan_topic.empty()) {
      rear_subscriber_ = node_.subscribe(params_.rear_scan_topic, 50, &SlamNode::onRearScan, this);
      ROS_INFO("ekf_slam_node: merging %s with the rear laser's %s (tolerance %.3f s)",
               input_subscriber_.getTopic().c_str(), rear_subscriber_.getTopic().c_str(),
               params_.rear_scan_tolerance);
    }
  }
  initial_pose_subscriber_ = node_.subscribe("initialpose", 2, &SlamNode::onInitialPose, this);
  tf_timer_ =
      node_.createTimer(ros::Duration(1.0 / params_.tf_publish_rate), &SlamNode::onTfTimer, this);
  // Inputs waiting for a missing transform are given up after tf_timeout
  // even when no new scan arrives (e.g. the laser stops).
  drain_timer_ = node_.createTimer(ros::Duration(std::max(0.01, params_.tf_timeout / 4.0)),
                                   [this](const ros::TimerEvent&) { expireWaiting(); });
  diagnostic_timer_ = node_.createTimer(ros::Duration(0.1),
                                        [this](const ros::TimerEvent&) { diagnostics_.update(); });
}

void SlamNode::createPipeline(const Pose2& laser_pose) {
  config_.pipeline.filter.laser_pose = laser_pose;
  laser_pose_ = laser_pose;
  PipelineOptions options = config_.pipeline;
  options.back_end_thread = true;  // scan processing never waits for a loop search
  // A node runs for hours: the history ~smooth re-solves is bounded, so
  // memory follows the map, not the time (the causal poses do not depend
  // on it). The offline runner keeps every scan: it writes one pose each.
  options.history_scans = params_.history_max_scans;
  // ~smooth draws its grid from the back end's key scans; without a back
  // end (loop closure off) the history keeps the scans' readings, and casts
  // those older than history_max_scans into a grid of its own.
  options.keep_readings = params_.input == "scan" && !config_.pipeline.loop_closure.enabled;
  options.readings_grid = config_.map;
  if (start_pose_) {
    options.initial_pose = *start_pose_;
    options.initial_pose_covariance = start_covariance_;
    start_pose_.reset();
  }
  pipeline_ = std::make_unique<SlamPipeline>(options);
  if (seed_map_) {
    std::unordered_map<int, LineSupport> support;
    const int refused = seedFilter(*seed_map_, &pipeline_->mutableFilter(), &support);
    pipeline_->seedLineSupport(support);
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
             radToDeg(laser_pose_->theta),
             !params_.rear_scan_topic.empty()
                 ? " (the merged front and rear scans' virtual laser)"
                 : (config_.laser_pose_given ? " (configuration)" : " (tf)"));
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

  const auto started = std::chrono::steady_clock::now();
  struct Timer {  // the whole of this function from here: pipeline and publication
    std::chrono::steady_clock::time_point start;
    ProcessingTimes* times;
    ~Timer() {
      times->add(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  } timer{started, processing_times_.get()};
  const ScanResult result = pending.scan ? pipeline_->processScan(*pending.scan, odometry)
                                         : pipeline_->processFeatures(pending.header.stamp.toSec(),
                                                                      *pending.features, odometry);
  if (step_pending_) {  // ~step: this was the one scan; pause until the next step
    step_pending_ = false;
    paused_ = true;
    ++steps_done_;
    clearWaiting();
    ROS_INFO("ekf_slam_node: step %ld: scan at %.3f %s; paused", steps_done_,
             pending.header.stamp.toSec(), toString(result.outcome));
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
  publishMapToOdom(stamp, /*new_estimate=*/true);
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
    landmarks_publisher_.publish(landmarkMarkers(pipeline_->filter(), lineSupport(),
                                                 &result.iteration, map_header,
                                                 params_.ellipse_probability));
  }
  publishLandmarkMap(map_header);
  std_msgs::Header laser_header = pending.header;
  association_publisher_.publish(
      toAssociationReport(result.observations, result.iteration, laser_header));
}

void SlamNode::resetState() {
  pipeline_.reset();
  optimisations_published_ = 0;
  optimisations_mapped_ = -1;
  keys_mapped_ = 0;
  if (!config_.laser_pose_given) laser_pose_.reset();  // looked up again at the next scan
  clearWaiting();
  last_accepted_stamp_.reset();
  step_pending_ = false;
  path_.poses.clear();
  odometry_path_.poses.clear();
  odometry_anchor_.reset();
  nis_window_.clear();
  have_map_to_odom_ = false;
  iterations_at_last_diagnostic_ = 0;
  // drops_ stay: they count the node's inputs, not the map's history.
}

}  // namespace ekf_slam
