// A saved SLAM state: what a later run needs to go on mapping where this one
// stopped (SlamPipeline::state / SlamPipeline::resume).
//
// It holds the filter (mean, covariance, the landmarks' bookkeeping and the
// lines' extents), the loop closer (key scans with their readings, the pose
// graph with its loops and heading edges, the search's bookkeeping), the
// link between the two (the filter's pose at each key scan, the key scan
// each landmark hangs off, the graph's frame in the map frame, where the
// robot stopped), the laser mount, the configuration text the map was
// made with, and the history of the scans and iterations (scan_history.h)
// that the smoothers and the trajectory files read: a resumed run's full
// smoother solves the saved scans and the new ones together, as one run's
// would, and its trajectories cover both. The history holds at most the
// newest kSavedHistoryScans scans (10,000, the live node's own bound); the
// rest is bounded by the building (landmarks, key scans: the loop closer
// lets the readings of a place's surplus key scans go). The occupancy grid
// is built again from the key scans.
//
// The front end's scan-matching map goes with them (its global mode; a
// local map refills within a few scans), so that new scans match against
// the old ones from the first. What starts afresh on a resume: the
// counters of the scans and the readings a live node keeps for its grid.
//
// The file (writeSlamState / readSlamState): the magic line
// "EKF-SLAM state\n", the format version (uint32), the payload's length
// (uint64), the payload, and its FNV-1a 64-bit checksum; numbers
// little-endian, doubles bit for bit. Written atomically (a reader sees the
// old file or the new one whole); a truncated or corrupt file, one of
// another format version and one whose numbers do not fit together are
// refused with a message naming the problem.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ekf_slam_core/filter/filter_state.h"
#include "ekf_slam_core/filter/line_support.h"
#include "ekf_slam_core/geometry/stamped_pose.h"
#include "ekf_slam_core/loop_closure/loop_closer.h"
#include "ekf_slam_core/pipeline/scan_history.h"
#include "ekf_slam_core/scan_matching/scan_matcher.h"

namespace ekf_slam {

// The version this build writes; it reads this one and version 3 (without
// the point landmarks' estimates at their latest sightings). Versions 1
// and 2 held no history of the scans and are refused by name.
constexpr uint32_t kSlamStateVersion = 4;
constexpr uint32_t kOldestSlamStateVersion = 3;

// The loop-closing back end's link to the filter (BackEndLink).
struct BackEndLinkState {
  LoopCloserState closer;
  std::vector<Pose2> key_filtered;                 // the filter's pose at each key scan (map)
  std::vector<std::pair<int, int>> landmark_scan;  // landmark id → the scan last observing it
  // Point landmark id → its estimate right after that scan (map frame);
  // empty in a version 3 state, whose landmarks are then drawn from their
  // estimates.
  std::vector<std::pair<int, Vector2>> point_seen_at;
  bool has_map_from_graph = false;
  Pose2 map_from_graph;  // the graph's frame in the map frame
  Pose2 last_front_end;  // the front end's pose at the last scan (the closer's frame)
  // The history record of each of the closer's newest scans (its last
  // record_of_loop_scan.size() scans), so that a loop to a saved key scan
  // joins that scan's iteration in a resumed run's full smoother.
  std::vector<long> record_of_loop_scan;
};

struct SlamState {
  std::string configuration;  // the options the map was made with, as text (for people)
  Pose2 laser_pose;           // base_link → laser
  FilterState filter;
  std::unordered_map<int, LineSupport> line_support;
  BackEndLinkState back_end;
  // The front end's scan-matching map (global map mode); without it a
  // resumed front end starts a map of its own in a frame of its own.
  bool has_front_end = false;
  ScanMatchingOdometryState front_end;
  ScanHistoryState history;
  long scans = 0;  // scans processed before the save (all runs together)
  // The last iteration: its stamp and the robot's raw odometry there. A
  // resumed run whose first scan follows within kResumeGap with odometry
  // that moved less than a jump (a log in parts, a node reloaded while the
  // driver ran on) takes that motion; otherwise the robot stands where the
  // saved run stopped.
  bool has_last_iteration = false;
  double last_stamp = 0.0;
  Pose2 last_raw_odometry;
};

// s: see SlamState::last_stamp.
constexpr double kResumeGap = 10.0;

// At most this many scans' history go into a state (SlamPipeline::state):
// the newest, as the live node's history_max_scans keeps them (its
// default), so that a state is bounded by the building, not by the hours
// driven, offline too.
constexpr long kSavedHistoryScans = 10000;

// Where a resumed run's robot stands at its first scan (SlamPipeline::resume).
enum class ResumeAt {
  kWhereItStopped,  // where the saved run stopped (see SlamState::last_stamp)
  kPlacedRobot,     // where placeRobot put it (global_localization.h)
};

// The file's bytes, and back. decodeSlamState leaves `state` unchanged and
// returns the problem when the bytes are not a whole, consistent state of
// kSlamStateVersion.
std::string encodeSlamState(const SlamState& state);
std::string decodeSlamState(const std::string& bytes, SlamState* state);

// Empty on success, else the problem, naming `path`.
std::string writeSlamState(const std::string& path, const SlamState& state);
std::string readSlamState(const std::string& path, SlamState* state);

}  // namespace ekf_slam
