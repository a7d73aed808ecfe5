#include "ekf_slam_core/mapping/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace ekf_slam {
namespace {

double logOdds(double p) { return std::log(p / (1.0 - p)); }

}  // namespace

std::string OccupancyGridOptions::validate() const { return checkFields(*this); }

OccupancyGrid::OccupancyGrid(const OccupancyGridOptions& options) : options_(options) {
  log_hit_ = static_cast<float>(logOdds(options_.hit_probability));
  log_miss_ = static_cast<float>(logOdds(options_.miss_probability));
}

bool OccupancyGrid::cellOf(double x, double y, int* ix, int* iy) const {
  const double fx = std::floor((x - origin_.x()) / options_.resolution);
  const double fy = std::floor((y - origin_.y()) / options_.resolution);
  if (!(fx >= 0 && fy >= 0 && fx < width_ && fy < height_)) return false;
  *ix = static_cast<int>(fx);
  *iy = static_cast<int>(fy);
  return true;
}

bool OccupancyGrid::contains(const Vector2& a, const Vector2& b) const {
  const double res = options_.resolution;
  const double min_x = std::min(a.x(), b.x()), max_x = std::max(a.x(), b.x());
  const double min_y = std::min(a.y(), b.y()), max_y = std::max(a.y(), b.y());
  return width_ > 0 && min_x >= origin_.x() && min_y >= origin_.y() &&
         max_x < origin_.x() + width_ * res && max_y < origin_.y() + height_ * res;
}

bool OccupancyGrid::ensureContains(const Vector2& a, const Vector2& b, double margin) {
  if (!a.allFinite() || !b.allFinite()) return false;
  if (contains(a, b)) return true;
  const double res = options_.resolution;
  const double min_x = std::min(a.x(), b.x()), max_x = std::max(a.x(), b.x());
  const double min_y = std::min(a.y(), b.y()), max_y = std::max(a.y(), b.y());
  const double cur_max_x = origin_.x() + width_ * res, cur_max_y = origin_.y() + height_ * res;
  double new_min_x = min_x - margin, new_min_y = min_y - margin;
  double new_max_x = max_x + margin, new_max_y = max_y + margin;
  if (width_ > 0) {
    new_min_x = std::min(new_min_x, origin_.x());
    new_min_y = std::min(new_min_y, origin_.y());
    new_max_x = std::max(new_max_x, cur_max_x);
    new_max_y = std::max(new_max_y, cur_max_y);
  }
  // Keep existing cells on the same lattice: shift the origin by whole cells.
  const int shift_x = width_ > 0 ? static_cast<int>(std::ceil((origin_.x() - new_min_x) / res)) : 0;
  const int shift_y = width_ > 0 ? static_cast<int>(std::ceil((origin_.y() - new_min_y) / res)) : 0;
  const Vector2 new_origin = width_ > 0
                                 ? Vector2(origin_.x() - shift_x * res, origin_.y() - shift_y * res)
                                 : Vector2(new_min_x, new_min_y);
  // Checked in floating point first: a corrupt pose kilometres off must not
  // overflow the cell count or allocate without bound.
  const double cells_x = std::ceil((new_max_x - new_origin.x()) / res) + 1.0;
  const double cells_y = std::ceil((new_max_y - new_origin.y()) / res) + 1.0;
  if (!(cells_x * cells_y <= options_.max_cells)) return false;
  const int new_width = static_cast<int>(cells_x);
  const int new_height = static_cast<int>(cells_y);
  std::vector<float> grid(static_cast<size_t>(new_width) * new_height, -0.0f);
  for (int iy = 0; iy < height_; ++iy) {
    for (int ix = 0; ix < width_; ++ix) {
      const size_t from = static_cast<size_t>(iy) * width_ + ix;
      const size_t to = static_cast<size_t>(iy + shift_y) * new_width + ix + shift_x;
      grid[to] = log_odds_[from];
    }
  }
  origin_ = new_origin;
  width_ = new_width;
  height_ = new_height;
  log_odds_.swap(grid);
  return true;
}

bool OccupancyGrid::isUnknown(float log_odds) {
  uint32_t bits;
  std::memcpy(&bits, &log_odds, sizeof(bits));
  return bits == 0x80000000u;
}

void OccupancyGrid::traceRay(int x0, int y0, int x1, int y1, bool mark_end) {
  // Bresenham: every cell the beam crosses before its end is free.
  const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  const float clamp = static_cast<float>(options_.clamp_log_odds);
  // Held in locals: a store through the cell pointer could otherwise alias
  // the members, and they would be read again for every cell.
  const float miss = log_miss_;
  float* const cells = log_odds_.data();
  const ptrdiff_t stride = width_;
  int x = x0, y = y0;
  while (x != x1 || y != y1) {
    float& cell = cells[y * stride + x];
    cell = std::max(-clamp, cell + miss);
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y += sy;
    }
  }
  float& end = at(x1, y1);
  end = mark_end ? std::min(clamp, end + log_hit_) : std::max(-clamp, end + log_miss_);
}

bool OccupancyGrid::rayEnd(const Pose2& laser_pose, const Scan& scan, int i, Vector2* end,
                           bool* hit) const {
  const double r = scan.ranges[i];
  *hit = scan.isValid(i);
  double length = r;
  if (!*hit) {
    // No return: optionally clear a stretch of free space, never a hit.
    const bool no_return = (std::isinf(r) && r > 0) || (std::isfinite(r) && r >= scan.range_max);
    if (!no_return || options_.no_return_free_range <= 0.0) return false;
    length = options_.no_return_free_range;
  } else if (r > options_.max_insert_range) {
    return false;
  }
  const double bearing = laser_pose.theta + scan.angle(i);
  if (!std::isfinite(bearing)) return false;  // a sweep whose bearings overflow
  *end = laser_pose.translation() + length * Vector2(std::cos(bearing), std::sin(bearing));
  return true;
}

