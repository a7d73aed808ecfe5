// ekf_slam_offline: offline EKF-SLAM over a recorded log (thesis §3.4.4.2),
// with RTS smoothing and the complete metric map (§3.4.5). Reads the bag
// directly (no roscore, no real-time playback), processes every scan in file
// order, and is deterministic: the same input gives bit-identical output.
//
//   rosrun ekf_slam ekf_slam_offline (--bag FILE | --carmen FILE) --out DIR
//                                    [--config YAML] [--preset NAME] [--max-scans N] [--first-scan
//                                    N]
//                                    [--no-figures] [--trace] [--export-graphs DIR]
//                                    [--save-state FILE] [--resume FILE [--localize-only]
//                                    [--global]]
//
// Writes into DIR: trajectory_filtered.txt, trajectory_smoothed.txt (the full
// smoother: batch MAP over every pose, landmark and observation the filter
// used; the RTS pass with smoother.method: rts), trajectory_rts.txt (the thesis's RTS smoother over
// the pose alone), trajectory_odometry.txt (one line per scan: "stamp x y theta", the scan's header
// stamp with 6 decimals), covariance_filtered.txt (the filter's pose covariance per scan, for NEES
// checks), landmarks.yaml, map.pgm + map.yaml (from the final trajectory: loop-closed with loop
// closure on, else smoothed), map_filtered.*, map_odometry.*, the figures and report.txt.
// report.txt is written last: a directory without it holds no complete result. --export-graphs DIR
// also writes, into DIR, the problems of the last two optimisations
// (ekf_slam_core/pose_graph/graph_io.h gives the formats), to be solved again by other solvers
// (docs/solvers.md): pose_graph.txt, the loop-closure pose graph as the back end's final
// optimisation started from (when a loop was closed), pose_graph_cold.txt, the same graph started
// from the front end's key-scan poses, and landmark_graph.txt, the full smoother's last
// optimisation as it started; with pose_graph_scans.txt and landmark_graph_scans.txt, the scan
// anchors that turn a solution into one pose per scan (as trajectory_optimized.txt and
// trajectory_smoothed.txt are made from the run's own solutions). --save-state FILE writes the
// SLAM state after the last scan (before the final optimisation; its key scans' final poses from
// trajectory_smoothed.txt), --resume FILE goes on from one
// (ekf_slam_core/pipeline/slam_state.h): a log mapped in parts, a building mapped over days;
// with --global the robot is first found in the saved map from the log's first scans
// (ekf_slam_core/pipeline/global_localization.h), wherever it starts.
// Exit code 0 on success, 1 on bad arguments or configuration, 2 on unreadable input (a state
// that cannot be resumed included), 3 when the output cannot be written.
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#ifdef __GLIBC__  // defined by the headers above
#include <malloc.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "ekf_slam_core/io/atomic_file.h"
#include "ekf_slam_core/io/landmark_map.h"
#include "ekf_slam_core/io/trajectory_file.h"
#include "ekf_slam_core/pipeline/global_localization.h"
#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_core/pipeline/slam_state.h"
#include "ekf_slam_core/pose_graph/graph_io.h"
#include "ekf_slam_ros/offline/log_input.h"

namespace {

using ekf_slam::Pose2;

// The folder this program runs from (devel/lib/ekf_slam or the install
// space's lib/ekf_slam): scripts it runs are installed beside it.
std::string programDir() {
  char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n <= 0) return ".";
  const std::string exe(path, static_cast<size_t>(n));
  const size_t slash = exe.rfind('/');
  return slash == std::string::npos ? "." : exe.substr(0, slash);
}

void usage(std::ostream& out = std::cerr) {
  out << "usage: ekf_slam_offline (--bag FILE | --carmen FILE) --out DIR [--config YAML]\n"
         "                        [--preset NAME] [--max-scans N] [--first-scan N] [--no-figures] "
         "[--no-maps]\n"
         "                        [--trace] [--export-graphs DIR] [--save-state FILE]\n"
         "                        [--resume FILE [--localize-only] [--global]]\n"
         "       ekf_slam_offline [--config YAML] [--preset NAME] --print-config\n"
         "       ekf_slam_offline --help\n"
         "  --config: overrides of the built-in defaults (config/ekf_slam.yaml holds them)\n"
         "  --preset: a named mode laid over that (config/ekf_slam_NAME.yaml): thesis,\n"
         "             the thesis's EKF-SLAM (odometry control, corners and lines, RTS)\n"
         "  --print-config: every parameter with the value it would run with, then exit\n"
         "  --no-maps: trajectories, landmarks and the report only (no occupancy grids,\n"
         "             no figures): the fastest run, for scoring trajectories\n"
         "  --export-graphs: the final loop-closure pose graph and the full smoother's\n"
         "             last problem as text files in DIR (docs/solvers.md)\n"
         "  --first-scan: leave out the log's scans before this one (counted from 0)\n"
         "  --save-state: the SLAM state after the last scan, to go on from with --resume\n"
         "  --resume: go on mapping from a saved state (the log's first scan is taken\n"
         "             where the saved run stopped)\n"
         "  --localize-only: with --resume, no landmark is added: the saved map localises\n"
         "  --global: with --resume, the robot need not start where the saved run stopped:\n"
         "             the log's first scans are searched for in the saved map, and the\n"
         "             scans before the robot is found are left out\n";
}

