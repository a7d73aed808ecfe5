// Log-odds occupancy grid built by ray casting laser scans from known poses:
// the complete metric map of thesis §3.4.5, re-projected along the smoothed
// trajectory. Saved as map_server PGM + YAML; converted to
// nav_msgs/OccupancyGrid values by the ROS adapter.
//
// Frame: the map frame; cell (ix, iy) covers [origin + i·resolution,
// origin + (i+1)·resolution) in x and y. The grid grows as scans reach
// beyond it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

struct OccupancyGridOptions {
  double resolution = 0.05;           // m per cell
  double hit_probability = 0.7;       // P(occupied | beam ended here)
  double miss_probability = 0.4;      // P(occupied | beam passed through)
  double clamp_log_odds = 5.0;        // |log-odds| bound, keeps the map revisable
  double max_insert_range = 30.0;     // m: longer readings are not inserted
  double no_return_free_range = 0.0;  // m: clear this far along no-return beams (0: do not)
  double grow_margin = 10.0;          // m added on each side when the grid grows
  // The grid never grows beyond this many cells (5 bytes each while it
  // grows: about 500 MB). A ray that would need more (a pose kilometres
  // off: corrupt odometry) is left out and counted, instead of an
  // allocation that exhausts the machine.
  double max_cells = 1.0e8;

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("resolution", resolution, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("hit_probability", hit_probability, Bounds::open(0.5, 1.0));
    v.number("miss_probability", miss_probability, Bounds::open(0.0, 0.5));
    v.number("clamp_log_odds", clamp_log_odds, Bounds::openClosed(0.0, 100.0));
    v.number("max_insert_range", max_insert_range, Bounds::above(0.0, "m"));
    v.number("no_return_free_range", no_return_free_range, Bounds::atLeast(0.0, "m"));
    v.number("max_cells", max_cells, Bounds::closed(1.0, 1e10, "cells"));
    v.number("grow_margin", grow_margin, Bounds::openClosed(0.0, 1e3, "m"));
  }

  std::string validate() const;
};

class OccupancyGrid {
 public:
  explicit OccupancyGrid(const OccupancyGridOptions& options = {});

  // Inserts one scan taken with the laser at `laser_pose` (map frame).
  void insertScan(const Pose2& laser_pose, const Scan& scan);

  // Grows the grid once to hold the rectangle [low, high], without the grow
  // margin. When the extent of many scans is known beforehand
  // (extendToScan), this replaces the repeated reallocations of a grid that
  // grows scan by scan: on a 400 m site those copies dominated the time and
  // doubled the peak memory.
  // False (and the grid unchanged) when that would exceed max_cells.
  bool cover(const Vector2& low, const Vector2& high) { return ensureContains(low, high, 0.0); }

  // Widens the box [*low, *high] to hold every ray insertScan(laser_pose,
  // scan) would trace: the extent to cover() for a log's scans, no larger
  // than what their rays reach.
  void extendToScan(const Pose2& laser_pose, const Scan& scan, Vector2* low, Vector2* high) const;

  // Inserts beams from `origin` that ended at `endpoints` (map frame): each
  // a hit at its end, free space before it (a key scan's kept readings).
  void insertHits(const Vector2& origin, const std::vector<Vector2>& endpoints);

  // Probability of occupancy of the cell containing (x, y); 0.5 when unknown
  // or outside.
  double probability(double x, double y) const;
  bool isKnown(double x, double y) const;

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return options_.resolution; }
  Vector2 origin() const { return origin_; }  // map-frame corner of cell (0, 0)

  // nav_msgs/OccupancyGrid data: row-major from cell (0, 0), −1 unknown,
  // else 0..100.
  std::vector<int8_t> occupancyValues() const;
  // The same, decided as map_server decides a saved image (occupied above
  // 0.65, free below 0.196, unknown between): every value is -1, 0 or 100,
  // as amcl and the navigation stack expect of a published map.
  std::vector<int8_t> trinaryValues() const;

  // map_server files: `<base>.pgm` and `<base>.yaml` (image referenced by its
  // file name). Returns an empty string on success, else the error.
  std::string save(const std::string& base_path) const;

  // Rays left out because the grid would have exceeded max_cells.
  long raysBeyondLimit() const { return rays_beyond_limit_; }

 private:
  bool cellOf(double x, double y, int* ix, int* iy) const;
  // Where beam i of a scan from `laser_pose` ends as insertScan traces it,
  // and whether it ends in a hit; false when it is not traced.
  bool rayEnd(const Pose2& laser_pose, const Scan& scan, int i, Vector2* end, bool* hit) const;
  // Whether the grid holds the rectangle with corners a and b.
  bool contains(const Vector2& a, const Vector2& b) const;
  // Grows the grid, when it must, to hold [a, b] and `margin` m beyond each
  // side it grows on. False when that would exceed max_cells (nothing
  // changes).
  bool ensureContains(const Vector2& a, const Vector2& b, double margin);
  void traceRay(int x0, int y0, int x1, int y1, bool mark_end);
  float& at(int ix, int iy) { return log_odds_[static_cast<size_t>(iy) * width_ + ix]; }
  float at(int ix, int iy) const { return log_odds_[static_cast<size_t>(iy) * width_ + ix]; }
  static bool isUnknown(float log_odds);  // the −0.0 of a cell no ray touched

  OccupancyGridOptions options_;
  float log_hit_ = 0.0f, log_miss_ = 0.0f;
  Vector2 origin_ = Vector2::Zero();
  int width_ = 0, height_ = 0;
  // Log-odds per cell. A cell no ray has touched holds −0.0, which no
  // update can produce (x + y is −0.0 only when both are, and the clamp is
  // never zero): the first update adds to it as to 0, and an unknown cell
  // costs no flag of its own (a fifth less memory on a large map).
  std::vector<float> log_odds_;
  long rays_beyond_limit_ = 0;
};

}  // namespace ekf_slam
