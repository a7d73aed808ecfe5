// ekf_slam_merge_states: two saved states of one building (ekf_slam_offline
// --save-state, the live node's ~write_state) joined into one map.
//
//   ekf_slam_merge_states FIRST.state SECOND.state --out DIR [--config YAML]
//
// The second run is found in the first's map by the global localisation,
// the loops between the two runs are matched, and both histories are
// smoothed as one problem (ekf_slam_core/pipeline/state_merge.h). Writes
// into DIR:
//   trajectory_merged.txt  one pose per scan of both runs, the first run's
//                          map frame ("stamp x y theta")
//   map.pgm, map.yaml      the occupancy grid of both runs' key scans at
//                          their merged poses (map_server files)
//   report.txt             the alignment, the loops and the solve
// Exit codes: 0 merged, 1 bad arguments, 2 a state cannot be read or the
// runs cannot be joined (the message says why), 3 the output cannot be
// written.
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "ekf_slam_core/io/trajectory_file.h"
#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_core/pipeline/state_merge.h"
#include "ekf_slam_ros/offline/slam_config.h"

namespace {

int usage(const char* why) {
  std::cerr << "ekf_slam_merge_states: " << why << "\n"
            << "usage: ekf_slam_merge_states FIRST.state SECOND.state --out DIR [--config YAML]\n"
               "  joins two saved states of one building: the second run placed in the\n"
               "  first's map, both smoothed as one (trajectory_merged.txt, map.pgm/.yaml,\n"
               "  report.txt in DIR). --config: the configuration both runs were made with\n"
               "  (default: the built-in one).\n";
  return 1;
}

// Both runs' key scans cast at the poses the merged trajectory gives their scans.
void castKeyScans(const ekf_slam::SlamState& state,
                  const std::unordered_map<double, ekf_slam::Pose2>& at_stamp,
                  const ekf_slam::Pose2& laser, ekf_slam::OccupancyGrid* grid) {
  for (const ekf_slam::LoopCloserState::Key& key : state.back_end.closer.keys) {
    const auto found = at_stamp.find(key.stamp);
    if (key.points.empty() || found == at_stamp.end()) continue;
    const ekf_slam::Pose2& pose = found->second;
    std::vector<ekf_slam::Vector2> ends;
    ends.reserve(key.points.size());
    for (const ekf_slam::Vector2& p : key.points) ends.push_back(ekf_slam::transformFrom(pose, p));
    grid->insertHits(ekf_slam::compose(pose, laser).translation(), ends);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> states;
  std::string out_dir, config_path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--out" && i + 1 < argc) {
      out_dir = argv[++i];
    } else if (arg == "--config" && i + 1 < argc) {
      config_path = argv[++i];
    } else if (arg == "-h" || arg == "--help") {
      return usage("joins two saved states");
    } else if (!arg.empty() && arg[0] == '-') {
      return usage(("unknown option " + arg).c_str());
    } else {
      states.push_back(arg);
    }
  }
  if (states.size() != 2) return usage("give two state files");
  if (out_dir.empty()) return usage("--out DIR is required");

  ekf_slam::SlamConfig config;
  if (!config_path.empty()) {
    if (const std::string error = ekf_slam::loadSlamConfigFile(config_path, &config);
        !error.empty()) {
      std::cerr << "ekf_slam_merge_states: " << config_path << ":\n" << error << "\n";
      return 1;
    }
  }
  ekf_slam::SlamState first, second;
  for (const auto& [path, state] : {std::pair{states[0], &first}, std::pair{states[1], &second}}) {
    if (const std::string error = ekf_slam::readSlamState(path, state); !error.empty()) {
      std::cerr << "ekf_slam_merge_states: " << error << "\n";
      return 2;
    }
  }
  // The key scans' readings hang off the laser mount the states were made with.
  config.pipeline.filter.laser_pose = first.laser_pose;

  const auto start = std::chrono::steady_clock::now();
  const ekf_slam::StateMerge merge = ekf_slam::mergeStates(first, second, config.pipeline);
  if (!merge.error.empty()) {
    std::cerr << "ekf_slam_merge_states: cannot merge " << states[0] << " and " << states[1] << ": "
              << merge.error << "\n";
    return 2;
  }
  const double align_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ekf_slam::FullSmootherResult details;
  const std::vector<ekf_slam::StampedPose> merged = merge.problem->solve(&details);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  ::mkdir(out_dir.c_str(), 0755);
  std::string error = ekf_slam::writeTrajectory(out_dir + "/trajectory_merged.txt", merged);
  std::unordered_map<double, ekf_slam::Pose2> at_stamp;
  for (const ekf_slam::StampedPose& p : merged) at_stamp.emplace(p.stamp, p.pose);
  ekf_slam::OccupancyGrid grid(config.map);
  castKeyScans(first, at_stamp, first.laser_pose, &grid);
  castKeyScans(second, at_stamp, first.laser_pose, &grid);
  if (error.empty()) error = grid.save(out_dir + "/map");

  std::ostringstream report;
  report.setf(std::ios::fixed);
  report.precision(3);
  const ekf_slam::Pose2& T = merge.first_from_second;
  report << "merged: " << states[0] << " (" << merge.first_scans << " scans, " << merge.first_loops
         << " loops) and " << states[1] << " (" << merge.second_scans << " scans, "
         << merge.second_loops << " loops)\n"
         << "alignment: the second state's key scan " << merge.aligned_key
         << " found in the first's"
         << " map after " << merge.second_keys_tried << " searches, score " << merge.placement.score
         << "; the second map frame at " << T.x << " " << T.y << " " << T.theta << " in the first\n"
         << "loops between the runs: " << merge.cross_loops << " (" << merge.cross_tried
         << " matches tried in " << merge.loop_rounds << " rounds)\n"
         << "full smoother: " << details.poses.size() << " poses, " << details.landmarks.size()
         << " landmarks, " << details.constraint_edges << " loop edges, "
         << details.summary.iterations << " iterations, cost " << details.summary.initial_cost
         << " -> " << details.summary.final_cost << "\n"
         << "time: " << align_seconds << " s to align and join, " << seconds << " s in all\n";
  if (error.empty()) {
    std::ofstream file(out_dir + "/report.txt");
    file << report.str();
    if (!file) error = out_dir + "/report.txt: cannot be written";
  }
  if (!error.empty()) {
    std::cerr << "ekf_slam_merge_states: " << error << "\n";
    return 3;
  }
  std::cout << report.str();
  return 0;
}
