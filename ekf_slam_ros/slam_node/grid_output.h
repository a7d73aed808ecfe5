// The occupancy grid on `map`: the live map (LiveMapPublisher, built in its
// own thread every map_update_interval: from the back end's key scans with
// loop closure, else from the scans the history keeps) and the grids the
// services publish themselves
// (~smooth, ~load_map). currentGrid() is the newer of the two, what
// ~save_map writes. A grid loaded for localisation stays on `map`: the
// live map does not replace it.
//
// Owns the `map` publisher, the live map and its timer, and the grid the
// node last published itself.
#pragma once

#include <nav_msgs/MapMetaData.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>

#include <chrono>
#include <memory>
#include <optional>

#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_ros/slam_node/live_map.h"
#include "ekf_slam_ros/slam_node/slam_control.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"

namespace ekf_slam {

class GridOutput {
 public:
  // `live`: build the live map (map_update_interval > 0, and loop closure
  // on or the scans' readings kept). `params` and `slam` must outlive the
  // output.
  GridOutput(ros::NodeHandle node, const SlamNodeParams& params, const OccupancyGridOptions& map,
             bool live, const SlamControl& slam);

  // The grid last published on `map`; false when there is none.
  bool currentGrid(nav_msgs::OccupancyGrid* map) const;
  // Publishes a grid of the node's own (~smooth, ~load_map) on `map`.
  void publish(const nav_msgs::OccupancyGrid& map);
  // true: the live map leaves the grid on `map` alone (a loaded map for
  // localisation); false: it replaces it with its next grid.
  void hold(bool hold) { hold_ = hold; }
  // A new pipeline: its key scans and scans are all new to the live map,
  // which starts a new grid from them.
  void restart();
  // ~reset: no grid at all until the next one is built.
  void forget();
  // The live map, for /diagnostics; null without one.
  const LiveMapPublisher* liveMap() const { return live_map_.get(); }

 private:
  // A new grid when the key scans changed (a new key scan or a new
  // optimisation) and the worker is free; it never blocks the scans.
  void onMapTimer(const ros::TimerEvent&);
  // With loop closure: every key scan, when they changed since the last grid.
  void submitKeyScans(const SlamPipeline& pipeline, const Pose2& laser,
                      const std_msgs::Header& header);
  // Without: the kept scans the live map has not cast yet.
  void submitNewScans(const SlamPipeline& pipeline, const Pose2& laser,
                      const std_msgs::Header& header);

  const SlamNodeParams& params_;
  const SlamControl& slam_;
  ros::Publisher map_publisher_;
  ros::Publisher metadata_publisher_;
  std::unique_ptr<LiveMapPublisher> live_map_;  // null when there is no live map
  ros::Timer map_timer_;
  long optimisations_mapped_ = -1;  // back-end optimisations seen by the last grid submitted
  int keys_mapped_ = 0;             // key scans in that grid
  long scans_mapped_ =
      -1;  // without loop closure: the scans before this one are cast (-1: none yet)
  // The grid the node published itself and when; the live map keeps its own.
  std::optional<nav_msgs::OccupancyGrid> node_grid_;
  std::chrono::steady_clock::time_point node_grid_time_;
  bool hold_ = false;
};

}  // namespace ekf_slam
