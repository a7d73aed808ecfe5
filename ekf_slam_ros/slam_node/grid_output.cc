#include "ekf_slam_ros/slam_node/grid_output.h"

#include <algorithm>
#include <deque>
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
  std_msgs::Header header;
  header.stamp = slam_.lastScanStamp();
  header.frame_id = params_.map_frame;
  // The laser pose the pipeline maps with (base_link → laser).
  const Pose2& laser = pipeline->options().filter.laser_pose;
  if (pipeline->backEnd().active()) {
    submitKeyScans(*pipeline, laser, header);
  } else {
    submitNewScans(*pipeline, laser, header);
  }
}

void GridOutput::submitKeyScans(const SlamPipeline& pipeline, const Pose2& laser,
                                const std_msgs::Header& header) {
  const long optimisations = pipeline.backEndOptimisations();
  std::vector<SlamPipeline::KeyScan> keys = pipeline.keyScans(/*with_points=*/true);
  if (keys.empty() ||
      (optimisations == optimisations_mapped_ && static_cast<int>(keys.size()) == keys_mapped_)) {
    return;
  }
  const int count = static_cast<int>(keys.size());
  if (live_map_->submit(std::move(keys), laser, header)) {
    optimisations_mapped_ = optimisations;
    keys_mapped_ = count;
  }
}

void GridOutput::submitNewScans(const SlamPipeline& pipeline, const Pose2& laser,
                                const std_msgs::Header& header) {
  const std::deque<KeptScan>& kept = pipeline.history().keptScans();
  if (kept.empty() || kept.back().scan < scans_mapped_) return;
  // A new pipeline's first kept scan (after a resume, the first new one:
  // the saved scans' readings were not kept).
  if (scans_mapped_ < 0) scans_mapped_ = kept.front().scan;
  if (kept.front().scan > scans_mapped_) {
    ROS_WARN_THROTTLE(60.0,
                      "ekf_slam_node: %ld scans left the history (history_max_scans %d) before the "
                      "live map cast them; they are missing from `%s` until ~smooth (raise "
                      "history_max_scans or lower map_update_interval)",
                      kept.front().scan - scans_mapped_, params_.history_max_scans,
                      params_.map_frame.c_str());
  }
  const auto first =
      std::lower_bound(kept.begin(), kept.end(), scans_mapped_,
                       [](const KeptScan& scan, long number) { return scan.scan < number; });
  std::vector<KeptScan> scans(first, kept.end());
  const long next = kept.back().scan + 1;
  if (live_map_->submitScans(std::move(scans), laser, header)) scans_mapped_ = next;
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
  scans_mapped_ = -1;
  if (live_map_) live_map_->newMap();
}

void GridOutput::forget() {
  node_grid_.reset();
  hold_ = false;
  if (live_map_) live_map_->forget();
}

}  // namespace ekf_slam
