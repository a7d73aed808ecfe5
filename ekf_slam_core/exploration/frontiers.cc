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

// Per cell of a width × height grid, its distance in cells from the nearest
// cell where `source` holds: Dijkstra outwards over 8-connected steps
// (within 8 % of the Euclidean distance), up to `limit`; +inf beyond.
std::vector<double> distanceFrom(int width, int height, const std::function<bool(int)>& source,
                                 double limit) {
  std::vector<double> distance(static_cast<size_t>(width) * height, kInfinity);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  for (int c = 0; c < width * height; ++c) {
    if (source(c)) {
      distance[c] = 0.0;
      open.push({0.0, c});
    }
  }
  while (!open.empty()) {
    const auto [d, c] = open.top();
    open.pop();
    if (d > distance[c]) continue;
    const int x = c % width, y = c / width;
    for (int k = 0; k < 8; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
      const int n = ny * width + nx;
      const double next = d + (k < 4 ? 1.0 : std::sqrt(2.0));
      if (next < distance[n] && next <= limit) {
        distance[n] = next;
        open.push({next, n});
      }
    }
  }
  return distance;
}

}  // namespace

ExplorationGrid::ExplorationGrid(const GridMapFile& grid, const ExplorationOptions& options)
    : width_(grid.width),
      height_(grid.height),
      resolution_(grid.resolution),
      origin_(grid.origin_x, grid.origin_y),
      free_max_(options.free_max),
      robot_radius_(options.robot_radius),
      cells_(grid.cells),
      traversable_(grid.cells.size(), false),
      weight_(grid.cells.size(), 1.0) {
  if (static_cast<long>(cells_.size()) != static_cast<long>(width_) * height_) {
    width_ = height_ = 0;
    cells_.clear();
    traversable_.clear();
    weight_.clear();
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
  // Clearance from every known, non-free cell, as far as the wall cost and
  // the goals' clearance need it.
  const double reach_m =
      std::max({options.wall_clearance, options.goal_clearance, options.frontier_clearance});
  if (reach_m <= 0.0) return;
  clearance_ = distanceFrom(
      width_, height_, [this](int c) { return !unknown(c) && !free(c); }, reach_m / resolution_);
  for (double& d : clearance_) d *= resolution_;
  // The goals' clearance counts the unknown as well: a wall not yet seen
  // (behind furniture) may be there.
  if (options.goal_clearance > 0.0) {
    open_clearance_ = distanceFrom(
        width_, height_, [this](int c) { return !free(c); }, options.goal_clearance / resolution_);
    for (double& d : open_clearance_) d *= resolution_;
  }
  if (options.wall_clearance <= 0.0 ||
      (options.wall_penalty <= 0.0 && options.narrow_penalty <= 1.0)) {
    return;
  }
  const double limit = options.wall_clearance;
  const std::vector<double>& clearance = clearance_;
  for (int c = 0; c < cellCount(); ++c) {
    if (clearance[c] < limit)
      weight_[c] = 1.0 + options.wall_penalty * (1.0 - clearance[c] / limit);
    // Where the robot cannot turn (less than goal_clearance), only a door
    // with no way round is worth crossing.
    if (clearance[c] < options.goal_clearance) weight_[c] *= options.narrow_penalty;
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

void clearFootprint(GridMapFile* grid, const Vector2& p, double radius) {
  if (grid->resolution <= 0.0 || grid->cells.size() != size_t(grid->width) * grid->height) return;
  const double cx = (p.x() - grid->origin_x) / grid->resolution;
  const double cy = (p.y() - grid->origin_y) / grid->resolution;
  const double r = radius / grid->resolution;
  if (!std::isfinite(cx) || !std::isfinite(cy)) return;
  for (int y = std::max(0, int(std::floor(cy - r))); y <= std::min(grid->height - 1, int(cy + r));
       ++y) {
    for (int x = std::max(0, int(std::floor(cx - r))); x <= std::min(grid->width - 1, int(cx + r));
         ++x) {
      const double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
      int8_t& cell = grid->cells[size_t(y) * grid->width + x];
      if (dx * dx + dy * dy <= r * r && cell < 0) cell = 0;
    }
  }
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
      const double step = (k < 4 ? 1.0 : std::sqrt(2.0)) * grid.stepWeight(n);
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

std::vector<Vector2> simplifyPath(const std::vector<Vector2>& path, double tolerance) {
  if (path.size() <= 2) return path;
  std::vector<bool> keep(path.size(), false);
  keep.front() = keep.back() = true;
  // Split at the point farthest from the chord while it is beyond tolerance.
  std::vector<std::pair<size_t, size_t>> spans = {{0, path.size() - 1}};
  while (!spans.empty()) {
    const auto [first, last] = spans.back();
    spans.pop_back();
    const Vector2 a = path[first], ab = path[last] - a;
    const double length2 = ab.squaredNorm();
    double farthest = -1.0;
    size_t at = first;
    for (size_t i = first + 1; i < last; ++i) {
      const double t = length2 > 0.0 ? std::clamp((path[i] - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
      const double d = (path[i] - (a + t * ab)).norm();
      if (d > farthest) {
        farthest = d;
        at = i;
      }
    }
    if (farthest > tolerance) {
      keep[at] = true;
      spans.push_back({first, at});
      spans.push_back({at, last});
    }
  }
  std::vector<Vector2> out;
  for (size_t i = 0; i < path.size(); ++i) {
    if (keep[i]) out.push_back(path[i]);
  }
  return out;
}

bool pathClear(const ExplorationGrid& grid, const std::vector<Vector2>& path) {
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    // Sample each segment at half a cell.
    const double length = (path[i + 1] - path[i]).norm();
    const int steps = std::max(1, static_cast<int>(std::ceil(length / (0.5 * grid.resolution()))));
    for (int k = 0; k <= steps; ++k) {
      const Vector2 p = path[i] + (path[i + 1] - path[i]) * (double(k) / steps);
      const int cell = grid.cellAt(p);
      if (cell < 0 || !grid.free(cell)) return false;
      // The robot may stand inside the inflation (beside a wall) at the start.
      if (!grid.traversable(cell) && (p - path.front()).norm() > grid.robotRadius()) return false;
    }
  }
  return true;
}

SweptFloor::SweptFloor(double front, double rear, double half_width, size_t max_poses)
    : front_(front), rear_(rear), half_width_(half_width), max_poses_(max_poses) {}

void SweptFloor::add(const Pose2& pose) {
  constexpr double kStep = 0.05, kTurn = 0.1;  // m, rad
  if (!poses_.empty()) {
    const Pose2 moved = between(poses_.back(), pose);
    if (moved.translation().norm() < kStep && std::abs(moved.theta) < kTurn) return;
  }
  poses_.push_back(pose);
  while (poses_.size() > max_poses_) poses_.pop_front();
}

bool SweptFloor::covers(const Vector2& point) const {
  for (const Pose2& pose : poses_) {
    const Vector2 local = transformTo(pose, point);
    constexpr double kEdge = 1e-9;  // m: a point on the body's edge is in it
    if (local.x() <= front_ + kEdge && local.x() >= -rear_ - kEdge &&
        std::abs(local.y()) <= half_width_ + kEdge) {
      return true;
    }
  }
  return false;
}

bool stripFree(const ExplorationGrid& grid, const Vector2& from, const Vector2& to,
               double half_width, const std::function<bool(const Vector2&)>& swept) {
  const double length = (to - from).norm();
  const Vector2 along = length > 0.0 ? Vector2((to - from) / length) : Vector2(1.0, 0.0);
  const Vector2 across(-along.y(), along.x());
  const double step = 0.5 * grid.resolution();
  const int steps_along = static_cast<int>(std::ceil(length / step));
  const int steps_across = static_cast<int>(std::ceil(half_width / step));
  for (int i = 0; i <= steps_along; ++i) {
    const Vector2 centre = from + along * std::min(length, i * step);
    for (int j = -steps_across; j <= steps_across; ++j) {
      const double offset = std::clamp(j * step, -half_width, half_width);
      const Vector2 p = centre + across * offset;
      const int cell = grid.cellAt(p);
      const bool known_free = cell >= 0 && grid.free(cell);
      const bool covered = (cell < 0 || grid.unknown(cell)) && swept && swept(p);
      if (!known_free && !covered) return false;
    }
  }
  return true;
}

std::vector<Frontier> findFrontiers(const ExplorationGrid& grid, const Reach& reach,
                                    const ExplorationOptions& options) {
  const int w = grid.width(), h = grid.height();
  auto isFrontier = [&](int c) {
    if (!grid.free(c) || grid.clearance(c) < options.frontier_clearance) return false;
    const int x = c % w, y = c / w;
    for (int k = 0; k < 4; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      if (nx >= 0 && ny >= 0 && nx < w && ny < h && grid.unknown(ny * w + nx)) return true;
    }
    return false;
  };
  // Steps (cells) from `from` to every cell of the group, through the group.
  auto stepsWithin = [&](const std::vector<int>& group, int from) {
    std::vector<std::pair<int, int>> steps;  // (cell, steps)
    std::vector<int> queue = {from};
    std::vector<int> depth = {0};
    std::vector<bool> in_group(grid.cellCount(), false), done(grid.cellCount(), false);
    for (int c : group) in_group[c] = true;
    done[from] = true;
    for (size_t i = 0; i < queue.size(); ++i) {
      steps.push_back({queue[i], depth[i]});
      const int x = queue[i] % w, y = queue[i] / w;
      for (int k = 0; k < 8; ++k) {
        const int nx = x + kDx[k], ny = y + kDy[k];
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const int n = ny * w + nx;
        if (in_group[n] && !done[n]) {
          done[n] = true;
          queue.push_back(n);
          depth.push_back(depth[i] + 1);
        }
      }
    }
    return steps;
  };
  // Goals up to twice goal_clearance from the frontier: as far from the
  // unknown as from the walls.
  const int search =
      std::max(1, static_cast<int>(std::ceil(2.0 * options.goal_clearance / grid.resolution())));
  const int piece_cells =
      std::max(1, static_cast<int>(std::round(options.max_frontier_length / grid.resolution())));
  std::vector<Frontier> out;
  std::vector<bool> seen(grid.cellCount(), false);
  for (int c = 0; c < grid.cellCount(); ++c) {
    if (seen[c] || !isFrontier(c)) continue;
    std::vector<int> group = {c};
    seen[c] = true;
    for (size_t i = 0; i < group.size(); ++i) {
      const int x = group[i] % w, y = group[i] / w;
      for (int k = 0; k < 8; ++k) {
        const int nx = x + kDx[k], ny = y + kDy[k];
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const int n = ny * w + nx;
        if (!seen[n] && isFrontier(n)) {
          seen[n] = true;
          group.push_back(n);
        }
      }
    }
    if (static_cast<double>(group.size()) * grid.resolution() < options.min_frontier_length) {
      continue;
    }
    // Pieces along the group: steps from one of its ends (the cell farthest
    // from any cell is one), max_frontier_length of steps each.
    std::vector<std::pair<int, int>> steps = stepsWithin(group, group.front());
    steps = stepsWithin(group, steps.back().first);
    const int pieces = steps.back().second / piece_cells + 1;
    std::vector<Frontier> parts(pieces);
    for (const auto& [cell, step] : steps) parts[step / piece_cells].cells.push_back(cell);
    for (Frontier& f : parts) {
      f.length = static_cast<double>(f.cells.size()) * grid.resolution();
      // A short tail piece stays only when the whole group is that short.
      if (f.cells.empty() || (pieces > 1 && f.length < options.min_frontier_length)) continue;
      for (int cell : f.cells) f.centroid += grid.centre(cell);
      f.centroid /= static_cast<double>(f.cells.size());
      // The goal: the reachable cell with goal_clearance from walls and
      // from the unknown, among the piece's cells and those within twice
      // goal_clearance of them (a frontier cell may lie inside the
      // inflation, or too near a wall to turn), nearest its centroid.
      double best = kInfinity;
      f.distance = kInfinity;
      for (int cell : f.cells) {
        const int x = cell % w, y = cell / w;
        for (int dy = -search; dy <= search; ++dy) {
          for (int dx = -search; dx <= search; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h || dx * dx + dy * dy > search * search) {
              continue;
            }
            const int n = ny * w + nx;
            if (!reach.reachable(n) || grid.openClearance(n) < options.goal_clearance) continue;
            const double d = (grid.centre(n) - f.centroid).squaredNorm();
            if (d < best || (d == best && reach.distance[n] < f.distance)) {
              best = d;
              f.goal = n;
              f.distance = reach.distance[n];
            }
          }
        }
      }
      out.push_back(std::move(f));
    }
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

std::vector<int> segmentRooms(const ExplorationGrid& grid, double door_width) {
  const int w = grid.width(), h = grid.height(), n = grid.cellCount();
  std::vector<int> label(n, -1);
  if (door_width <= 0.0) return label;
  // Clearance (cells) from every cell that is not free, up to the core's.
  const double core = 0.5 * door_width / grid.resolution();
  const std::vector<double> clearance = distanceFrom(
      w, h, [&grid](int c) { return !grid.free(c); }, core + 1.0);
  // The cores, numbered by connected component (8-neighbours).
  int rooms = 0;
  std::vector<int> frontier_cells;
  for (int c = 0; c < n; ++c) {
    if (label[c] >= 0 || clearance[c] <= core) continue;
    std::vector<int> stack = {c};
    label[c] = rooms;
    while (!stack.empty()) {
      const int cell = stack.back();
      stack.pop_back();
      frontier_cells.push_back(cell);
      const int x = cell % w, y = cell / w;
      for (int k = 0; k < 8; ++k) {
        const int nx = x + kDx[k], ny = y + kDy[k];
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
        const int m = ny * w + nx;
        if (label[m] < 0 && clearance[m] > core) {
          label[m] = rooms;
          stack.push_back(m);
        }
      }
    }
    ++rooms;
  }
  // The rest of the free space: breadth first from all cores at once.
  std::queue<int> grow;
  for (int c : frontier_cells) grow.push(c);
  while (!grow.empty()) {
    const int cell = grow.front();
    grow.pop();
    const int x = cell % w, y = cell / w;
    for (int k = 0; k < 4; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
      const int m = ny * w + nx;
      if (label[m] < 0 && grid.free(m)) {
        label[m] = label[cell];
        grow.push(m);
      }
    }
  }
  return label;
}

ExplorationPlan planExploration(const ExplorationGrid& grid, const Vector2& robot,
                                const RoomOf& room_of, const Excluded& excluded,
                                const ExplorationOptions& options,
                                const std::optional<Vector2>& current, double same_goal,
                                const std::vector<Vector2>& finished_rooms) {
  ExplorationPlan plan;
  plan.reach = reachFrom(grid, robot);
  plan.frontiers = findFrontiers(grid, plan.reach, options);
  // The finished rooms' labels on this grid; the robot's own stays open.
  const int room = room_of ? room_of(robot) : -1;
  auto roomOfGoal = [&](const Frontier& f) { return room_of(grid.centre(f.goal)); };
  std::vector<int> finished;
  bool robot_room_finished = false;
  if (room_of) {
    for (const Vector2& p : finished_rooms) {
      const int r = room_of(p);
      if (r < 0) continue;
      if (r == room) {
        robot_room_finished = true;
      } else {
        finished.push_back(r);
      }
    }
  }
  // Frontiers passed over keep no goal: one the caller excludes (given up),
  // and a short one in a finished room.
  auto passedOver = [&](const Frontier& f) {
    if (excluded && excluded(grid.centre(f.goal))) return true;
    return !finished.empty() && f.length < options.reopen_length &&
           std::find(finished.begin(), finished.end(), roomOfGoal(f)) != finished.end();
  };
  for (Frontier& f : plan.frontiers) {
    if (f.goal >= 0 && passedOver(f)) {
      f.goal = -1;
      f.distance = kInfinity;
    }
  }
  if (current) {
    double nearest = same_goal;
    for (size_t i = 0; i < plan.frontiers.size(); ++i) {
      const Frontier& f = plan.frontiers[i];
      if (f.goal < 0 || !std::isfinite(f.distance)) continue;
      const double d = (grid.centre(f.goal) - *current).norm();
      if (d <= nearest) {
        nearest = d;
        plan.chosen = i;
      }
    }
  }
  if (!plan.chosen) plan.chosen = chooseFrontier(plan.frontiers, grid, robot, room_of, options);
  if (!plan.chosen) return plan;
  plan.path =
      simplifyPath(pathTo(grid, plan.reach, plan.frontiers[*plan.chosen].goal), grid.resolution());
  // Leaving the robot's room with nothing left in it: the room is finished.
  if (room >= 0 && !robot_room_finished && roomOfGoal(plan.frontiers[*plan.chosen]) != room &&
      std::none_of(plan.frontiers.begin(), plan.frontiers.end(), [&](const Frontier& f) {
        return f.goal >= 0 && std::isfinite(f.distance) && roomOfGoal(f) == room;
      })) {
    plan.finished_room = robot;
  }
  return plan;
}

}  // namespace ekf_slam
