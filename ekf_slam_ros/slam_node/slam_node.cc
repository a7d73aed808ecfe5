#include "ekf_slam_ros/slam_node/slam_node.h"

#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>

#include "ekf_slam_core/io/grid_map_file.h"
#include "ekf_slam_core/io/map_set.h"
#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_ros/conversions/grid_conversion.h"

namespace ekf_slam {
namespace {

// The landmark map named by initial_map, if any (a bad file stops the node).
std::optional<LandmarkMapFile> initialMap(const SlamNodeParams& params) {
  if (params.initial_map.empty()) return std::nullopt;
  std::string error = finishInterruptedMapSave(params.initial_map);
  LandmarkMapFile map;
  if (error.empty()) error = readLandmarkMap(params.initial_map, &map);
  if (!error.empty()) throw std::runtime_error("initial_map: " + error);
  ROS_INFO("ekf_slam_node: %zu landmarks from %s%s", map.landmarks.size(),
           params.initial_map.c_str(), params.localize_only ? " (localisation only)" : "");
  return map;
}

// The grid saved beside initial_map, if there is one (a bad one stops the
// node; initialMap has completed an interrupted save of the set).
std::optional<GridMapFile> initialGrid(const SlamNodeParams& params) {
  if (params.initial_map.empty()) return std::nullopt;
  const std::string path = mapSetPaths(params.initial_map).grid;
  if (::access(path.c_str(), F_OK) != 0) return std::nullopt;
  GridMapFile grid;
  const std::string error = readGridMap(path, &grid);
  if (!error.empty()) throw std::runtime_error("initial_map: " + error);
  return grid;
}

// The laser pose the pipeline starts with, when known before the first
// scan: with a rear laser the merged scans' virtual laser at base_link
// (a laser pose in the configuration is then the front laser's mount);
// else the configuration's, if it gives one (else tf at the first scan).
std::optional<Pose2> knownLaserPose(const SlamNodeParams& params, const SlamConfig& config) {
  if (!params.rear_scan_topic.empty()) return Pose2();
  if (config.laser_pose_given) return config.pipeline.filter.laser_pose;
  return std::nullopt;
}

// With a rear laser: the front laser's mount from the configuration, if it
// gives one (else tf gives it per scan).
std::optional<Pose2> frontMount(const SlamConfig& config) {
  if (!config.laser_pose_given) return std::nullopt;
  return config.pipeline.filter.laser_pose;
}

// Whether the history keeps the scans' readings: ~smooth draws its grid
// from the back end's key scans, and without a back end (loop closure off)
// from the readings; features from feature_node carry none.
bool keepsReadings(const SlamNodeParams& params, const SlamConfig& config) {
  return params.input == "scan" && !config.pipeline.loop_closure.enabled;
}

// A live map on `map`: from the key scans, else from the kept readings.
bool liveMap(const SlamNodeParams& params, const SlamConfig& config) {
  return params.map_update_interval > 0.0 &&
         (config.pipeline.loop_closure.enabled || keepsReadings(params, config));
}

}  // namespace

SlamNode::SlamNode(ros::NodeHandle node, ros::NodeHandle private_node, const SlamNodeParams& params,
                   const SlamConfig& config)
    : params_(params),
      config_(config),
      transforms_(params.tf_cache_time, params.max_future_stamp),
      laser_pose_(knownLaserPose(params, config)),
      seed_map_(initialMap(params)),
      localize_only_(params.localize_only),
      outputs_(node, params_),
      map_to_odom_(node, params_, transforms_),
      grids_(node, params_, config_.map, liveMap(params_, config_), *this),
      services_(node, private_node, params_, config_.map, *this, outputs_, grids_),
      input_(node, params_, transforms_, drops_,
             {[this] { return services_.paused(); }, [this] { onClockJump(); },
              [this](const PendingInput& pending, const Pose2& odometry, const Pose2& laser) {
                onReleased(pending, odometry, laser);
              }}),
      rear_(params_.rear_scan_topic.empty()
                ? nullptr
                : std::make_unique<RearScanMerger>(node, params_, frontMount(config_), transforms_,
                                                   drops_, input_.topic())),
      relocaliser_(config_.pipeline.scan_matching, GlobalLocalizationOptions()),
      diagnostics_(
          node, private_node, params_, config_.pipeline,
          {this, &drops_, &transforms_, &input_, rear_.get(), &grids_, &services_, &relocaliser_}) {
  // The saved grid stays on `map` while localising; when mapping, the live
  // grid replaces it.
  if (const std::optional<GridMapFile> grid = initialGrid(params_)) {
    std_msgs::Header header;
    header.stamp = ros::Time::now();
    header.frame_id = params_.map_frame;
    grids_.publish(ros_conversions::toOccupancyGridMessage(*grid, header));
    grids_.hold(localize_only_);
  }
  const Pose2 start(params_.initial_pose_x, params_.initial_pose_y, params_.initial_pose_a);
  const Matrix3 covariance =
      Vector3(params_.initial_cov_xx, params_.initial_cov_yy, params_.initial_cov_aa).asDiagonal();
  if (start.translation().norm() > 0.0 || start.theta != 0.0 || !covariance.isZero()) {
    const std::string error = setStartPose(start, covariance);
    if (!error.empty()) throw std::runtime_error("initial_pose: " + error);
    ROS_INFO(
        "ekf_slam_node: starts at (%.3f m, %.3f m, %.2f deg), sigma (%.3f m, %.3f m, %.2f deg)",
        start.x, start.y, radToDeg(start.theta), std::sqrt(params_.initial_cov_xx),
        std::sqrt(params_.initial_cov_yy), radToDeg(std::sqrt(params_.initial_cov_aa)));
  }
  if (!params_.initial_state.empty()) {
    SlamState state;
    std::string error = readSlamState(params_.initial_state, &state);
    const int landmarks = state.filter.landmarkCount();
    const size_t keys = state.back_end.closer.keys.size();
    if (error.empty()) error = resumeFrom(std::move(state), localize_only_);
    if (!error.empty()) throw std::runtime_error("initial_state: " + error);
    ROS_INFO("ekf_slam_node: %d landmarks and %zu key scans from %s%s", landmarks, keys,
             params_.initial_state.c_str(),
             localize_only_ ? " (localisation only; a lost robot is searched for)" : "");
  }
  if (params_.map_update_interval > 0.0 && !liveMap(params_, config_)) {
    ROS_INFO(
        "ekf_slam_node: no live grid on `map`: features carry no readings and loop closure "
        "(whose key scans would give one) is off");
  }
}

void SlamNode::onReleased(const PendingInput& pending, const Pose2& odometry, const Pose2& laser) {
  if (!rear_ || !pending.scan) {
    process(pending, odometry, laser);
    return;
  }
  // The pipeline maps the merged 360° scan from a laser at base_link.
  const std::optional<PendingInput> merged = rear_->merge(pending, odometry, laser);
  if (merged) process(*merged, odometry, Pose2());
}

void SlamNode::ensurePipeline(const PendingInput& pending, const Pose2& laser) {
  if (!pipeline_) {
    createPipeline(laser_pose_ ? *laser_pose_ : laser);
    ROS_INFO(
        "ekf_slam_node: started; laser pose %s -> %s: %.3f m, %.3f m, "
        "%.2f deg%s%s",
        params_.base_frame.c_str(), pending.header.frame_id.c_str(), laser_pose_->x, laser_pose_->y,
        radToDeg(laser_pose_->theta),
        pending.mount.inverted ? ", upside down (each scan is mirrored)" : "",
        !params_.rear_scan_topic.empty()
            ? " (the merged front and rear scans' virtual laser)"
            : (config_.laser_pose_given ? " (configuration)" : " (tf)"));
    return;
  }
  if (config_.laser_pose_given) return;
  const Pose2 d = between(*laser_pose_, laser);
  if (std::hypot(d.x, d.y) > params_.laser_pose_tolerance ||
      std::abs(d.theta) > params_.laser_pose_tolerance) {
    diagnostics_.countLaserPoseChange();
    ROS_WARN_THROTTLE(10.0,
                      "ekf_slam_node: %s -> %s changed by (%.3f m, %.3f m, %.2f deg) since "
                      "start; the filter keeps the pose it started with (reset to adopt it)",
                      params_.base_frame.c_str(), pending.header.frame_id.c_str(), d.x, d.y,
                      radToDeg(d.theta));
  }
}

PipelineOptions SlamNode::liveOptions(const Pose2& laser_pose) const {
  PipelineOptions options = config_.pipeline;
  options.filter.laser_pose = laser_pose;
  options.back_end_thread = true;  // scan processing never waits for a loop search
  // A node runs for hours: the history ~smooth re-solves is bounded, so
  // memory follows the map, not the time (the causal poses do not depend
  // on it). The offline runner keeps every scan: it writes one pose each.
  options.history_scans = params_.history_max_scans;
  // Without a back end the history keeps the scans' readings for the live
  // map and ~smooth, and casts those older than history_max_scans into a
  // grid of its own.
  options.keep_readings = keepsReadings(params_, config_);
  options.readings_grid = config_.map;
  return options;
}

void SlamNode::createPipeline(const Pose2& laser_pose) {
  config_.pipeline.filter.laser_pose = laser_pose;
  laser_pose_ = laser_pose;
  PipelineOptions options = liveOptions(laser_pose);
  if (seed_state_) {
    // A state loaded before the laser pose was known.
    pipeline_ = std::make_unique<SlamPipeline>(options);
    const std::string error = pipeline_->resume(*seed_state_);
    if (error.empty()) {
      pipeline_->mutableFilter().setMappingEnabled(!localize_only_);
      watchForLoss(std::move(*seed_state_));
      seed_state_.reset();
      ROS_INFO("ekf_slam_node: load_state: going on from the loaded state");
      return;
    }
    seed_state_.reset();
    ROS_ERROR("ekf_slam_node: load_state: %s; a new map instead", error.c_str());
  }
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
  ensurePipeline(pending, laser);
  diagnostics_.noteLaserMount(pending.header.frame_id, pending.mount);
  if (pending.mount.tilt > params_.max_laser_tilt) {
    ROS_WARN_THROTTLE(30.0,
                      "ekf_slam_node: %s -> %s is tilted %.1f deg from level (roll %.1f, pitch "
                      "%.1f deg; max_laser_tilt %.1f deg): each scan is levelled, but beams "
                      "this steep meet the floor and furniture below the walls; fix the mount "
                      "or its transform",
                      params_.base_frame.c_str(), pending.header.frame_id.c_str(),
                      radToDeg(pending.mount.tilt), radToDeg(pending.mount.roll),
                      radToDeg(pending.mount.pitch), radToDeg(params_.max_laser_tilt));
  }
  // Times the rest of this function: the pipeline and the publication.
  const SlamDiagnostics::Timing timing = diagnostics_.timeProcessing();
  const ros::Time stamp = pending.header.stamp;
  if (pending.scan && odometry.allFinite()) {
    if (const std::optional<GlobalPlacement> place = relocaliser_.takeFound(odometry)) {
      relocate(*place);
    }
  }
  const ScanResult result =
      pending.scan ? pipeline_->processScan(*pending.scan, odometry)
                   : pipeline_->processFeatures(stamp.toSec(), *pending.features, odometry);
  services_.afterScan(stamp, result.outcome);
  if (!result.message.empty()) {
    ROS_WARN_THROTTLE(2.0, "ekf_slam_node: scan at %.3f %s: %s", stamp.toSec(),
                      toString(result.outcome), result.message.c_str());
  }
  if (!odometry.allFinite()) return;
  last_scan_stamp_ = stamp;
  // The causal estimate: with loop closure on, the loop-closed graph as it
  // stands after this scan (the filter is re-anchored to it after each
  // loop); otherwise the filter's.
  map_to_odom_.update(compose(result.causal_pose, inverse(odometry)), stamp);
  if (result.outcome == ScanOutcome::kIterated) diagnostics_.addIteration(result);
  outputs_.publishScan(result, odometry, *pipeline_, pending.header);
  if (pending.scan && relocaliser_.watching() &&
      (result.outcome == ScanOutcome::kIterated ||
       result.outcome == ScanOutcome::kSkippedNoMotion)) {
    relocaliser_.afterScan(
        scanPointsInRobotFrame(*pending.scan, *laser_pose_, config_.pipeline.scan_matching),
        odometry, result.causal_pose);
  }
}

void SlamNode::watchForLoss(SlamState state) {
  if (localize_only_ && params_.relocalise_when_lost) {
    relocaliser_.watch(std::move(state));
  } else {
    relocaliser_.stop();
  }
}

void SlamNode::relocate(const GlobalPlacement& place) {
  SlamState state = pipeline_->state(describeSlamConfig(config_));
  placeRobot(place, placementCovariance(), &state);
  auto moved = std::make_unique<SlamPipeline>(liveOptions(*laser_pose_));
  const std::string error = moved->resume(state, ResumeAt::kPlacedRobot);
  if (!error.empty()) {
    ROS_ERROR("ekf_slam_node: found again, but the state cannot be moved there: %s", error.c_str());
    return;
  }
  pipeline_ = std::move(moved);
  pipeline_->mutableFilter().setMappingEnabled(!localize_only_);
  ROS_WARN("ekf_slam_node: relocalised: the robot now stands at (%.2f m, %.2f m, %.1f deg)",
           place.map_pose.x, place.map_pose.y, radToDeg(place.map_pose.theta));
}

void SlamNode::onClockJump() {
  map_to_odom_.restartStamps();
  if (params_.clock_jump == "continue") {
    const std::optional<LandmarkMapFile> prior = landmarks();
    const std::string error =
        restart(config_.pipeline.initial_pose, config_.pipeline.initial_pose_covariance, prior,
                localize_only_);
    if (error.empty()) {
      ROS_WARN(
          "ekf_slam_node: clock_jump: continue: the filter restarts at the initial pose with "
          "the %zu landmarks mapped so far as its prior",
          prior ? prior->landmarks.size() : size_t{0});
      return;
    }
    ROS_WARN("ekf_slam_node: clock_jump: continue: %s; a new map instead", error.c_str());
  }
  services_.startNewMap("the clock jumped back (clock_jump: new_map)");
}

void SlamNode::acceptNextMotion() {
  if (pipeline_) pipeline_->acceptNextMotion();
}

std::optional<LandmarkMapFile> SlamNode::landmarks() const {
  if (pipeline_) {
    return toLandmarkMapFile(pipeline_->filter(), pipeline_->lineSupport(), params_.map_frame);
  }
  if (seed_state_) {  // a loaded state waiting for the first scan
    EkfSlam filter(config_.pipeline.filter);
    filter.restore(seed_state_->filter);
    return toLandmarkMapFile(filter, seed_state_->line_support, params_.map_frame);
  }
  return seed_map_;
}

void SlamNode::clearMap() {
  resetState();
  seed_map_.reset();
  start_pose_.reset();
  localize_only_ = params_.localize_only;
}

std::string SlamNode::restart(const Pose2& pose, const Matrix3& covariance,
                              std::optional<LandmarkMapFile> prior, bool localize_only) {
  const std::string error = setStartPose(pose, covariance);
  if (!error.empty()) return error;
  resetState();
  seed_map_ = std::move(prior);
  localize_only_ = localize_only;
  if (laser_pose_) createPipeline(*laser_pose_);  // else at the next scan
  return "";
}

std::optional<SlamState> SlamNode::state() const {
  if (!pipeline_) return std::nullopt;
  return pipeline_->state(describeSlamConfig(config_));
}

std::string SlamNode::resumeFrom(SlamState state, bool localize_only) {
  if (!laser_pose_) {
    // Checked against the laser mount at the first scan.
    resetState();
    seed_map_.reset();
    start_pose_.reset();
    seed_state_ = std::move(state);
    localize_only_ = localize_only;
    return "";
  }
  // Tried on a pipeline of its own: a refused state leaves the running one.
  const Pose2 laser = *laser_pose_;
  auto resumed = std::make_unique<SlamPipeline>(liveOptions(laser));
  const std::string error = resumed->resume(state);
  if (!error.empty()) return error;
  resetState();
  seed_map_.reset();
  start_pose_.reset();
  laser_pose_ = laser;
  localize_only_ = localize_only;
  pipeline_ = std::move(resumed);
  pipeline_->mutableFilter().setMappingEnabled(!localize_only_);
  watchForLoss(std::move(state));
  return "";
}

std::string SlamNode::setStartPose(const Pose2& pose, const Matrix3& covariance) {
  if (!pose.allFinite()) return "not finite";
  const Matrix3 symmetric = 0.5 * (covariance + covariance.transpose());
  if (!symmetric.allFinite() || !covariance.isApprox(covariance.transpose(), 1e-9) ||
      Eigen::SelfAdjointEigenSolver<Matrix3>(symmetric).eigenvalues().minCoeff() < 0.0) {
    return "the (x, y, yaw) covariance is not finite, symmetric and positive "
           "semi-definite";
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

void SlamNode::resetState() {
  pipeline_.reset();
  relocaliser_.stop();
  ++generation_;
  if (!config_.laser_pose_given) laser_pose_.reset();  // looked up again at the next scan
  outputs_.clear();
  grids_.restart();
  input_.clear();
  input_.restartStampOrder();
  services_.cancelStep();
  map_to_odom_.clear();
  diagnostics_.restart();
  // The drop counts stay: they count the node's inputs, not the map's history.
}

}  // namespace ekf_slam