void progress(size_t done, size_t total, int landmarks, double seconds, bool tty) {
  const int percent = total ? static_cast<int>(100 * done / total) : 100;
  if (tty) {
    const int width = 40, filled = percent * width / 100;
    std::fprintf(stderr, "\r[%s%s] %3d%% %zu/%zu scans, %d landmarks, %.1f s",
                 std::string(filled, '=').c_str(), std::string(width - filled, ' ').c_str(),
                 percent, done, total, landmarks, seconds);
  } else {
    std::fprintf(stderr, "%3d%% %zu/%zu scans, %d landmarks, %.1f s\n", percent, done, total,
                 landmarks, seconds);
  }
}

ekf_slam::OccupancyGrid buildMap(const ekf_slam::OccupancyGridOptions& options,
                                 const ekf_slam::LogData& log,
                                 const std::vector<ekf_slam::StampedPose>& poses,
                                 const Pose2& laser) {
  ekf_slam::OccupancyGrid grid(options);
  // Size the grid once, to what the rays reach.
  Eigen::Vector2d low = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d high = -low;
  for (size_t i = 0; i < poses.size() && i < log.scans.size(); ++i) {
    grid.extendToScan(ekf_slam::compose(poses[i].pose, laser), log.scans[i].scan, &low, &high);
  }
  if (low.allFinite() && high.allFinite()) grid.cover(low, high);
  for (size_t i = 0; i < poses.size() && i < log.scans.size(); ++i) {
    grid.insertScan(ekf_slam::compose(poses[i].pose, laser), log.scans[i].scan);
  }
  if (grid.raysBeyondLimit() > 0) {
    std::cerr << "ekf_slam_offline: warning: " << grid.raysBeyondLimit()
              << " rays left out of a map: they reach so far from the others that the grid "
                 "would exceed map.max_cells ("
              << options.max_cells << " cells); a pose is corrupt or far off\n";
  }
  return grid;
}

// The first and the last scan as map-frame points, placed once with the
// odometry poses and once with the smoothed SLAM poses (thesis Fig. 5.7: with
// a good estimate both scans of the same place overlap).
std::string writeFirstLastScans(const std::string& path, const ekf_slam::LogData& log,
                                const std::vector<ekf_slam::StampedPose>& odometry,
                                const std::vector<ekf_slam::StampedPose>& slam,
                                const Pose2& laser) {
  std::ofstream out(path);
  if (!out) return path + ": cannot write";
  out << "# frame (odometry|slam) scan (first|last) x y  [m, map frame]\n";
  out.precision(6);
  out.setf(std::ios::fixed);
  if (log.scans.empty()) return "";
  const size_t indices[2] = {0, log.scans.size() - 1};
  const char* names[2] = {"first", "last"};
  for (const auto& [frame, poses] :
       {std::make_pair("odometry", &odometry), std::make_pair("slam", &slam)}) {
    for (int k = 0; k < 2; ++k) {
      const ekf_slam::Scan& scan = log.scans[indices[k]].scan;
      const Pose2 sensor = ekf_slam::compose((*poses)[indices[k]].pose, laser);
      for (int i = 0; i < scan.size(); ++i) {
        if (!scan.isValid(i)) continue;
        const double a = scan.angle(i);
        if (!std::isfinite(a)) continue;  // a sweep whose bearings overflow
        const ekf_slam::Vector2 p = ekf_slam::transformFrom(
            sensor, ekf_slam::Vector2(scan.ranges[i] * std::cos(a), scan.ranges[i] * std::sin(a)));
        out << frame << ' ' << names[k] << ' ' << p.x() << ' ' << p.y() << '\n';
      }
    }
  }
  out.close();  // a full disk shows when the last buffer is written
  return out ? "" : path + ": write error";
}

// The filter's pose covariance for every scan: that of the iteration the
// scan's pose hangs off (the scan's own when it was iterated; dead-reckoned
// scans between iterations are more uncertain than this). For consistency
// checks (NEES) against a ground truth.
std::string writeFilteredCovariances(const std::string& path, const ekf_slam::SlamPipeline& p) {
  std::ofstream out(path);
  if (!out) return path + ": cannot write";
  out.precision(9);
  out << "# stamp  xx xy xtheta yy ytheta thetatheta  (filtered pose covariance, m^2, m*rad, "
         "rad^2; between iterations carried through the motion model)\n";
  for (const ekf_slam::ScanRecord& r : p.scans()) {
    if (r.iteration < 0) continue;
    const ekf_slam::Matrix3& c = r.covariance;
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.6f", r.stamp);
    out << stamp << ' ' << c(0, 0) << ' ' << c(0, 1) << ' ' << c(0, 2) << ' ' << c(1, 1) << ' '
        << c(1, 2) << ' ' << c(2, 2) << '\n';
  }
  out.close();
  return out ? "" : path + ": write error";
}

