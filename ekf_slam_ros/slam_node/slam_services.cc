#include "ekf_slam_ros/slam_node/slam_services.h"

#include <nav_msgs/OccupancyGrid.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <boost/make_shared.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <sstream>
#include <utility>

#include "ekf_slam_core/io/atomic_file.h"
#include "ekf_slam_core/io/map_set.h"
#include "ekf_slam_core/pipeline/slam_state.h"
#include "ekf_slam_ros/conversions/grid_conversion.h"
#include "ekf_slam_ros/slam_node/spin_thread.h"
#include "ros_conversions/pose_conversion.h"

namespace ekf_slam {
namespace {

using ros_conversions::fromPoseMessage;
using ros_conversions::toPoseMessage;

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

// What ~smooth needs of the SLAM state, copied on the spin thread.
struct SmoothInput {
  SmoothingProblem problem;
  std::vector<SlamPipeline::KeyScan> keys;  // with readings; empty when the history keeps them
  Pose2 laser;                              // base_link → laser
  long iterations = 0;                      // the pipeline's, for the reply
  long first_scan = 0;                      // of the kept history …
  long recorded_scans = 0;                  // … and of the run
  std_msgs::Header header;                  // the map frame at the last scan's stamp
  long generation = 0;                      // SlamControl::generation
};

// ~smooth's path (into `path`) and grid; false without a grid (input:
// features, or no key scan yet). `older_keys`: key scans older than the
// smoothed scans (a bounded history), at their loop-closed poses. The
// input's key scans are moved out.
bool smoothedGrid(SmoothInput&& input, const std::vector<StampedPose>& smoothed,
                  const std::string& map_frame, const OccupancyGridOptions& map_options,
                  nav_msgs::Path* path, OccupancyGrid* grid, long* older_keys) {
  auto addToPath = [&](double stamp, const Pose2& pose) {
    geometry_msgs::PoseStamped p;
    p.header.stamp = ros::Time(stamp);
    p.header.frame_id = map_frame;
    p.pose = toPoseMessage(pose);
    path->poses.push_back(p);
  };
  // With loop closure on, the grid is cast from the back end's key scans
  // (the readings it keeps anyway) at their smoothed poses, and the history
  // keeps no readings: memory grows with the key scans only. Key scans
  // older than the smoothed scans keep their loop-closed poses, and lead
  // the path.
  const ScanHistory& history = input.problem.history;
  std::vector<SlamPipeline::KeyScan> keys;
  if (history.keptScans().empty()) keys = keysAtSmoothedPoses(std::move(input.keys), smoothed);
  for (const SlamPipeline::KeyScan& key : keys) {
    if (smoothed.empty() || key.stamp >= smoothed.front().stamp) break;
    addToPath(key.stamp, key.pose);
    ++*older_keys;
  }
  // Without loop closure the history's kept scans are cast at their
  // smoothed poses, over its grid of the scans older than them.
  if (history.leftScansGrid()) *grid = *history.leftScansGrid();
  for (size_t i = 0; i < smoothed.size(); ++i) {
    addToPath(smoothed[i].stamp, smoothed[i].pose);
    if (const KeptScan* kept = history.keptScan(input.first_scan + static_cast<long>(i))) {
      grid->insertScan(compose(smoothed[i].pose, input.laser), kept->toScan());
    }
  }
  if (history.keptScans().empty() && keys.empty()) return false;
  if (!keys.empty()) *grid = gridFromKeyScans(keys, input.laser, map_options);
  return true;
}

// Run first on the slow services' thread: it yields to the node's other
// threads (nice +10, Linux's per-thread priority).
class LowerPriority : public ros::CallbackInterface {
 public:
  CallResult call() override {
    if (setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10) != 0) {
      ROS_DEBUG("ekf_slam_node: the slow services' thread keeps its priority: %s",
                std::strerror(errno));
    }
    return Success;
  }
};

// The reply of a slow service that the node's shutdown interrupted.
const char* const kShuttingDown = "the node is shutting down (nothing done)";

// A service's refusal as a callable: the reply names the problem and what
// happened instead (`outcome`), and the node logs it as a warning.
template <class Response>
auto refusal(Response& response, const char* service, const char* outcome) {
  return [&response, service, outcome](const std::string& problem) {
    response.message = problem + " (" + outcome + ")";
    ROS_WARN("ekf_slam_node: %s: %s", service, response.message.c_str());
    return true;
  };
}

std::string withoutLeadingSlash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

}  // namespace

