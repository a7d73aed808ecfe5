#include "ekf_slam_ros/slam_node/relocaliser.h"

#include <ros/console.h>

#include <utility>

namespace ekf_slam {

Relocaliser::Relocaliser(const ScanMatcherOptions& icp, const GlobalLocalizationOptions& options)
    : icp_(icp), options_(options), lost_(options), thread_([this] { run(); }) {}

Relocaliser::~Relocaliser() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void Relocaliser::watch(SlamState state) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++generation_;
    to_build_ = std::move(state);
    localizer_.reset();
    jobs_.clear();
    found_.reset();
    status_.watching = true;
    status_.lost = false;
    status_.score = 0.0;
    status_.last_search.clear();
    status_.map_error.clear();
  }
  lost_.reset();
  wake_.notify_all();
}

void Relocaliser::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++generation_;
    to_build_.reset();
    localizer_.reset();
    jobs_.clear();
    found_.reset();
    status_.watching = false;
    status_.lost = false;
  }
  lost_.reset();
}

void Relocaliser::afterScan(const std::vector<Vector2>& robot_points, const Pose2& odometry,
                            const Pose2& map_pose) {
  std::shared_ptr<GlobalLocalizer> localizer;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!localizer_ || found_) return;  // no map yet, or a place waits to be taken
    localizer = localizer_;
  }
  bool restart = false;
  if (!lost_.lost()) {
    // fitNear reads only the built map, which the search thread never changes.
    const double score = localizer->fitNear(robot_points, map_pose);
    const bool lost = lost_.add(score);
    std::lock_guard<std::mutex> lock(mutex_);
    status_.score = score;
    if (!lost) return;
    status_.lost = true;
    ++status_.times_lost;
    restart = true;
    ROS_WARN(
        "ekf_slam_node: lost: %d scans in a row fit the saved map under %.2f where the robot "
        "was thought to be (the last %.2f); searching the whole map for it",
        options_.lost_scans, options_.lost_score, score);
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (restart) jobs_.clear();
    jobs_.push_back({robot_points, odometry, restart});
    // The search joins at most max_joined_scans: older ones waiting are of no use.
    while (jobs_.size() > static_cast<size_t>(options_.max_joined_scans)) {
      const bool first = jobs_.front().restart;
      jobs_.pop_front();
      jobs_.front().restart = jobs_.front().restart || first;
    }
  }
  wake_.notify_all();
}

std::optional<GlobalPlacement> Relocaliser::takeFound(const Pose2& odometry) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!found_) return std::nullopt;
  const GlobalPlacement place = movedOn(found_->first, between(found_->second, odometry));
  found_.reset();
  jobs_.clear();
  lost_.reset();
  status_.lost = false;
  ++status_.times_found;
  return place;
}

bool Relocaliser::watching() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_.watching;
}

Relocaliser::Status Relocaliser::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_;
}

void Relocaliser::run() {
  for (;;) {
    std::optional<SlamState> to_build;
    std::deque<Job> jobs;
    std::shared_ptr<GlobalLocalizer> localizer;
    long generation = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return closing_ || to_build_ || (localizer_ && !jobs_.empty()); });
      if (closing_) return;
      generation = generation_;
      if (to_build_) {
        to_build.swap(to_build_);
      } else {
        jobs.swap(jobs_);
        localizer = localizer_;
      }
    }
    if (to_build) {
      auto built = std::make_shared<GlobalLocalizer>(*to_build, icp_, options_);
      to_build.reset();
      std::lock_guard<std::mutex> lock(mutex_);
      if (generation != generation_) continue;  // replaced meanwhile
      status_.map_error = built->mapError();
      if (status_.map_error.empty()) {
        localizer_ = std::move(built);
      } else {
        ROS_WARN("ekf_slam_node: no relocalisation in the loaded state: %s",
                 status_.map_error.c_str());
      }
      continue;
    }
    for (const Job& job : jobs) {
      if (job.restart) localizer->restart();
      const GlobalPlacement placement = localizer->add(job.points, job.odometry);
      if (!placement.searched) continue;
      std::lock_guard<std::mutex> lock(mutex_);
      if (generation != generation_) break;  // the map was replaced: not its robot any more
      ++status_.searches;
      status_.last_search = placement.found ? "" : placement.message;
      if (!placement.found) {
        ROS_INFO("ekf_slam_node: lost: search %ld: %s", status_.searches,
                 placement.message.c_str());
        continue;
      }
      found_.emplace(placement, job.odometry);
      jobs_.clear();
      ROS_INFO(
          "ekf_slam_node: found again at (%.2f m, %.2f m, %.1f deg) in the map, score %.2f "
          "(%d scans joined)",
          placement.map_pose.x, placement.map_pose.y, radToDeg(placement.map_pose.theta),
          placement.score, placement.joined_scans);
      break;
    }
  }
}

}  // namespace ekf_slam
