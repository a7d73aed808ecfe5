// ekf_slam_node's services: ~pause, ~resume, ~reset, ~save_map, ~load_map
// and ~smooth.
#include "ekf_slam_ros/slam_node/slam_node.h"

#include <nav_msgs/OccupancyGrid.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "ekf_slam_core/io/grid_map_file.h"
#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_ros/conversions/grid_conversion.h"
#include "ekf_slam_ros/conversions/pose_conversion.h"
#include "ekf_slam_ros/slam_node/slam_messages.h"

namespace ekf_slam {
namespace {

using ros_conversions::fromPoseMessage;
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

// "12 landmarks (lines: 3, line angles: 2)", for the services' replies.
std::string landmarkCounts(const LandmarkMapFile& map) {
  std::string text = std::to_string(map.size()) + " landmarks";
  if (!map.lines.empty() || !map.line_angles.empty()) {
    text += " (lines: " + std::to_string(map.lines.size()) +
            ", line angles: " + std::to_string(map.line_angles.size()) + ")";
  }
  return text;
}

// The key scans moved to the smoothed pose of their scan (matched by
// stamp); a key scan with no smoothed pose is left out, unless it is older
// than the smoothed scans (a bounded history): it keeps its loop-closed
// pose, the frame the smoothed window is anchored in.
std::vector<SlamPipeline::KeyScan> keysAtSmoothedPoses(std::vector<SlamPipeline::KeyScan> keys,
                                                       const std::vector<StampedPose>& smoothed) {
  std::vector<SlamPipeline::KeyScan> moved;
  moved.reserve(keys.size());
  for (SlamPipeline::KeyScan& key : keys) {
    if (!smoothed.empty() && key.stamp < smoothed.front().stamp) {
      moved.push_back(std::move(key));
      continue;
    }
    const auto at =
        std::lower_bound(smoothed.begin(), smoothed.end(), key.stamp,
                         [](const StampedPose& pose, double stamp) { return pose.stamp < stamp; });
    if (at == smoothed.end() || at->stamp != key.stamp) continue;
    key.pose = at->pose;
    moved.push_back(std::move(key));
  }
  return moved;
}

}  // namespace

bool SlamNode::onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  paused_ = true;
  step_pending_ = false;
  clearWaiting();
  response.success = true;
  response.message = "paused: scans are dropped until resume";
  ROS_INFO("ekf_slam_node: %s", response.message.c_str());
  return true;
}

bool SlamNode::onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  // Whatever the robot did while paused is one move, however large: the
  // next scan takes it as control instead of discarding it as a jump.
  if (paused_ && pipeline_) pipeline_->acceptNextMotion();
  paused_ = false;
  step_pending_ = false;
  response.success = true;
  response.message = "resumed";
  ROS_INFO("ekf_slam_node: resumed");
  return true;
}

bool SlamNode::onStep(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  if (paused_ && pipeline_) pipeline_->acceptNextMotion();
  response.message =
      paused_ ? "one iteration on the next scan, then paused" : "pausing after the next scan";
  paused_ = false;
  step_pending_ = true;
  response.success = true;
  ROS_INFO("ekf_slam_node: step: %s", response.message.c_str());
  return true;
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
    map = toLandmarkMapFile(pipeline_->filter(), lineSupport(), params_.map_frame);
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
  response.message =
      error.empty() ? landmarkCounts(map) + " written to " + request.path + grid_note : error;
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
  response.landmarks = static_cast<int>(map.size());
  std::ostringstream text;
  text.setf(std::ios::fixed);
  text.precision(3);
  text << landmarkCounts(map) << " loaded from " << request.path;
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

bool SlamNode::onSmooth(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  if (!pipeline_ || pipeline_->scans().empty()) {
    response.success = false;
    response.message = "no scans processed yet";
    return true;
  }
  // With history_max_scans, the smoother covers the newest scans only.
  const std::vector<StampedPose> smoothed = pipeline_->smoothedScanPoses();
  std_msgs::Header header;
  header.stamp = last_scan_stamp_;
  header.frame_id = params_.map_frame;
  nav_msgs::Path path;
  path.header = header;
  auto addToPath = [&](double stamp, const Pose2& pose) {
    geometry_msgs::PoseStamped p;
    p.header.stamp = ros::Time(stamp);
    p.header.frame_id = params_.map_frame;
    p.pose = toPoseMessage(pose);
    path.poses.push_back(p);
  };
  // With loop closure on, the grid is cast from the back end's key scans
  // (the readings it keeps anyway) at their smoothed poses: the node keeps
  // no ranges of its own, and its memory grows with the key scans only.
  // Key scans older than the smoothed scans keep their loop-closed poses,
  // and lead the path.
  const ScanHistory& history = pipeline_->history();
  std::vector<SlamPipeline::KeyScan> keys;
  if (history.keptScans().empty()) keys = keysAtSmoothedPoses(pipeline_->keyScans(true), smoothed);
  long older_keys = 0;
  for (const SlamPipeline::KeyScan& key : keys) {
    if (smoothed.empty() || key.stamp >= smoothed.front().stamp) break;
    addToPath(key.stamp, key.pose);
    ++older_keys;
  }
  // Without loop closure the history's kept scans are cast at their
  // smoothed poses, over its grid of the scans older than them.
  OccupancyGrid grid =
      history.leftScansGrid() ? *history.leftScansGrid() : OccupancyGrid(config_.map);
  const long first_record = pipeline_->firstScan();
  for (size_t i = 0; i < smoothed.size(); ++i) {
    addToPath(smoothed[i].stamp, smoothed[i].pose);
    if (const KeptScan* kept = history.keptScan(first_record + static_cast<long>(i))) {
      grid.insertScan(compose(smoothed[i].pose, *laser_pose_), kept->toScan());
    }
  }
  smoothed_path_publisher_.publish(path);
  if (history.keptScans().empty() && keys.empty()) {
    // input: features: the node never saw the ranges a grid is cast from.
    response.success = true;
    response.message = "smoothed " + std::to_string(smoothed.size()) +
                       " scan poses; no occupancy grid (no scans stored: input is features, "
                       "or no key scan yet)";
    ROS_INFO("ekf_slam_node: smooth: %s", response.message.c_str());
    return true;
  }
  if (!keys.empty()) grid = gridFromKeyScans(keys, *laser_pose_, config_.map);

  publishNodeGrid(toOccupancyGridMessage(grid, header));

  std::ostringstream text;
  text << "smoothed " << smoothed.size() << " scan poses (" << pipeline_->counters().iterations
       << " iterations";
  if (pipeline_->firstScan() > 0) {
    text << "; the newest " << smoothed.size() << " of " << pipeline_->recordedScans()
         << " scans, history_max_scans";
    if (older_keys > 0) text << ", before them " << older_keys << " loop-closed key scans";
  }
  text << "); map " << grid.width() << " x " << grid.height() << " cells at " << grid.resolution()
       << " m";
  response.success = true;
  response.message = text.str();
  ROS_INFO("ekf_slam_node: smooth: %s", response.message.c_str());
  return true;
}

}  // namespace ekf_slam