SlamServices::SlamServices(ros::NodeHandle node, ros::NodeHandle private_node,
                           const SlamNodeParams& params, const OccupancyGridOptions& map,
                           SlamControl& slam, ScanOutputs& outputs, GridOutput& grids)
    : params_(params), map_options_(map), slam_(slam), outputs_(outputs), grids_(grids) {
  paused_ = params_.start_paused;
  if (paused_) ROS_INFO("ekf_slam_node: started paused (start_paused): call ~resume to map");
  services_.push_back(private_node.advertiseService("pause", &SlamServices::onPause, this));
  services_.push_back(private_node.advertiseService("resume", &SlamServices::onResume, this));
  services_.push_back(private_node.advertiseService("step", &SlamServices::onStep, this));
  services_.push_back(private_node.advertiseService("reset", &SlamServices::onReset, this));
  ros::NodeHandle slow(private_node);
  slow.setCallbackQueue(&slow_queue_);
  services_.push_back(slow.advertiseService("smooth", &SlamServices::onSmooth, this));
  services_.push_back(slow.advertiseService("save_map", &SlamServices::onSaveMap, this));
  services_.push_back(slow.advertiseService("load_map", &SlamServices::onLoadMap, this));
  services_.push_back(slow.advertiseService("write_state", &SlamServices::onWriteState, this));
  services_.push_back(slow.advertiseService("load_state", &SlamServices::onLoadState, this));
  ros::NodeHandle slow_public(node);
  slow_public.setCallbackQueue(&slow_queue_);
  services_.push_back(
      slow_public.advertiseService("dynamic_map", &SlamServices::onDynamicMap, this));
  initial_pose_subscriber_ = node.subscribe("initialpose", 2, &SlamServices::onInitialPose, this);
  slow_thread_ = std::make_unique<ros::AsyncSpinner>(1, &slow_queue_);
  slow_thread_->start();
  // The scans and tf go first when the machine is busy.
  slow_queue_.addCallback(boost::make_shared<LowerPriority>());
}

SlamServices::~SlamServices() {
  closing_ = true;
  slow_thread_->stop();
}

bool SlamServices::onSpinThread(const std::function<void()>& work) const {
  return runOnSpinThread(work, closing_);
}

std_msgs::Header SlamServices::mapHeader() const {
  std_msgs::Header header;
  header.stamp = slam_.lastScanStamp();
  header.frame_id = params_.map_frame;
  return header;
}

void SlamServices::afterScan(const ros::Time& stamp, ScanOutcome outcome) {
  if (!step_pending_) return;
  // ~step: this was the one scan; pause until the next step.
  step_pending_ = false;
  paused_ = true;
  ++steps_done_;
  slam_.dropWaitingInputs();
  ROS_INFO("ekf_slam_node: step %ld: scan at %.3f %s; paused", steps_done_, stamp.toSec(),
           toString(outcome));
}

bool SlamServices::onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  paused_ = true;
  step_pending_ = false;
  slam_.dropWaitingInputs();
  response.success = true;
  response.message = "paused: scans are dropped until resume";
  ROS_INFO("ekf_slam_node: %s", response.message.c_str());
  return true;
}

bool SlamServices::onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  // Whatever the robot did while paused is one move, however large: the
  // next scan takes it as control instead of discarding it as a jump.
  if (paused_) slam_.acceptNextMotion();
  paused_ = false;
  step_pending_ = false;
  response.success = true;
  response.message = "resumed";
  ROS_INFO("ekf_slam_node: resumed");
  return true;
}

bool SlamServices::onStep(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  if (paused_) slam_.acceptNextMotion();
  response.message =
      paused_ ? "one iteration on the next scan, then paused" : "pausing after the next scan";
  paused_ = false;
  step_pending_ = true;
  response.success = true;
  ROS_INFO("ekf_slam_node: step: %s", response.message.c_str());
  return true;
}

