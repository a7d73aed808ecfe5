// Global relocalisation of a robot localising in a loaded state (~load_state
// with localize_only): a kidnapped robot, carried elsewhere, or one started
// where the state's robot did not stop.
//
// Each processed scan is scored against the saved map near the pose the node
// publishes (GlobalLocalizer::fitNear); when lost_scans in a row fit it
// under lost_score (LostDetector) the robot is lost, and its scans go to a
// search thread (GlobalLocalizer::add: the whole map at every heading,
// seconds on a large building) until a place is found. The node takes the
// place at its next scan, carried on by the odometry since (movedOn), and
// moves its SLAM state there (placeRobot). Nothing here touches the SLAM
// state: the spin thread asks (afterScan, takeFound), the thread searches.
// A search's result for a map that was replaced meanwhile is dropped.
#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ekf_slam_core/pipeline/global_localization.h"

namespace ekf_slam {

class Relocaliser {
 public:
  // `icp`: the configuration's scan matcher settings (GlobalLocalizer).
  Relocaliser(const ScanMatcherOptions& icp, const GlobalLocalizationOptions& options);
  ~Relocaliser();  // the search under way finishes, then the thread stops
  Relocaliser(const Relocaliser&) = delete;
  Relocaliser& operator=(const Relocaliser&) = delete;

  // Localising in `state` from now on: its map is built for the search on
  // the thread (until then scans are not scored). Replaces any earlier map.
  void watch(SlamState state);
  // Not localising in a saved map (mapping, a new map): nothing is watched.
  void stop();

  // After each processed scan: its readings in the robot frame, the raw
  // odometry and the pose published (map frame).
  void afterScan(const std::vector<Vector2>& robot_points, const Pose2& odometry,
                 const Pose2& map_pose);
  // Before a scan at `odometry`: the place found for an earlier scan,
  // carried on to this one; empty when none is waiting.
  std::optional<GlobalPlacement> takeFound(const Pose2& odometry);

  struct Status {
    bool watching = false;  // a saved map is watched (built or being built)
    bool lost = false;      // lost, being searched for
    double score = 0.0;     // the last scored scan's fit
    long times_lost = 0;
    long times_found = 0;
    long searches = 0;        // searches run (each lost spell: until found)
    std::string last_search;  // why the last search did not place the robot ("" if it did)
    std::string map_error;    // the watched state cannot be searched: why
  };
  Status status() const;
  // A saved map is watched (status().watching, without copying the rest).
  bool watching() const;

 private:
  struct Job {
    std::vector<Vector2> points;
    Pose2 odometry;
    bool restart = false;  // the first scan of a lost spell: the joined scans before go
  };
  void run();

  ScanMatcherOptions icp_;
  GlobalLocalizationOptions options_;
  LostDetector lost_;  // spin thread only

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool closing_ = false;
  long generation_ = 0;                                     // of the watched map
  std::optional<SlamState> to_build_;                       // a map waiting to be built
  std::shared_ptr<GlobalLocalizer> localizer_;              // the built map (null: none yet)
  std::deque<Job> jobs_;                                    // scans of a lost robot, to search with
  std::optional<std::pair<GlobalPlacement, Pose2>> found_;  // and the odometry it is at
  Status status_;
  std::thread thread_;
};

}  // namespace ekf_slam
