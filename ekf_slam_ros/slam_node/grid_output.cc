#include "ekf_slam_ros/slam_node/grid_output.h"

#include <utility>
#include <vector>

namespace ekf_slam {

GridOutput::GridOutput(ros::NodeHandle node, const SlamNodeParams& params,
                       const OccupancyGridOptions& map, bool live, const SlamControl& slam)
    : params_(params), slam_(slam) {
  map_publisher_ = node.advertise<nav_msgs::OccupancyGrid>("map", 1, /*latch=*/true);
  metadata_publisher_ = node.advertise<nav_msgs::MapMetaData>("map_metadata", 1, /*latch=*/true);
  if (live) {
    live_map_ = std::make_unique<LiveMapPublisher>(node, map);
    map_timer_ =
        node.createTimer(ros::Duration(params_.map_update_interval), &GridOutput::onMapTimer, this);
  }
}

void GridOutput::onMapTimer(const ros::TimerEvent&) {
  const SlamPipeline* pipeline = slam_.pipeline();
  if (!pipeline || !live_map_ || hold_) return;
  const long optimisations = pipeline->backEndOptimisations();
  std::vector<SlamPipeline::KeyScan> keys = pipeline->keyScans(/*with_points=*/true);
  if (keys.empty() ||
      (optimisations == optimisations_mapped_ && static_cast<int>(keys.size()) == keys_mapped_)) {
    return;
  }
  std_msgs::Header header;
  header.stamp = slam_.lastScanStamp();
  header.frame_id = params_.map_frame;
  const int count = static_cast<int>(keys.size());
  // The laser pose the pipeline maps with (base_link → laser).
  if (live_map_->submit(std::move(keys), pipeline->options().filter.laser_pose, header)) {
    optimisations_mapped_ = optimisations;
    keys_mapped_ = count;
  }
}

bool GridOutput::currentGrid(nav_msgs::OccupancyGrid* map) const {
  nav_msgs::OccupancyGrid live;
  std::chrono::steady_clock::time_point live_time;
  const bool have_live = live_map_ && live_map_->latest(&live, &live_time);
  if (node_grid_ && (!have_live || node_grid_time_ >= live_time)) {
    *map = *node_grid_;
    return true;
  }
  if (have_live) {
    *map = std::move(live);
    return true;
  }
  return false;
}

void GridOutput::publish(const nav_msgs::OccupancyGrid& map) {
  map_publisher_.publish(map);
  metadata_publisher_.publish(map.info);  // map_metadata always describes map
  node_grid_ = map;
  node_grid_time_ = std::chrono::steady_clock::now();
}

void GridOutput::restart() {
  optimisations_mapped_ = -1;
  keys_mapped_ = 0;
}

void GridOutput::forget() {
  node_grid_.reset();
  hold_ = false;
  if (live_map_) live_map_->forget();
}

}  // namespace ekf_slam