// --export-graphs: the two problems with their scan anchors (see the top).
std::string exportGraphs(const std::string& dir, const ekf_slam::SlamPipeline& pipeline,
                         const ekf_slam::PipelineOptions& options,
                         const ekf_slam::LandmarkGraph& smoother_problem) {
  if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) return dir + ": cannot create";
  std::string error;
  const ekf_slam::LoopCloser* closer = pipeline.loopCloser();
  if (closer && closer->finalProblem().nodeCount() > 0) {
    error = ekf_slam::savePoseGraph(dir + "/pose_graph.txt", closer->finalProblem(),
                                    options.loop_closure.optimizer);
    std::vector<ekf_slam::ScanAnchor> anchors;
    for (int s = 0; s < closer->scanCount(); ++s) {
      anchors.push_back({closer->scanStamp(s), closer->scanKey(s), closer->scanOffset(s)});
    }
    if (error.empty()) error = ekf_slam::saveScanAnchors(dir + "/pose_graph_scans.txt", anchors);
    // The same graph from the front end's key-scan poses (no loop applied):
    // a cold start, harder than the warm one the back end's last solve had.
    ekf_slam::PoseGraph cold = closer->finalProblem();
    const Pose2 frame = ekf_slam::compose(cold.pose(0), ekf_slam::inverse(closer->keyFrontEnd(0)));
    for (int k = 1; k < cold.nodeCount() && k < closer->keyCount(); ++k) {
      cold.setPose(k, ekf_slam::compose(frame, closer->keyFrontEnd(k)));
    }
    if (error.empty()) {
      error = ekf_slam::savePoseGraph(dir + "/pose_graph_cold.txt", cold,
                                      options.loop_closure.optimizer);
    }
  }
  if (error.empty() && smoother_problem.poseCount() > 0) {
    error = ekf_slam::saveLandmarkGraph(dir + "/landmark_graph.txt", smoother_problem,
                                        options.smoother.optimizer);
    // As SlamPipeline::scanPosesFrom places the scans on the iteration poses.
    std::vector<ekf_slam::ScanAnchor> anchors;
    for (const ekf_slam::ScanRecord& r : pipeline.scans()) {
      if (r.iteration < 0 || r.iteration >= smoother_problem.poseCount()) {
        anchors.push_back({r.stamp, -1, r.filtered});
      } else {
        anchors.push_back({r.stamp, r.iteration, between(r.odometry_at_iteration, r.odometry)});
      }
    }
    if (error.empty()) {
      error = ekf_slam::saveScanAnchors(dir + "/landmark_graph_scans.txt", anchors);
    }
  }
  return error;
}

// "a of them disagreed with the wheels, b corrections beyond max_correction_*,
// c too few points, pairs or inliers": why a scan matcher's refused matches were refused.
std::string refusalReasons(const ekf_slam::ScanMatcherCounters& c) {
  return std::to_string(c.refused_by_odometry) + " of them disagreed with the wheels, " +
         std::to_string(c.refused_by_correction) + " corrections beyond max_correction_*, " +
         std::to_string(c.refused_by_fit) + " too few points, pairs or inliers";
}

std::string loopClosureLine(const ekf_slam::LoopCloser* closer) {
  if (!closer) return "off";
  const ekf_slam::LoopClosureCounters& c = closer->counters();
  std::ostringstream line;
  line.setf(std::ios::fixed);
  line.precision(3);
  line << c.key_scans << " key scans (" << c.released
       << " without readings: their place was full), " << c.candidates << " candidates verified ("
       << c.refused << " refused: " << c.refused_by_score << " scored under min_score, "
       << c.refused_by_fit << " failed the fine match, " << c.refused_as_degenerate
       << " sliding along a corridor, " << c.ambiguous << " ambiguous), " << c.accepted
       << " loops accepted (" << c.dropped << " dropped by the kernel at the end, "
       << c.inconsistent << " refused as inconsistent with the graph, " << c.unconfirmed
       << " wide-window matches never confirmed), " << c.heading_loops
       << " heading loops between the walls of one place, " << c.optimisations
       << " optimisations; verification " << c.verification_seconds << " s, optimisation "
       << c.optimisation_seconds << " s";
  return line.str();
}

// The full smoother's wheel edges and the wheel noise they were weighted by.
std::string wheelEdgesLine(const ekf_slam::WheelNoise& wheels) {
  std::ostringstream line;
  if (wheels.edges == 0) {
    line << "none (" << wheels.samples << " steps where the wheels and the motion edges differ)";
    return line.str();
  }
  line.precision(4);
  line << wheels.edges << ", the wheels' noise learned from " << wheels.samples
       << " steps: " << wheels.sigma_per_sqrt_metre.x() << " m forward, "
       << wheels.sigma_per_sqrt_metre.y() << " m sideways, "
       << ekf_slam::radToDeg(wheels.sigma_per_sqrt_metre.z()) << " deg per sqrt(m)";
  return line.str();
}

// The command line.
struct Arguments {
  std::string bag_path, carmen_path, out_dir, config_path, preset, export_dir, save_state, resume;
  long max_scans = -1;
  long first_scan = 0;
  bool figures = true;
  bool maps = true;
  bool trace = false;
  bool print_config = false;
  bool localize_only = false;
  bool global = false;
};

// Returns -1 to go on, else the exit code.
int parseArguments(int argc, char** argv, Arguments* a) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    // roslaunch appends __name:=… and __log:=…; remappings mean nothing here.
    if (arg.rfind("__", 0) == 0 && arg.find(":=") != std::string::npos) continue;
    if (arg == "--bag" && i + 1 < argc) {
      a->bag_path = argv[++i];
    } else if (arg == "--carmen" && i + 1 < argc) {
      a->carmen_path = argv[++i];
    } else if (arg == "--out" && i + 1 < argc) {
      a->out_dir = argv[++i];
    } else if (arg == "--config" && i + 1 < argc) {
      a->config_path = argv[++i];
    } else if (arg == "--preset" && i + 1 < argc) {
      a->preset = argv[++i];
    } else if (arg == "--max-scans" && i + 1 < argc) {
      a->max_scans = std::atol(argv[++i]);
    } else if (arg == "--first-scan" && i + 1 < argc) {
      a->first_scan = std::max(0L, std::atol(argv[++i]));
    } else if (arg == "--save-state" && i + 1 < argc) {
      a->save_state = argv[++i];
    } else if (arg == "--resume" && i + 1 < argc) {
      a->resume = argv[++i];
    } else if (arg == "--localize-only") {
      a->localize_only = true;
    } else if (arg == "--global") {
      a->global = true;
    } else if (arg == "--no-figures") {
      a->figures = false;
    } else if (arg == "--no-maps") {
      a->maps = false;
      a->figures = false;  // the figures draw the maps
    } else if (arg == "--trace") {
      a->trace = true;
    } else if (arg == "--export-graphs" && i + 1 < argc) {
      a->export_dir = argv[++i];
    } else if (arg == "--print-config") {
      a->print_config = true;
    } else if (arg == "--help" || arg == "-h") {
      usage(std::cout);
      return 0;
    } else {
      usage();
      return 1;
    }
  }
  if (!a->print_config && (a->out_dir.empty() || a->bag_path.empty() == a->carmen_path.empty())) {
    usage();
    return 1;
  }
  if ((a->localize_only || a->global) && a->resume.empty()) {
    std::cerr << "ekf_slam_offline: --" << (a->global ? "global" : "localize-only")
              << " needs a map to localise in: --resume FILE\n";
    return 1;
  }
  return -1;
}

