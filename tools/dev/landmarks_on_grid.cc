// ekf_slam_landmarks_on_grid: how well the landmarks drawn in the `map`
// frame agree with the occupancy grid, offline and in seconds, on a bag run
// with the built-in configuration (test/landmarks_on_grid.test measures the
// same on a live replay, at 5x real time for minutes).
//
//   ekf_slam_landmarks_on_grid --bag FILE [--seconds S] [--every N]
//                              [--radius R] [--list]
//
// Every N scans (default 50) after the first optimisation of the loop
// closer (a loop or heading loops) it builds the grid the
// live node publishes (the key scans at their loop-closed poses, cells
// above 0.65 occupied) and the loop-closed landmark map (loopClosedMap), and
// prints the share of the point landmarks within R (0.3 m) of an occupied
// cell. --list also prints, at the last snapshot, every landmark beyond R:
// its distance, its 1-sigma position uncertainty, its observation count
// and the filter steps of its creation and last match.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_core/pipeline/loop_closed_map.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_ros/offline/log_input.h"

namespace {

using ekf_slam::Pose2;
using ekf_slam::Vector2;

ekf_slam::OccupancyGrid keyScanGrid(const ekf_slam::SlamPipeline& pipeline, const Pose2& laser) {
  ekf_slam::OccupancyGrid grid;
  for (const auto& key : pipeline.keyScans(true)) {
    std::vector<Vector2> ends;
    ends.reserve(key.points.size());
    for (const Vector2& p : key.points) ends.push_back(ekf_slam::transformFrom(key.pose, p));
    grid.insertHits(ekf_slam::transformFrom(key.pose, laser.translation()), ends);
  }
  return grid;
}

// Distance from `p` to the centre of the nearest cell above 0.65, searched
// within `reach`; reach + 1 when there is none.
double distanceToOccupied(const ekf_slam::OccupancyGrid& grid, const Vector2& p, double reach) {
  const double r = grid.resolution();
  double best = reach + 1.0;
  const int cells = static_cast<int>(std::ceil(reach / r));
  const Vector2 o = grid.origin();
  const int cx = static_cast<int>(std::floor((p.x() - o.x()) / r));
  const int cy = static_cast<int>(std::floor((p.y() - o.y()) / r));
  for (int iy = cy - cells; iy <= cy + cells; ++iy) {
    for (int ix = cx - cells; ix <= cx + cells; ++ix) {
      const Vector2 centre(o.x() + (ix + 0.5) * r, o.y() + (iy + 0.5) * r);
      const double d = (centre - p).norm();
      if (d < best && grid.probability(centre.x(), centre.y()) > 0.65) best = d;
    }
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  std::string bag;
  double seconds = -1.0, radius = 0.3;
  int every = 50;
  bool list = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--bag" && has_value) {
      bag = argv[++i];
    } else if (arg == "--seconds" && has_value) {
      seconds = std::atof(argv[++i]);
    } else if (arg == "--every" && has_value) {
      every = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--radius" && has_value) {
      radius = std::atof(argv[++i]);
    } else if (arg == "--list") {
      list = true;
    } else {
      std::cerr << "usage: ekf_slam_landmarks_on_grid --bag FILE [--seconds S] [--every N] "
                   "[--radius R] [--list]\n";
      return 2;
    }
  }
  if (bag.empty()) {
    std::cerr << "ekf_slam_landmarks_on_grid: --bag is required\n";
    return 2;
  }
  ekf_slam::SlamConfig config;
  ekf_slam::LogData log;
  if (const std::string error = ekf_slam::readBag(bag, config.input, &log); !error.empty()) {
    std::cerr << "ekf_slam_landmarks_on_grid: " << error << "\n";
    return 2;
  }
  config.pipeline.filter.laser_pose = log.laser_pose;
  ekf_slam::SlamPipeline pipeline(config.pipeline);
  const Pose2 laser = config.pipeline.filter.laser_pose;

  std::vector<double> shares;
  Pose2 causal;
  for (size_t i = 0; i < log.scans.size(); ++i) {
    const auto& scan = log.scans[i];
    if (seconds >= 0 && scan.scan.stamp - log.first_stamp > seconds) break;
    const ekf_slam::ScanResult result = pipeline.processScan(scan.scan, scan.odometry);
    if (result.outcome == ekf_slam::ScanOutcome::kIterated) causal = result.causal_pose;
    const bool last = i + 1 == log.scans.size() ||
                      (seconds >= 0 && log.scans[i + 1].scan.stamp - log.first_stamp > seconds);
    if (pipeline.backEndOptimisations() == 0 || (i % every != 0 && !last)) continue;
    const ekf_slam::OccupancyGrid grid = keyScanGrid(pipeline, laser);
    const ekf_slam::LoopClosedMap map = ekf_slam::loopClosedMap(pipeline, causal);
    int points = 0, near = 0;
    for (size_t slot = 0; slot < map.filter.landmarks().size(); ++slot) {
      const ekf_slam::LandmarkInfo& info = map.filter.landmarks()[slot];
      if (info.kind != ekf_slam::LandmarkKind::kPoint) continue;
      const Vector2 p = map.filter.landmarkPosition(static_cast<int>(slot));
      const double d = distanceToOccupied(grid, p, 3.0);
      ++points;
      if (d <= radius) ++near;
      if (list && last && d > radius) {
        const ekf_slam::Matrix2 c = map.filter.landmarkCovariance(static_cast<int>(slot));
        const double sigma = std::sqrt(std::max(
            0.0,
            0.5 * (c.trace() + std::sqrt(std::pow(c(0, 0) - c(1, 1), 2) + 4 * c(0, 1) * c(0, 1)))));
        std::printf(
            "  landmark %d at (%.2f, %.2f): %.2f m off, sigma %.2f m, %d observations, "
            "created at step %ld, last seen at step %ld (now %ld)\n",
            info.id, p.x(), p.y(), d, sigma, info.observations, info.created_step,
            info.last_seen_step, map.filter.step());
      }
    }
    const double share = points > 0 ? static_cast<double>(near) / points : 1.0;
    shares.push_back(share);
    std::printf("scan %zu (%.0f s): %d of %d point landmarks within %.2f m (%.0f %%)\n", i,
                scan.scan.stamp - log.first_stamp, near, points, radius, 100.0 * share);
  }
  if (shares.empty()) {
    std::printf("the loop closer never optimised: nothing measured\n");
    return 0;
  }
  std::vector<double> sorted = shares;
  std::sort(sorted.begin(), sorted.end());
  std::printf("%zu snapshots: median %.0f %%, lowest %.0f %%\n", sorted.size(),
              100.0 * sorted[sorted.size() / 2], 100.0 * sorted.front());
  return 0;
}