void OccupancyGrid::extendToScan(const Pose2& laser_pose, const Scan& scan, Vector2* low,
                                 Vector2* high) const {
  if (!laser_pose.allFinite()) return;
  *low = low->cwiseMin(laser_pose.translation());
  *high = high->cwiseMax(laser_pose.translation());
  for (int i = 0; i < scan.size(); ++i) {
    Vector2 end;
    bool hit;
    if (!rayEnd(laser_pose, scan, i, &end, &hit)) continue;
    *low = low->cwiseMin(end);
    *high = high->cwiseMax(end);
  }
}

void OccupancyGrid::insertScan(const Pose2& laser_pose, const Scan& scan) {
  if (!laser_pose.allFinite()) return;
  const Vector2 origin = laser_pose.translation();
  // Where the grid holds the square that every ray of the scan stays in,
  // no ray needs the test of its own (rounding keeps |r cos| <= r).
  const Vector2 reach =
      Vector2::Constant(std::max(options_.max_insert_range, options_.no_return_free_range));
  const bool covered = contains(origin - reach, origin + reach);
  for (int i = 0; i < scan.size(); ++i) {
    Vector2 end;
    bool hit;
    if (!rayEnd(laser_pose, scan, i, &end, &hit)) continue;
    if (!covered && !ensureContains(origin, end, options_.grow_margin)) {
      ++rays_beyond_limit_;
      continue;
    }
    int x0, y0, x1, y1;
    if (!cellOf(origin.x(), origin.y(), &x0, &y0) || !cellOf(end.x(), end.y(), &x1, &y1)) continue;
    traceRay(x0, y0, x1, y1, hit);
  }
}

void OccupancyGrid::insertHits(const Vector2& origin, const std::vector<Vector2>& endpoints) {
  if (!origin.allFinite()) return;
  for (const Vector2& end : endpoints) {
    if (!end.allFinite() || (end - origin).norm() > options_.max_insert_range) continue;
    if (!ensureContains(origin, end, options_.grow_margin)) {
      ++rays_beyond_limit_;
      continue;
    }
    int x0, y0, x1, y1;
    if (!cellOf(origin.x(), origin.y(), &x0, &y0) || !cellOf(end.x(), end.y(), &x1, &y1)) continue;
    traceRay(x0, y0, x1, y1, /*mark_end=*/true);
  }
}

double OccupancyGrid::probability(double x, double y) const {
  int ix, iy;
  if (!cellOf(x, y, &ix, &iy)) return 0.5;
  return 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(at(ix, iy))));
}

bool OccupancyGrid::isKnown(double x, double y) const {
  int ix, iy;
  return cellOf(x, y, &ix, &iy) && !isUnknown(at(ix, iy));
}

std::vector<int8_t> OccupancyGrid::occupancyValues() const {
  std::vector<int8_t> out(log_odds_.size(), -1);
  for (size_t i = 0; i < out.size(); ++i) {
    if (isUnknown(log_odds_[i])) continue;
    const double p = 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(log_odds_[i])));
    out[i] = static_cast<int8_t>(std::lround(100.0 * p));
  }
  return out;
}

std::vector<int8_t> OccupancyGrid::trinaryValues() const {
  std::vector<int8_t> out(log_odds_.size(), -1);
  const float occupied = static_cast<float>(logOdds(0.65));
  const float free = static_cast<float>(logOdds(0.196));
  for (size_t i = 0; i < out.size(); ++i) {
    if (isUnknown(log_odds_[i])) continue;
    if (log_odds_[i] > occupied) {
      out[i] = 100;
    } else if (log_odds_[i] < free) {
      out[i] = 0;
    }
  }
  return out;
}

std::string OccupancyGrid::save(const std::string& base_path) const {
  const std::string pgm_path = base_path + ".pgm", yaml_path = base_path + ".yaml";
  std::ofstream pgm(pgm_path, std::ios::binary);
  if (!pgm) return "cannot write " + pgm_path;
  const int w = std::max(width_, 1), h = std::max(height_, 1);
  pgm << "P5\n# ekf_slam occupancy grid, " << options_.resolution << " m/cell\n"
      << w << ' ' << h << "\n255\n";
  // map_server: the first image row is the top (largest y); 0 = occupied
  // (black), 254 = free (white), 205 = unknown (grey).
  std::vector<uint8_t> row(w);
  for (int iy = h - 1; iy >= 0; --iy) {
    for (int ix = 0; ix < w; ++ix) {
      if (ix >= width_ || iy >= height_ || isUnknown(at(ix, iy))) {
        row[ix] = 205;
        continue;
      }
      const double p = 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(at(ix, iy))));
      row[ix] = static_cast<uint8_t>(std::lround(254.0 * (1.0 - p)));
    }
    pgm.write(reinterpret_cast<const char*>(row.data()), w);
  }
  if (!pgm) return "error while writing " + pgm_path;
  std::ofstream yaml(yaml_path);
  if (!yaml) return "cannot write " + yaml_path;
  const size_t slash = pgm_path.find_last_of('/');
  const std::string image = slash == std::string::npos ? pgm_path : pgm_path.substr(slash + 1);
  char origin[128];
  std::snprintf(origin, sizeof(origin), "[%.6f, %.6f, 0.0]", origin_.x(), origin_.y());
  yaml << "image: " << image << "\nresolution: " << options_.resolution << "\norigin: " << origin
       << "\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  if (!yaml) return "error while writing " + yaml_path;
  return "";
}

}  // namespace ekf_slam