// The log, cut to --max-scans, and the laser mount from it unless the
// configuration gives one. Returns -1 to go on, else the exit code.
int readInput(const Arguments& a, ekf_slam::SlamConfig* config, ekf_slam::LogData* log) {
  const std::string input_error = a.bag_path.empty()
                                      ? ekf_slam::readCarmen(a.carmen_path, log)
                                      : ekf_slam::readBag(a.bag_path, config->input, log);
  if (!input_error.empty()) {
    std::cerr << "ekf_slam_offline: " << input_error << "\n";
    return 2;
  }
  if (log->unusable_scans > 0) {
    std::cerr << "ekf_slam_offline: warning: " << log->unusable_scans
              << " scans left out: their stamp or odometry is not finite (the first: "
              << log->first_unusable << ")\n";
  }
  if (a.max_scans >= 0 && static_cast<size_t>(a.max_scans) < log->scans.size()) {
    log->scans.resize(a.max_scans);
    log->last_stamp = log->first_stamp;
    for (const auto& s : log->scans) log->last_stamp = std::max(log->last_stamp, s.scan.stamp);
  }
  if (a.first_scan > 0) {
    const size_t drop = std::min(log->scans.size(), static_cast<size_t>(a.first_scan));
    log->scans.erase(log->scans.begin(), log->scans.begin() + drop);
    if (!log->scans.empty()) log->first_stamp = log->scans.front().scan.stamp;
  }
  if (!config->laser_pose_given) {
    if (!log->laser_pose_found) {
      std::cerr << "ekf_slam_offline: warning: no " << config->input.base_frame << " -> "
                << log->laser_frame
                << " transform in the log and none in the configuration (filter.laser_pose): "
                   "assuming the laser at base_link\n";
    }
    config->pipeline.filter.laser_pose = log->laser_pose;
  }
  return -1;
}

// --trace: every observation's association, for finding the scan where an
// estimate goes wrong (the live node publishes the same as `association`).
void openTrace(const std::string& path, std::ofstream* trace) {
  trace->open(path);
  *trace << "# stamp  x y theta (filtered, after the scan)  range bearing  decision  "
            "landmark_id  d2 (Mahalanobis squared of the match or the best candidate)  "
            "kind (corner / front_edge)  var_range var_range_bearing var_bearing (m^2, m rad, "
            "rad^2)\n";
  trace->precision(9);
}

void traceScan(double stamp, const ekf_slam::ScanResult& result, std::ofstream* trace) {
  const auto& decisions = result.iteration.association.observations;
  for (size_t k = 0; k < result.observations.size() && k < decisions.size(); ++k) {
    const ekf_slam::Matrix2& c = result.observations[k].covariance;
    char text[32];
    std::snprintf(text, sizeof(text), "%.6f", stamp);
    *trace << text << ' ' << result.pose.x << ' ' << result.pose.y << ' ' << result.pose.theta
           << ' ' << result.observations[k].z.range << ' ' << result.observations[k].z.bearing
           << ' ' << ekf_slam::toString(decisions[k].decision) << ' ' << decisions[k].landmark_id
           << ' ' << decisions[k].mahalanobis2 << ' '
           << (result.features.points_of_interest[result.observation_feature[k]].kind ==
                       ekf_slam::PointKind::kCorner
                   ? "corner"
                   : "front_edge")
           << ' ' << c(0, 0) << ' ' << c(0, 1) << ' ' << c(1, 1) << '\n';
  }
}

// Every scan through the pipeline in file order, then the back end's final
// optimisation. With --save-state, `to_save` receives the state after the
// last scan, before that optimisation (a later run goes on from the run as
// it stood: its resumed full smoother solves the saved scans again with
// the new ones).
// --global: the log's first scans searched for in the saved map, one more
// joined at a time, until the robot is found (at most kGlobalScans); the
// state's robot is moved there and the scans before it are left out.
// `line` receives the report's line. Returns "" or why the robot was not
// found.
constexpr size_t kGlobalScans = 200;