bool SlamServices::onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  startNewMap("reset");
  response.success = true;
  response.message = "reset: empty map; the next scan starts a new one";
  return true;
}

void SlamServices::startNewMap(const std::string& why) {
  slam_.clearMap();
  grids_.forget();
  const std_msgs::Header header = mapHeader();
  outputs_.publishLandmarkMap(slam_.landmarks().value_or(LandmarkMapFile()), header);
  outputs_.republishPath(header.stamp);
  ROS_INFO("ekf_slam_node: %s: empty map; the next scan starts a new one", why.c_str());
}

bool SlamServices::onSaveMap(SaveMap::Request& request, SaveMap::Response& response) {
  response.success = false;
  if (request.path.empty()) {
    response.message = "path is empty";
    return true;
  }
  const auto refuse = refusal(response, "save_map", "nothing saved");
  // A path that is not a regular file (a directory, a device, a pipe) is
  // refused before the map is copied (writeMapSet checks them again).
  const MapSetPaths paths = mapSetPaths(request.path);
  for (const std::string& path : {paths.landmarks, paths.grid, paths.image}) {
    const std::string problem = writeTargetProblem(path);
    if (!problem.empty()) return refuse(problem);
  }
  // The map as it stands now, copied on the spin thread; written here.
  LandmarkMapFile map;
  nav_msgs::OccupancyGrid grid;
  bool have_grid = false;
  const bool copied = onSpinThread([&] {
    if (std::optional<LandmarkMapFile> landmarks = slam_.landmarks()) {
      map = std::move(*landmarks);
    } else {
      map.frame = params_.map_frame;
    }
    have_grid = grids_.currentGrid(&grid) && grid.info.width > 0 && grid.info.height > 0;
  });
  if (!copied) {
    response.message = kShuttingDown;
    return true;
  }
  // The landmarks, the grid's image and its YAML as one set: a load never
  // pairs files of two saves. A map saved without a grid removes the grid
  // an earlier save left at that path.
  std::optional<GridMapFile> grid_file;
  if (have_grid) grid_file = ros_conversions::toGridMapFile(grid);
  const std::string error = writeMapSet(request.path, map, grid_file);
  const std::string grid_note = have_grid ? " and the " + std::to_string(grid.info.width) + " x " +
                                                std::to_string(grid.info.height) +
                                                " occupancy grid to " + paths.grid
                                          : "; no occupancy grid yet (nothing published on map)";
  response.success = error.empty();
  if (response.success && have_grid) response.grid_path = paths.grid;
  response.message =
      error.empty() ? landmarkCounts(map) + " written to " + request.path + grid_note : error;
  ROS_INFO("ekf_slam_node: save_map: %s", response.message.c_str());
  return true;
}

bool SlamServices::onDynamicMap(nav_msgs::GetMap::Request&, nav_msgs::GetMap::Response& response) {
  bool have_grid = false;
  if (!onSpinThread([&] { have_grid = grids_.currentGrid(&response.map); })) return false;
  if (!have_grid) {
    ROS_WARN_THROTTLE(5.0, "ekf_slam_node: dynamic_map: no grid published on map yet");
  }
  return have_grid;
}

bool SlamServices::onLoadMap(LoadMap::Request& request, LoadMap::Response& response) {
  response.success = false;
  response.landmarks = 0;
  const auto refuse = refusal(response, "load_map", "the current map is kept");
  // The files are read here, off the spin thread, after a save of them
  // that stopped after its commit has been completed.
  const std::string grid_path = mapSetPaths(request.path).grid;
  std::string error = finishInterruptedMapSave(request.path);
  if (!error.empty()) return refuse(error);
  LandmarkMapFile map;
  error = readLandmarkMap(request.path, &map);
  if (!error.empty()) return refuse(error);
  // The grid saved beside it, if there is one: a broken one refuses the load.
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
  bool localize_only = false;
  const bool done = onSpinThread([&] {
    error = slam_.restart(start, start_covariance, map, request.localize_only);
    if (!error.empty()) return;
    localize_only = slam_.localizeOnly();
    const std_msgs::Header header = mapHeader();
    outputs_.publishLandmarkMap(slam_.landmarks().value_or(LandmarkMapFile()), header);
    grids_.hold(false);
    if (grid) {
      grids_.publish(ros_conversions::toOccupancyGridMessage(*grid, header));
      grids_.hold(localize_only);  // mapping on: the live map takes over
    }
  });
  if (!done) return refuse(kShuttingDown);
  if (!error.empty()) return refuse("pose: " + error);
  response.success = true;
  response.landmarks = static_cast<int>(map.size());
  std::ostringstream text;
  text.setf(std::ios::fixed);
  text.precision(3);
  text << landmarkCounts(map) << " loaded from " << request.path;
  if (grid) text << " and a " << grid->width << " x " << grid->height << " grid from " << grid_path;
  text << "; the robot starts at (" << start.x << ", " << start.y << ", " << radToDeg(start.theta)
       << " deg)" << (localize_only ? "; localisation only" : "; mapping continues");
  response.message = text.str();
  ROS_INFO("ekf_slam_node: load_map: %s", response.message.c_str());
  return true;
}

