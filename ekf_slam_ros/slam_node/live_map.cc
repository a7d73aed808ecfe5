#include "ekf_slam_ros/slam_node/live_map.h"

#include <malloc.h>

#include <chrono>
#include <limits>
#include <utility>

namespace ekf_slam {

nav_msgs::OccupancyGrid toOccupancyGridMessage(const OccupancyGrid& grid,
                                               const std_msgs::Header& header) {
  nav_msgs::OccupancyGrid map;
  map.header = header;
  map.info.map_load_time = header.stamp;
  map.info.resolution = static_cast<float>(grid.resolution());
  map.info.width = grid.width();
  map.info.height = grid.height();
  map.info.origin.position.x = grid.origin().x();
  map.info.origin.position.y = grid.origin().y();
  map.info.origin.orientation.w = 1.0;
  map.data = grid.trinaryValues();
  return map;
}

OccupancyGrid gridFromKeyScans(const std::vector<SlamPipeline::KeyScan>& keys, const Pose2& laser,
                               const OccupancyGridOptions& options) {
  OccupancyGrid grid(options);
  // Sized once to the laser positions and the hits insertHits keeps.
  Vector2 low = Vector2::Constant(std::numeric_limits<double>::infinity());
  Vector2 high = -low;
  const auto extend = [&](const Vector2& p) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  };
  for (const SlamPipeline::KeyScan& key : keys) {
    if (!key.pose.allFinite()) continue;
    const Vector2 origin = transformFrom(key.pose, laser.translation());
    extend(origin);
    for (const Vector2& p : key.points) {
      const Vector2 end = transformFrom(key.pose, p);
      if ((end - origin).norm() <= options.max_insert_range) extend(end);
    }
  }
  if (!low.allFinite()) return grid;
  grid.cover(low, high);
  std::vector<Vector2> ends;
  for (const SlamPipeline::KeyScan& key : keys) {
    if (!key.pose.allFinite()) continue;
    ends.clear();
    for (const Vector2& p : key.points) ends.push_back(transformFrom(key.pose, p));
    grid.insertHits(transformFrom(key.pose, laser.translation()), ends);
  }
  return grid;
}

LiveMapPublisher::LiveMapPublisher(ros::NodeHandle node, const OccupancyGridOptions& options)
    : options_(options),
      map_publisher_(node.advertise<nav_msgs::OccupancyGrid>("map", 1, /*latch=*/true)),
      metadata_publisher_(node.advertise<nav_msgs::MapMetaData>("map_metadata", 1, true)),
      worker_([this] { run(); }) {}

LiveMapPublisher::~LiveMapPublisher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

bool LiveMapPublisher::submit(std::vector<SlamPipeline::KeyScan> keys, const Pose2& laser,
                              const std_msgs::Header& header) {
  Job job;
  job.keys = std::move(keys);
  job.laser = laser;
  job.header = header;
  return hand(std::move(job));
}

bool LiveMapPublisher::submitScans(std::vector<KeptScan> scans, const Pose2& laser,
                                   const std_msgs::Header& header) {
  Job job;
  job.scans = std::move(scans);
  job.incremental = true;
  job.laser = laser;
  job.header = header;
  return hand(std::move(job));
}

bool LiveMapPublisher::hand(Job job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (pending_) return false;
    job.generation = generation_;
    job_ = std::move(job);
    pending_ = true;
  }
  wake_.notify_all();
  return true;
}

long LiveMapPublisher::published() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return published_;
}

double LiveMapPublisher::lastBuildSeconds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_build_seconds_;
}

bool LiveMapPublisher::latest(nav_msgs::OccupancyGrid* map,
                              std::chrono::steady_clock::time_point* when) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!have_latest_) return false;
  *map = latest_;
  *when = latest_time_;
  return true;
}

void LiveMapPublisher::newMap() {
  std::lock_guard<std::mutex> publishing(publish_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  ++generation_;
}

void LiveMapPublisher::forget() {
  std::lock_guard<std::mutex> publishing(publish_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  ++generation_;
  have_latest_ = false;
  latest_ = nav_msgs::OccupancyGrid();
}

nav_msgs::OccupancyGrid LiveMapPublisher::build(const Job& job) {
  if (!job.incremental) {
    return toOccupancyGridMessage(gridFromKeyScans(job.keys, job.laser, options_), job.header);
  }
  if (!kept_grid_ || kept_generation_ != job.generation) {
    kept_grid_.emplace(options_);
    kept_generation_ = job.generation;
  }
  for (const KeptScan& scan : job.scans) {
    kept_grid_->insertScan(compose(scan.causal, job.laser), scan.toScan());
  }
  return toOccupancyGridMessage(*kept_grid_, job.header);
}

void LiveMapPublisher::run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || pending_; });
      if (stop_) return;
      job = std::move(job_);
      job_ = Job();
    }
    {
      const auto start = std::chrono::steady_clock::now();
      const nav_msgs::OccupancyGrid map = build(job);
      std::lock_guard<std::mutex> publishing(publish_mutex_);
      bool current;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        current = job.generation == generation_;  // else the map it belongs to is gone
      }
      if (current) {
        map_publisher_.publish(map);
        metadata_publisher_.publish(map.info);
      }
      std::lock_guard<std::mutex> lock(mutex_);
      if (current) {
        ++published_;
        latest_ = map;
        latest_time_ = std::chrono::steady_clock::now();
        have_latest_ = true;
        last_build_seconds_ =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      }
      pending_ = false;
    }
    // The grid just built and the key scans' copy are freed now, and so is
    // what the back end's optimisations left behind since the last map
    // (their linear systems, earlier views of the graph). The allocator
    // keeps such pages unless told; handing them back here, on this
    // thread, lets the resident set show what the node really holds
    // (docs/robustness.md, Soak) without the scan thread ever waiting for it.
    job = Job();
#ifdef __GLIBC__
    malloc_trim(0);
#endif
  }
}

}  // namespace ekf_slam