std::string placeGlobally(const ekf_slam::SlamConfig& config, ekf_slam::SlamState* state,
                          ekf_slam::LogData* log, std::string* line) {
  ekf_slam::GlobalLocalizer localizer(*state, config.pipeline.scan_matching,
                                      ekf_slam::GlobalLocalizationOptions());
  if (!localizer.mapError().empty()) return localizer.mapError();
  ekf_slam::GlobalPlacement placement;
  std::string last_reason = "no scan";  // of the last search
  size_t found = 0;
  for (; found < std::min(log->scans.size(), kGlobalScans); ++found) {
    const ekf_slam::LoggedScan& s = log->scans[found];
    placement =
        localizer.add(ekf_slam::scanPointsInRobotFrame(s.scan, config.pipeline.filter.laser_pose,
                                                       config.pipeline.scan_matching),
                      s.odometry);
    if (placement.found) break;
    if (placement.searched) {
      last_reason = placement.message;
      std::cerr << "global localisation, scan " << found + 1 << ": " << last_reason << "\n";
    }
  }
  if (!placement.found) {
    return "not found in the first " + std::to_string(found) +
           " scans (the last search: " + last_reason + ")";
  }
  ekf_slam::placeRobot(placement, ekf_slam::placementCovariance(), state);
  std::ostringstream text;
  text.setf(std::ios::fixed);
  text.precision(3);
  text << "global localisation: found at the log's scan " << found + 1 << " ("
       << log->scans[found].scan.stamp - log->scans.front().scan.stamp << " s after its first, "
       << placement.joined_scans << " scans joined), at " << placement.map_pose.x << " "
       << placement.map_pose.y << " " << placement.map_pose.theta << ", score " << placement.score
       << ", no other place above " << ekf_slam::GlobalLocalizationOptions().max_runner_up_ratio
       << " of it";
  *line = text.str();
  log->scans.erase(log->scans.begin(), log->scans.begin() + static_cast<long>(found));
  return "";
}

// --localize-only in a state with key scans: how each scan fits the saved
// map where the robot is estimated to stand, and the lost spells the live
// node's detector (relocalise_when_lost) would start on this log: lost
// after lost_scans in a row under lost_score, found again (here) once a
// scan fits again.
struct FitWatch {
  explicit FitWatch(const ekf_slam::SlamState& state, const ekf_slam::SlamConfig& config)
      : map(state, config.pipeline.scan_matching, ekf_slam::GlobalLocalizationOptions()) {}
  void add(const ekf_slam::Scan& scan, const ekf_slam::SlamConfig& config,
           const ekf_slam::ScanResult& result) {
    if (result.outcome != ekf_slam::ScanOutcome::kIterated &&
        result.outcome != ekf_slam::ScanOutcome::kSkippedNoMotion) {
      return;
    }
    const double score =
        map.fitNear(ekf_slam::scanPointsInRobotFrame(scan, config.pipeline.filter.laser_pose,
                                                     config.pipeline.scan_matching),
                    result.causal_pose);
    scores.push_back(score);
    stamps.push_back(scan.stamp);
    const bool was_lost = lost.lost();
    if (lost.add(score) && !was_lost) ++spells;
    if (lost.lost() && score >= ekf_slam::GlobalLocalizationOptions().lost_score) lost.reset();
  }
  ekf_slam::GlobalLocalizer map;
  ekf_slam::LostDetector lost;
  std::vector<double> scores, stamps;
  long spells = 0;
};

// The report's line of FitWatch.
void reportFit(const FitWatch& fit, std::ostream& report) {
  std::vector<double> sorted = fit.scores;
  std::sort(sorted.begin(), sorted.end());
  const ekf_slam::GlobalLocalizationOptions options;
  const long under =
      std::lower_bound(sorted.begin(), sorted.end(), options.lost_score) - sorted.begin();
  report << "fit to the saved map (--localize-only): median " << sorted[sorted.size() / 2]
         << ", 5 % of scans under " << sorted[sorted.size() / 20] << "; " << under << " of "
         << sorted.size() << " scans under " << options.lost_score << ", " << fit.spells
         << " lost spells (" << options.lost_scans << " scans in a row under it)\n";
}

void runSlam(const Arguments& a, const ekf_slam::SlamConfig& config, const ekf_slam::LogData& log,
             std::chrono::steady_clock::time_point wall_start, ekf_slam::SlamPipeline* pipeline,
             std::optional<ekf_slam::SlamState>* to_save, FitWatch* fit) {
  const bool tty = ::isatty(STDERR_FILENO);
  const size_t total = log.scans.size();
  size_t next_report = 0;
  std::ofstream trace;
  if (a.trace) openTrace(a.out_dir + "/association_trace.txt", &trace);
  for (size_t i = 0; i < total; ++i) {
    const ekf_slam::ScanResult result =
        pipeline->processScan(log.scans[i].scan, log.scans[i].odometry);
    if (fit != nullptr) fit->add(log.scans[i].scan, config, result);
    if (a.trace && result.outcome == ekf_slam::ScanOutcome::kIterated) {
      traceScan(log.scans[i].scan.stamp, result, &trace);
    }
    if (i + 1 >= next_report || i + 1 == total) {
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      progress(i + 1, total, pipeline->filter().landmarkCount(), seconds, tty);
      next_report += std::max<size_t>(1, total / (tty ? 200 : 10));
    }
  }
  if (tty) std::fprintf(stderr, "\n");
  if (!a.save_state.empty()) *to_save = pipeline->state(ekf_slam::describeSlamConfig(config));
  pipeline->finishLoopClosure();
}

// The trajectories of a run, one pose per scan with its header stamp.
struct Trajectories {
  std::vector<ekf_slam::StampedPose> filtered, smoothed, rts, odometry, optimized;
  ekf_slam::FullSmootherResult smoother;
  ekf_slam::LandmarkGraph smoother_problem;  // with --export-graphs
  double smoothing_seconds = 0.0;
  // The final trajectory: loop-closed when loop closure is on, else smoothed.
  const std::vector<ekf_slam::StampedPose>& final() const {
    return optimized.empty() ? smoothed : optimized;
  }
};

void smooth(const Arguments& a, const ekf_slam::LogData& log,
            const ekf_slam::SlamPipeline& pipeline, Trajectories* t) {
  t->filtered = pipeline.filteredScanPoses();
  const auto smoothing_start = std::chrono::steady_clock::now();
  t->smoothed = pipeline.smoothedScanPoses(&t->smoother,
                                           a.export_dir.empty() ? nullptr : &t->smoother_problem);
  t->smoothing_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - smoothing_start).count();
  t->rts = pipeline.rtsScanPoses();
  for (const auto& s : log.scans) t->odometry.push_back({s.scan.stamp, s.odometry});
  t->optimized = pipeline.optimizedScanPoses();
}