bool SlamServices::onWriteState(StateFile::Request& request, StateFile::Response& response) {
  response.success = false;
  const auto refuse = refusal(response, "write_state", "nothing written");
  if (request.path.empty()) return refuse("path is empty");
  if (const std::string problem = writeTargetProblem(request.path); !problem.empty()) {
    return refuse(problem);
  }
  // Copied on the spin thread, written here.
  std::optional<SlamState> state;
  if (!onSpinThread([&] { state = slam_.state(); })) return refuse(kShuttingDown);
  if (!state) return refuse("no map yet: no scan has been processed");
  const std::string error = writeSlamState(request.path, *state);
  if (!error.empty()) return refuse(error);
  const LoopCloserState& closer = state->back_end.closer;
  long loops = 0;
  for (const PoseGraphEdge& edge : closer.graph.edges()) loops += edge.robust && edge.active;
  response.success = true;
  response.message = std::to_string(state->filter.landmarkCount()) + " landmarks, " +
                     std::to_string(closer.keys.size()) + " key scans and " +
                     std::to_string(loops) + " loop edges written to " + request.path;
  ROS_INFO("ekf_slam_node: write_state: %s", response.message.c_str());
  return true;
}

bool SlamServices::onLoadState(StateFile::Request& request, StateFile::Response& response) {
  response.success = false;
  const auto refuse = refusal(response, "load_state", "the current map is kept");
  // Read and checked here, off the spin thread.
  SlamState state;
  std::string error = readSlamState(request.path, &state);
  if (!error.empty()) return refuse(error);
  const int landmarks = state.filter.landmarkCount();
  const size_t keys = state.back_end.closer.keys.size();
  const bool done = onSpinThread([&] {
    error = slam_.resumeFrom(std::move(state), request.localize_only);
    if (!error.empty()) return;
    const std_msgs::Header header = mapHeader();
    outputs_.publishLandmarkMap(slam_.landmarks().value_or(LandmarkMapFile()), header);
    grids_.hold(false);
  });
  if (!done) return refuse(kShuttingDown);
  if (!error.empty()) return refuse(request.path + ": " + error);
  response.success = true;
  response.message = std::to_string(landmarks) + " landmarks and " + std::to_string(keys) +
                     " key scans loaded from " + request.path +
                     (request.localize_only ? "; localising in it from where the saved run stopped"
                                            : "; mapping goes on where the saved run stopped");
  ROS_INFO("ekf_slam_node: load_state: %s", response.message.c_str());
  return true;
}

void SlamServices::onInitialPose(const geometry_msgs::PoseWithCovarianceStamped& message) {
  if (withoutLeadingSlash(message.header.frame_id) != params_.map_frame) {
    ROS_WARN(
        "ekf_slam_node: initialpose in frame '%s' ignored: it must be given in '%s' (set "
        "rviz's fixed frame to it)",
        message.header.frame_id.c_str(), params_.map_frame.c_str());
    return;
  }
  const Pose2 start = fromPoseMessage(message.pose.pose);
  const Matrix3 covariance = ros_conversions::planarCovariance(message.pose.covariance);
  // The landmarks mapped so far (or the map loaded and not yet used) stay,
  // as the prior of the restarted filter.
  const std::optional<LandmarkMapFile> prior = slam_.landmarks();
  const std::string error = slam_.restart(start, covariance, prior, slam_.localizeOnly());
  if (!error.empty()) {
    ROS_WARN("ekf_slam_node: initialpose ignored: %s", error.c_str());
    return;
  }
  ++relocalisations_;
  ROS_INFO(
      "ekf_slam_node: initialpose: the filter restarts at (%.3f m, %.3f m, %.1f deg), "
      "sigma (%.3f m, %.3f m, %.1f deg), with %zu landmarks as its prior",
      start.x, start.y, radToDeg(start.theta), std::sqrt(covariance(0, 0)),
      std::sqrt(covariance(1, 1)), radToDeg(std::sqrt(covariance(2, 2))),
      prior ? prior->landmarks.size() : size_t{0});
}

