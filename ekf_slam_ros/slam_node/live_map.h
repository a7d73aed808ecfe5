// The occupancy grid a live node publishes while the robot drives: built in
// its own thread from the back end's key scans at their loop-closed poses,
// so scan processing and the map → odom publication never wait for it.
// Published on `map` (nav_msgs/OccupancyGrid, latched, values -1 / 0..100
// as map_server and amcl expect) and `map_metadata`.
#pragma once

#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
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

  // Hands a snapshot to the worker. False, and nothing done, while the
  // previous one is still being built (the caller tries again later).
  bool submit(std::vector<SlamPipeline::KeyScan> keys, const Pose2& laser,
              const std_msgs::Header& header);
  long published() const;
  double lastBuildSeconds() const;
  // The last grid published and when; false when none was (or after
  // forget()).
  bool latest(nav_msgs::OccupancyGrid* map, std::chrono::steady_clock::time_point* when) const;
  void forget();

 private:
  void run();

  OccupancyGridOptions options_;
  ros::Publisher map_publisher_, metadata_publisher_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  bool pending_ = false;  // a snapshot waits for (or is in) the worker
  std::vector<SlamPipeline::KeyScan> keys_;
  Pose2 laser_;
  std_msgs::Header header_;
  long published_ = 0;
  double last_build_seconds_ = 0.0;
  bool have_latest_ = false;
  nav_msgs::OccupancyGrid latest_;
  std::chrono::steady_clock::time_point latest_time_;
  std::thread worker_;
};

}  // namespace ekf_slam