// The trajectory files, the filter's covariances, the landmark map and the
// first and last scans; empty on success, else what failed.
std::string writeResults(const std::string& dir, const ekf_slam::SlamConfig& config,
                         const ekf_slam::LogData& log, const ekf_slam::SlamPipeline& pipeline,
                         const Trajectories& t) {
  std::string error = ekf_slam::writeTrajectory(dir + "/trajectory_filtered.txt", t.filtered);
  if (error.empty())
    error = ekf_slam::writeTrajectory(dir + "/trajectory_smoothed.txt", t.smoothed);
  // What a live run publishes for each scan at that scan's time.
  if (error.empty()) {
    error = ekf_slam::writeTrajectory(dir + "/trajectory_live.txt", pipeline.causalScanPoses());
  }
  if (error.empty()) error = ekf_slam::writeTrajectory(dir + "/trajectory_rts.txt", t.rts);
  if (error.empty())
    error = ekf_slam::writeTrajectory(dir + "/trajectory_odometry.txt", t.odometry);
  if (error.empty()) error = writeFilteredCovariances(dir + "/covariance_filtered.txt", pipeline);
  if (error.empty() && config.pipeline.scan_matching.enabled) {
    // The control source alone (scan-matched odometry, before the filter).
    std::vector<ekf_slam::StampedPose> matched;
    for (const ekf_slam::ScanRecord& r : pipeline.scans()) matched.push_back({r.stamp, r.odometry});
    error = ekf_slam::writeTrajectory(dir + "/trajectory_scan_matched.txt", matched);
  }
  // The loop-closed trajectory (pose graph over key scans), when on.
  if (error.empty() && !t.optimized.empty()) {
    error = ekf_slam::writeTrajectory(dir + "/trajectory_optimized.txt", t.optimized);
  }
  if (error.empty()) {
    // The same file as the live node's save_map, line extents and
    // endpoints included.
    error = ekf_slam::writeLandmarkMap(
        dir + "/landmarks.yaml",
        ekf_slam::toLandmarkMapFile(pipeline.filter(), pipeline.lineSupport(), "map"));
  }
  if (error.empty()) {
    error = writeFirstLastScans(dir + "/first_last_scans.txt", log, t.odometry, t.final(),
                                config.pipeline.filter.laser_pose);
  }
  return error;
}

// The occupancy grids from the final, the filtered and the odometry
// trajectories.
std::string writeMaps(const std::string& dir, const ekf_slam::SlamConfig& config,
                      const ekf_slam::LogData& log, const Trajectories& t) {
  const Pose2 laser = config.pipeline.filter.laser_pose;
#ifdef __GLIBC__
  // The loop verification's grids and the smoother's matrices are freed by
  // now, but glibc keeps their pages in the heap, beneath the occupancy
  // grids about to be built: hand them back first (hospital log: peak
  // 306 → 295 MiB).
  malloc_trim(0);
#endif
  std::string error = buildMap(config.map, log, t.final(), laser).save(dir + "/map");
  if (error.empty())
    error = buildMap(config.map, log, t.filtered, laser).save(dir + "/map_filtered");
  if (error.empty())
    error = buildMap(config.map, log, t.odometry, laser).save(dir + "/map_odometry");
  return error;
}

// The figures, drawn by a Python script in a child process.
void drawFigures(const std::string& dir) {
  const std::string script = programDir() + "/plot_offline.py";
  const std::string command = "/usr/bin/python3 '" + script + "' '" + dir + "'";
  if (::access(script.c_str(), R_OK) != 0 || std::system(command.c_str()) != 0) {
    std::cerr << "ekf_slam_offline: warning: figures not drawn (" << script << ")\n";
  }
}

// report.txt, section by section.
void reportInput(const Arguments& a, const ekf_slam::SlamConfig& config,
                 const ekf_slam::LogData& log, std::ostream& report) {
  const Pose2 laser = config.pipeline.filter.laser_pose;
  report << "input: " << (a.bag_path.empty() ? a.carmen_path : a.bag_path) << "\n"
         << "scans: " << log.scans.size() << " (" << log.scans_out_of_time_order
         << " with a stamp not after the previous one)\n"
         << "scans left out (stamp not finite, odometry not finite or beyond 1e6 m): "
         << log.unusable_scans
         << (log.unusable_scans > 0 ? ", the first " + log.first_unusable : std::string()) << "\n"
         << "data duration: " << log.duration() << " s\n"
         << "odometry samples: " << log.odometry_samples << ", scans with an odometry gap > "
         << config.input.max_odometry_gap << " s: " << log.odometry_gaps << "\n"
         << "laser pose (base_link -> laser): " << laser.x << " " << laser.y << " " << laser.theta
         << (config.laser_pose_given ? " (configuration)"
             : log.laser_pose_found  ? " (log)"
                                     : " (assumed)")
         << (log.laser_inverted ? ", upside down in the log's tf: scans mirrored" : "") << "\n";
  if (a.first_scan > 0) report << "log scans left out before scan " << a.first_scan << "\n";
  if (!a.resume.empty()) {
    report << "resumed from the saved state " << a.resume
           << (a.localize_only ? " (localisation only: no landmark added)" : "") << "\n";
  }
  if (!a.save_state.empty()) report << "state saved to " << a.save_state << "\n";
}

