#include "ekf_slam_core/exploration/frontiers.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace ekf_slam {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The eight neighbours' offsets (dx, dy), the four sides first.
constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};

}  // namespace

ExplorationGrid::ExplorationGrid(const GridMapFile& grid, const ExplorationOptions& options)
    : width_(grid.width),
      height_(grid.height),
      resolution_(grid.resolution),
      origin_(grid.origin_x, grid.origin_y),
      free_max_(options.free_max),
      cells_(grid.cells),
      traversable_(grid.cells.size(), false) {
  if (static_cast<long>(cells_.size()) != static_cast<long>(width_) * height_) {
    width_ = height_ = 0;
    cells_.clear();
    traversable_.clear();
    return;
  }
  for (int c = 0; c < cellCount(); ++c) traversable_[c] = free(c);
  // Inflation: every known, non-free cell clears the free cells within the
  // robot's radius of it (centre to centre).
  const int reach = static_cast<int>(std::floor(options.robot_radius / resolution_));
  const double radius_cells = options.robot_radius / resolution_;
  for (int c = 0; c < cellCount(); ++c) {
    if (unknown(c) || free(c)) continue;
    const int x = c % width_, y = c / width_;
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (nx < 0 || ny < 0 || nx >= width_ || ny >= height_) continue;
        if (dx * dx + dy * dy <= radius_cells * radius_cells)
          traversable_[ny * width_ + nx] = false;
      }
    }
  }
}

int ExplorationGrid::cellAt(const Vector2& p) const {
  const double fx = (p.x() - origin_.x()) / resolution_;
  const double fy = (p.y() - origin_.y()) / resolution_;
  if (!std::isfinite(fx) || !std::isfinite(fy) || fx < 0 || fy < 0 || fx >= width_ ||
      fy >= height_) {
    return -1;
  }
  return static_cast<int>(fy) * width_ + static_cast<int>(fx);
}

Vector2 ExplorationGrid::centre(int cell) const {
  return origin_ + resolution_ * Vector2(cell % width_ + 0.5, cell / width_ + 0.5);
}

bool Reach::reachable(int cell) const {
  return cell >= 0 && cell < static_cast<int>(distance.size()) && std::isfinite(distance[cell]);
}

Reach reachFrom(const ExplorationGrid& grid, const Vector2& start) {
  Reach out;
  out.distance.assign(grid.cellCount(), kInfinity);
  out.previous.assign(grid.cellCount(), -1);
  out.start = grid.cellAt(start);
  if (out.start < 0 || !grid.free(out.start)) return out;
  // Lengths in cells, scaled to metres at the end.
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  out.distance[out.start] = 0.0;
  open.push({0.0, out.start});
  const int w = grid.width(), h = grid.height();
  while (!open.empty()) {
    const auto [d, c] = open.top();
    open.pop();
    if (d > out.distance[c]) continue;
    const int x = c % w, y = c / w;
    for (int k = 0; k < 8; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
      const int n = ny * w + nx;
      // Out of the inflation through free cells, then on traversable ones.
      auto open_to = [&](int cell) {
        return grid.traversable(cell) || (!grid.traversable(c) && grid.free(cell));
      };
      if (!open_to(n)) continue;
      // No corner cutting: a diagonal step needs both sides open.
      if (k >= 4 && (!open_to(y * w + nx) || !open_to(ny * w + x))) continue;
      const double step = k < 4 ? 1.0 : std::sqrt(2.0);
      if (d + step < out.distance[n]) {
        out.distance[n] = d + step;
        out.previous[n] = c;
        open.push({d + step, n});
      }
    }
  }
  for (double& d : out.distance) {
    if (std::isfinite(d)) d *= grid.resolution();
  }
  return out;
}

std::vector<Vector2> pathTo(const ExplorationGrid& grid, const Reach& reach, int cell) {
  std::vector<Vector2> path;
  if (!reach.reachable(cell)) return path;
  for (int c = cell; c >= 0; c = reach.previous[c]) path.push_back(grid.centre(c));
  std::reverse(path.begin(), path.end());
  return path;
}

std::vector<Frontier> findFrontiers(const ExplorationGrid& grid, const Reach& reach,
                                    const ExplorationOptions& options) {
  const int w = grid.width(), h = grid.height();
  auto isFrontier = [&](int c) {
    if (!grid.free(c)) return false;
    const int x = c % w, y = c / w;
    for (int k = 0; k < 4; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      if (nx >= 0 && ny >= 0 && nx < w && ny < h && grid.unknown(ny * w + nx)) return true;
    }
    return false;
  };
  std::vector<Frontier> out;
  std::vector<bool> seen(grid.cellCount(), false);
  for (int c = 0; c < grid.cellCount(); ++c) {
    if (seen[c] || !isFrontier(c)) continue;
    Frontier f;
    f.distance = kInfinity;
    std::vector<int> stack = {c};
    seen[c] = true;
    while (!stack.empty()) {
      const int cell = stack.back();
      stack.pop_back();
      f.cells.push_back(cell);
      const int x = cell % w, y = cell / w;
      for (int k = 0; k < 8; ++k) {
        const int nx = x + kDx[k], ny = y + kDy[k];
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const int n = ny * w + nx;
        if (!seen[n] && isFrontier(n)) {
          seen[n] = true;
          stack.push_back(n);
        }
      }
    }
    f.length = static_cast<double>(f.cells.size()) * grid.resolution();
    if (f.length < options.min_frontier_length) continue;
    for (int cell : f.cells) {
      f.centroid += grid.centre(cell);
      // The frontier cell itself may lie inside the inflation; its
      // traversable neighbour is where the robot can stand to look on.
      const int x = cell % w, y = cell / w;
      for (int k = -1; k < 8; ++k) {
        const int nx = k < 0 ? x : x + kDx[k], ny = k < 0 ? y : y + kDy[k];
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const int n = ny * w + nx;
        if (reach.reachable(n) && reach.distance[n] < f.distance) {
          f.distance = reach.distance[n];
          f.goal = n;
        }
      }
    }
    f.centroid /= static_cast<double>(f.cells.size());
    out.push_back(std::move(f));
  }
  std::sort(out.begin(), out.end(),
            [](const Frontier& a, const Frontier& b) { return a.cells.size() > b.cells.size(); });
  return out;
}

std::optional<size_t> chooseFrontier(const std::vector<Frontier>& frontiers,
                                     const ExplorationGrid& grid, const Vector2& robot,
                                     const RoomOf& room_of, const ExplorationOptions& options) {
  const int room = room_of ? room_of(robot) : -1;
  std::optional<size_t> best;
  bool best_in_room = false;
  double best_cost = kInfinity;
  for (size_t i = 0; i < frontiers.size(); ++i) {
    const Frontier& f = frontiers[i];
    if (f.goal < 0 || !std::isfinite(f.distance)) continue;
    const bool in_room = room >= 0 && room_of(grid.centre(f.goal)) == room;
    const double cost = f.distance - options.gain_weight * f.length;
    if (!best || (in_room && !best_in_room) || (in_room == best_in_room && cost < best_cost)) {
      best = i;
      best_in_room = in_room;
      best_cost = cost;
    }
  }
  return best;
}

}  // namespace ekf_slam
