// The occupancy grid a live node publishes while the robot drives, built in
// its own thread so that scan processing and the map → odom publication
// never wait for it. Two sources:
//   - with loop closure, the back end's key scans at their loop-closed
//     poses: a loop moves them, so each grid is cast anew from all of them;
//   - without (the simulation's and the thesis's configurations), the
//     scans the pipeline's history keeps, at the causal poses they were
//     given: those never move, so each scan is cast once into a grid the
//     worker keeps, and each grid costs only the scans since the last.
// Published on `map` (nav_msgs/OccupancyGrid, latched, values -1 / 0..100
// as map_server and amcl expect) and `map_metadata`, always together.
#pragma once

#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"

namespace ekf_slam {

// nav_msgs/OccupancyGrid of a grid: -1 unknown, 0 free, 100 occupied
// (OccupancyGrid::trinaryValues, map_server's thresholds).
nav_msgs::OccupancyGrid toOccupancyGridMessage(const OccupancyGrid& grid,
                                               const std_msgs::Header& header);

// The grid of key scans (robot-frame readings) at their poses, the laser at
// `laser` on the robot: one pass, sized once.
OccupancyGrid gridFromKeyScans(const std::vector<SlamPipeline::KeyScan>& keys, const Pose2& laser,
                               const OccupancyGridOptions& options);

class LiveMapPublisher {
 public:
  LiveMapPublisher(ros::NodeHandle node, const OccupancyGridOptions& options);
  ~LiveMapPublisher();  // finishes the grid being built, then stops
  LiveMapPublisher(const LiveMapPublisher&) = delete;
  LiveMapPublisher& operator=(const LiveMapPublisher&) = delete;

  // Hands the worker every key scan: the next grid is cast from them
  // alone. False, and nothing done, while the previous grid is still being
  // built (the caller tries again later).
  bool submit(std::vector<SlamPipeline::KeyScan> keys, const Pose2& laser,
              const std_msgs::Header& header);
  // Hands the worker the scans since the last ones handed (each at its
  // causal pose): the next grid is the kept one with them cast in. False,
  // and nothing done, while the previous grid is still being built.
  bool submitScans(std::vector<KeptScan> scans, const Pose2& laser, const std_msgs::Header& header);
  long published() const;
  double lastBuildSeconds() const;
  // The last grid published and when; false when none was (or after
  // forget()).
  bool latest(nav_msgs::OccupancyGrid* map, std::chrono::steady_clock::time_point* when) const;
  // A new map: the grid kept from earlier scans goes, and a grid being
  // built for the old map is not published.
  void newMap();
  // newMap(), and latest() has nothing until the next grid.
  void forget();

 private:
  struct Job {
    std::vector<SlamPipeline::KeyScan> keys;  // the whole map …
    std::vector<KeptScan> scans;              // … or the scans to add to the kept grid
    bool incremental = false;
    Pose2 laser;
    std_msgs::Header header;
    long generation = 0;
  };
  bool hand(Job job);
  void run();
  // The grid of `job`, as the message (on the worker).
  nav_msgs::OccupancyGrid build(const Job& job);

  OccupancyGridOptions options_;
  ros::Publisher map_publisher_, metadata_publisher_;
  std::mutex publish_mutex_;  // held while a grid is published; newMap() waits for it
  mutable std::mutex mutex_;  // guards what follows
  std::condition_variable wake_;
  bool stop_ = false;
  bool pending_ = false;  // a job waits for (or is in) the worker
  Job job_;
  long generation_ = 0;  // newMap() calls
  long published_ = 0;
  double last_build_seconds_ = 0.0;
  bool have_latest_ = false;
  nav_msgs::OccupancyGrid latest_;
  std::chrono::steady_clock::time_point latest_time_;
  // The worker's own: the grid of the scans cast so far, and its map's generation.
  std::optional<OccupancyGrid> kept_grid_;
  long kept_generation_ = -1;
  std::thread worker_;
};

}  // namespace ekf_slam