void reportFrontAndBackEnd(const ekf_slam::SlamConfig& config,
                           const ekf_slam::SlamPipeline& pipeline, std::ostream& report) {
  const ekf_slam::PipelineCounters c = pipeline.counters();
  report << "iterations: " << c.iterations << ", skipped (no motion): " << c.skipped_no_motion
         << ", skipped (time not increasing): " << c.time_not_increasing
         << ", odometry jumps: " << c.odometry_jumps << ", bad input: " << c.bad_input
         << ", update failures: " << c.update_failures << "\n"
         << "scan matching: "
         << (config.pipeline.scan_matching.enabled
                 ? std::to_string(c.scan_matches) + " scans matched, " +
                       std::to_string(c.scan_match_refusals) +
                       " fell back to the odometry increment (" + refusalReasons(c.front_end) +
                       "), " + std::to_string(c.front_end.unchecked_by_odometry) +
                       " matches not checked against the wheels (stamp not after the "
                       "previous scan's)"
                 : std::string("off (raw odometry is the control)"))
         << "\n"
         << (c.local_matcher_runs
                 ? "local matcher (the full smoother's motion edges): " +
                       std::to_string(c.local_matcher.matched) + " scans matched, " +
                       std::to_string(c.local_matcher.refused) +
                       " fell back to the odometry increment (" + refusalReasons(c.local_matcher) +
                       ")\n"
                 : std::string())
         << "loop closure: " << loopClosureLine(pipeline.loopCloser())
         << "; the filter re-anchored " << c.reanchors << " times\n";
}

void reportLandmarks(const ekf_slam::SlamConfig& config, const ekf_slam::SlamPipeline& pipeline,
                     std::ostream& report) {
  const ekf_slam::PipelineCounters c = pipeline.counters();
  const ekf_slam::LandmarkSet set = config.pipeline.landmarks;
  report << "observations (landmark candidates): " << c.observations << " ("
         << (c.iterations ? static_cast<double>(c.observations) / c.iterations : 0.0)
         << " per iteration), matched: " << c.matches << ", ambiguous: " << c.ambiguous
         << ", new: " << c.new_landmarks << "\n"
         << "landmarks: " << pipeline.filter().landmarkCount() << " (" << c.new_landmarks
         << " created, " << c.pruned << " pruned as seen once, " << c.pruned_rare
         << " as seen rarely, " << c.marginalised << " marginalised by max_landmarks)"
         << ", average NIS: " << (c.matches ? c.nis_sum / c.matches : 0.0) << " (expected 2)\n"
         << "line landmarks (" << ekf_slam::toString(set) << "): "
         << (set == ekf_slam::LandmarkSet::kPoints || set == ekf_slam::LandmarkSet::kPointsAndMecp
                 ? std::string("none")
                 : std::to_string(c.line_observations) +
                       " segments offered, matched: " + std::to_string(c.line_matches) + " (" +
                       std::to_string(c.line_endpoint_matches) + " through endpoint points)" +
                       ", ambiguous: " + std::to_string(c.line_ambiguous) +
                       ", new: " + std::to_string(c.new_line_landmarks) +
                       ", refused (non-finite): " + std::to_string(c.lines_refused) +
                       ", update failures: " + std::to_string(c.line_update_failures) +
                       ", average NIS: " +
                       std::to_string(c.line_matches ? c.line_nis_sum / c.line_matches : 0.0) +
                       ", in the map: " + std::to_string(pipeline.lineSupport().size()))
         << "\n"
         << "MECP association (points+mecp): "
         << (set == ekf_slam::LandmarkSet::kPointsAndMecp
                 ? std::to_string(c.mecp_polygons) + " scans with a polygon round the robot, " +
                       std::to_string(c.mecp_group_matches) + " matched to one remembered (" +
                       std::to_string(c.mecp_pairings_changed) + " pairings changed), " +
                       std::to_string(c.mecp_group_refused) + " refused by the group gate, " +
                       std::to_string(c.mecp_remembered) + " remembered"
                 : std::string("off"))
         << "\n"
         << "room gating (rooms.enabled): "
         << (config.pipeline.rooms.enabled
                 ? std::to_string(c.room_rebuilds) + " rebuilds (" +
                       std::to_string(c.room_rebuild_failures) +
                       " without a usable map), last: " + std::to_string(c.rooms) + " rooms, " +
                       std::to_string(c.doorways) + " doorways"
                 : std::string("off"))
         << "\n";
}

void reportSmoother(const Trajectories& t, ekf_slam::SmootherMethod method, std::ostream& report) {
  if (method == ekf_slam::SmootherMethod::kRts) {
    report << "smoother: RTS over the pose alone (smoother.method: rts), " << t.rts.size()
           << " poses, " << t.smoothing_seconds << " s\n";
    return;
  }
  const ekf_slam::FullSmootherResult& smoother = t.smoother;
  report << "full smoother: " << smoother.poses.size() << " poses, " << smoother.landmarks.size()
         << " landmarks ("
         << (smoother.reassociated
                 ? "sightings re-associated, " + std::to_string(smoother.ambiguous_sightings) +
                       " ambiguous left out"
                 : std::string("the filter's associations"))
         << "), " << smoother.observation_edges << " observation edges, "
         << smoother.constraint_edges << " loop and heading-loop edges, "
         << smoother.detached_visits << " revisits detached; " << smoother.summary.iterations
         << " iterations (" << solveEndName(smoother.summary.end) << "), cost "
         << smoother.summary.initial_cost << " -> " << smoother.summary.final_cost << ", "
         << t.smoothing_seconds << " s\n"
         << "wheel edges: " << wheelEdgesLine(smoother.wheels) << "\n";
}