bool SlamServices::onSmooth(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  response.success = false;
  // The problem and the readings, copied on the spin thread; solved here
  // while the scans go on.
  std::optional<SmoothInput> input;
  const ros::WallTime asked = ros::WallTime::now();
  const bool copied = onSpinThread([&] {
    const SlamPipeline* pipeline = slam_.pipeline();
    if (!pipeline || pipeline->scans().empty()) return;
    input.emplace(SmoothInput{pipeline->smoothingProblem(), {}, Pose2(), 0, 0, 0, {}, 0});
    // With loop closure on the history keeps no readings: the grid is cast
    // from the back end's key scans.
    if (input->problem.history.keptScans().empty()) input->keys = pipeline->keyScans(true);
    input->laser = pipeline->options().filter.laser_pose;
    input->iterations = pipeline->counters().iterations;
    input->first_scan = pipeline->firstScan();
    input->recorded_scans = pipeline->recordedScans();
    input->header = mapHeader();
    input->generation = slam_.generation();
  });
  ROS_DEBUG("ekf_slam_node: smooth: the state copied in %.3f s",
            (ros::WallTime::now() - asked).toSec());
  if (!copied) {
    response.message = kShuttingDown;
    return true;
  }
  if (!input) {
    response.message = "no scans processed yet";
    return true;
  }
  // With history_max_scans, the smoother covers the newest scans only.
  const std::vector<StampedPose> smoothed = input->problem.solve();
  nav_msgs::Path path;
  path.header = input->header;
  OccupancyGrid grid(map_options_);
  long older_keys = 0;
  const bool have_grid = smoothedGrid(std::move(*input), smoothed, params_.map_frame, map_options_,
                                      &path, &grid, &older_keys);
  std::optional<nav_msgs::OccupancyGrid> grid_message;
  if (have_grid) grid_message = toOccupancyGridMessage(grid, input->header);
  bool current = false;
  const bool published = onSpinThread([&] {
    current = slam_.generation() == input->generation;
    if (!current) return;
    outputs_.publishSmoothedPath(path);
    if (grid_message) grids_.publish(*grid_message);
  });
  if (!published) {
    response.message = kShuttingDown;
    return true;
  }
  if (!current) {
    response.message =
        "the map restarted while it was smoothed (~reset, a loaded map or an "
        "initial pose): nothing published";
    ROS_WARN("ekf_slam_node: smooth: %s", response.message.c_str());
    return true;
  }
  response.success = true;
  if (!have_grid) {
    // input: features: the node never saw the ranges a grid is cast from.
    response.message = "smoothed " + std::to_string(smoothed.size()) +
                       " scan poses; no occupancy grid (no scans stored: input is features, "
                       "or no key scan yet)";
    ROS_INFO("ekf_slam_node: smooth: %s", response.message.c_str());
    return true;
  }
  std::ostringstream text;
  text << "smoothed " << smoothed.size() << " scan poses (" << input->iterations << " iterations";
  if (input->first_scan > 0) {
    text << "; the newest " << smoothed.size() << " of " << input->recorded_scans
         << " scans, history_max_scans";
    if (older_keys > 0) text << ", before them " << older_keys << " loop-closed key scans";
  }
  text << "); map " << grid.width() << " x " << grid.height() << " cells at " << grid.resolution()
       << " m";
  response.message = text.str();
  ROS_INFO("ekf_slam_node: smooth: %s", response.message.c_str());
  return true;
}

}  // namespace ekf_slam