void reportTimes(const ekf_slam::LogData& log, double wall, double processing,
                 std::ostream& report) {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  report << "wall-clock: " << wall
         << " s, real-time factor: " << (wall > 0 ? log.duration() / wall : 0.0)
         << "x, peak memory: " << usage.ru_maxrss / 1024.0 << " MiB\n"
         << "processing: " << processing
         << " s (reading, scan matching, SLAM, smoothing, trajectories and maps; the figures "
            "excluded)\n";
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  if (const int exit_code = parseArguments(argc, argv, &args); exit_code >= 0) return exit_code;
  ekf_slam::SlamConfig config;
  // The built-in defaults, then --config, then the preset over both.
  const std::string preset_path =
      args.preset.empty() ? "" : programDir() + "/ekf_slam_" + args.preset + ".yaml";
  if (!preset_path.empty() && ::access(preset_path.c_str(), R_OK) != 0) {
    std::cerr << "ekf_slam_offline: no preset '" << args.preset << "' (" << preset_path
              << " is not readable; the presets are config/ekf_slam_<name>.yaml)\n";
    return 1;
  }
  for (const std::string& path : {args.config_path, preset_path}) {
    if (path.empty()) continue;
    const std::string error = ekf_slam::loadSlamConfigFile(path, &config);
    if (!error.empty()) {
      std::cerr << "ekf_slam_offline: bad configuration " << path << ":\n" << error << "\n";
      return 1;
    }
  }
  if (args.print_config) {
    std::cout << ekf_slam::describeSlamConfig(config);
    return 0;
  }
  // Whatever happens below, a report from an earlier run must not make this
  // directory look complete: report.txt is removed first and written last.
  ::unlink((args.out_dir + "/report.txt").c_str());

  const auto wall_start = std::chrono::steady_clock::now();
  ekf_slam::LogData log;
  if (const int exit_code = readInput(args, &config, &log); exit_code >= 0) return exit_code;
  if (::mkdir(args.out_dir.c_str(), 0755) != 0 && errno != EEXIST) {
    std::cerr << "ekf_slam_offline: cannot create " << args.out_dir << "\n";
    return 3;
  }
  ekf_slam::SlamPipeline pipeline(config.pipeline);
  std::string global_line;
  std::optional<FitWatch> fit;
  if (!args.resume.empty()) {
    ekf_slam::SlamState state;
    std::string error = ekf_slam::readSlamState(args.resume, &state);
    if (error.empty() && args.global) {
      error = placeGlobally(config, &state, &log, &global_line);
      if (!error.empty()) error = "global localisation in " + args.resume + ": " + error;
    }
    if (error.empty()) {
      error = pipeline.resume(state, args.global ? ekf_slam::ResumeAt::kPlacedRobot
                                                 : ekf_slam::ResumeAt::kWhereItStopped);
      if (!error.empty()) error = args.resume + ": " + error;
    }
    if (!error.empty()) {
      std::cerr << "ekf_slam_offline: cannot resume: " << error << "\n";
      return 2;
    }
    if (args.localize_only) {
      pipeline.mutableFilter().setMappingEnabled(false);
      fit.emplace(state, config);
      if (!fit->map.mapError().empty()) fit.reset();  // no key scans to fit
    }
  }
  std::optional<ekf_slam::SlamState> to_save;
  runSlam(args, config, log, wall_start, &pipeline, &to_save, fit ? &*fit : nullptr);
  Trajectories trajectories;
  smooth(args, log, pipeline, &trajectories);
  std::string error;
  if (to_save) error = ekf_slam::writeSlamState(args.save_state, *to_save);
  if (error.empty()) error = writeResults(args.out_dir, config, log, pipeline, trajectories);
  if (args.maps && error.empty()) error = writeMaps(args.out_dir, config, log, trajectories);
  if (error.empty() && !args.export_dir.empty()) {
    error = exportGraphs(args.export_dir, pipeline, config.pipeline, trajectories.smoother_problem);
  }
  if (!error.empty()) {
    std::cerr << "ekf_slam_offline: " << error << "\n";
    return 3;
  }
  const double processing = secondsSince(wall_start);
  if (args.figures) drawFigures(args.out_dir);

  std::ostringstream report;
  report.setf(std::ios::fixed);
  report.precision(3);
  reportInput(args, config, log, report);
  if (!global_line.empty()) report << global_line << "\n";
  if (fit && !fit->scores.empty()) {
    reportFit(*fit, report);
    std::ostringstream text;
    text.setf(std::ios::fixed);
    text << "# stamp fit: each scan's fit to the saved map near its causal pose\n";
    for (size_t k = 0; k < fit->scores.size(); ++k) {
      text << std::setprecision(6) << fit->stamps[k] << " " << std::setprecision(3)
           << fit->scores[k] << "\n";
    }
    const std::string error =
        ekf_slam::writeFileAtomically(args.out_dir + "/fit_to_saved_map.txt", text.str());
    if (!error.empty()) {
      std::cerr << "ekf_slam_offline: " << error << "\n";
      return 3;
    }
  }
  reportFrontAndBackEnd(config, pipeline, report);
  reportLandmarks(config, pipeline, report);
  reportSmoother(trajectories, config.pipeline.smoother.method, report);
  reportTimes(log, secondsSince(wall_start), processing, report);
  std::cout << report.str();
  // Last, and whole or not at all: a report says the run's files are there.
  const std::string report_error =
      ekf_slam::writeFileAtomically(args.out_dir + "/report.txt", report.str());
  if (!report_error.empty()) {
    std::cerr << "ekf_slam_offline: " << report_error << "\n";
    return 3;
  }
  return 0;
}
