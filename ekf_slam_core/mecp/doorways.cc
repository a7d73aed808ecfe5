#include "ekf_slam_core/mecp/doorways.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <set>

namespace ekf_slam {
namespace {

// Walls shorter than this (m) have no direction.
constexpr double kMinWallLength = 1e-9;

double cross(const Vector2& a, const Vector2& b) { return a.x() * b.y() - a.y() * b.x(); }

double pointSegmentDistance(const Vector2& p, const Vector2& a, const Vector2& b) {
  const Vector2 ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

// Distance between the segments a–b and c–d: zero when they cross.
double segmentDistance(const Vector2& a, const Vector2& b, const Vector2& c, const Vector2& d) {
  const double c_side = cross(b - a, c - a), d_side = cross(b - a, d - a);
  const double a_side = cross(d - c, a - c), b_side = cross(d - c, b - c);
  if (((c_side > 0.0 && d_side < 0.0) || (c_side < 0.0 && d_side > 0.0)) &&
      ((a_side > 0.0 && b_side < 0.0) || (a_side < 0.0 && b_side > 0.0))) {
    return 0.0;
  }
  return std::min({pointSegmentDistance(a, c, d), pointSegmentDistance(b, c, d),
                   pointSegmentDistance(c, a, b), pointSegmentDistance(d, a, b)});
}

bool isFinite(const Segment2& s) { return s.start.allFinite() && s.end.allFinite(); }

// A doorway and the wall ends it uses (2·wall, +1 for the wall's `end`).
struct Candidate {
  Doorway doorway;
  int end_id_a = 0;
  int end_id_b = 0;
};

// The doorway between walls a and b, if they form one (the header's tests
// but the free-space one).
bool doorwayBetween(const std::vector<Segment2>& walls, int a, int b, const DoorwayOptions& options,
                    Candidate* candidate) {
  const Segment2& wall_a = walls[a];
  const Segment2& wall_b = walls[b];
  const double length_a = (wall_a.end - wall_a.start).norm();
  const double length_b = (wall_b.end - wall_b.start).norm();
  if (length_a < kMinWallLength || length_b < kMinWallLength) return false;
  const Vector2 d_a = (wall_a.end - wall_a.start) / length_a;
  const Vector2 d_b = (wall_b.end - wall_b.start) / length_b;
  if (std::atan2(std::abs(cross(d_a, d_b)), std::abs(d_a.dot(d_b))) > options.max_angle) {
    return false;
  }
  // b's ends along a's direction, from a's start.
  const double t_start = d_a.dot(wall_b.start - wall_a.start);
  const double t_end = d_a.dot(wall_b.end - wall_a.start);
  const bool b_start_nearer = t_start < t_end;
  Candidate c;
  c.doorway.wall_a = a;
  c.doorway.wall_b = b;
  if (std::min(t_start, t_end) > length_a) {  // b beyond a's end
    c.end_id_a = 2 * a + 1;
    c.end_id_b = 2 * b + (b_start_nearer ? 0 : 1);
  } else if (std::max(t_start, t_end) < 0.0) {  // b before a's start
    c.end_id_a = 2 * a;
    c.end_id_b = 2 * b + (b_start_nearer ? 1 : 0);
  } else {
    return false;  // overlapping along the line
  }
  c.doorway.end_a = c.end_id_a % 2 ? wall_a.end : wall_a.start;
  c.doorway.end_b = c.end_id_b % 2 ? wall_b.end : wall_b.start;
  if (std::abs(cross(d_a, c.doorway.end_b - wall_a.start)) > options.max_offset ||
      std::abs(cross(d_b, c.doorway.end_a - wall_b.start)) > options.max_offset) {
    return false;
  }
  c.doorway.width = (c.doorway.end_b - c.doorway.end_a).norm();
  if (c.doorway.width < options.min_width || c.doorway.width > options.max_width) return false;
  // The opening without `2·clearance` at each jamb: walls meeting a jamb
  // (a corner, the wall's other side) do not close the door.
  const Vector2 u = (c.doorway.end_b - c.doorway.end_a) / c.doorway.width;
  const double trim = std::min(2.0 * options.clearance, 0.5 * c.doorway.width);
  const Vector2 inner_a = c.doorway.end_a + trim * u, inner_b = c.doorway.end_b - trim * u;
  for (int w = 0; w < static_cast<int>(walls.size()); ++w) {
    if (w == a || w == b || (walls[w].end - walls[w].start).norm() < kMinWallLength) continue;
    if (segmentDistance(inner_a, inner_b, walls[w].start, walls[w].end) < options.clearance) {
      return false;
    }
  }
  *candidate = c;
  return true;
}

}  // namespace

std::string DoorwayOptions::validate() const {
  const std::string error = checkFields(*this);
  if (!error.empty()) return "DoorwayOptions." + error;
  if (min_width > max_width) return "DoorwayOptions.min_width must be <= max_width";
  return "";
}

FreeSpaceTest crossesNoWall(std::vector<Segment2> walls) {
  return [walls = std::move(walls)](const Vector2& from, const Vector2& to) {
    return std::none_of(walls.begin(), walls.end(), [&](const Segment2& w) {
      return segmentDistance(from, to, w.start, w.end) == 0.0;
    });
  };
}

std::vector<Doorway> findDoorways(const std::vector<Segment2>& walls, const DoorwayOptions& options,
                                  const FreeSpaceTest& is_free) {
  if (!options.validate().empty()) return {};
  if (!std::all_of(walls.begin(), walls.end(), isFinite)) return {};
  std::vector<Candidate> candidates;
  const int n = static_cast<int>(walls.size());
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      Candidate c;
      if (!doorwayBetween(walls, a, b, options, &c)) continue;
      if (is_free) {
        const Vector2 u = (c.doorway.end_b - c.doorway.end_a) / c.doorway.width;
        const Vector2 across = options.free_space_depth * Vector2(-u.y(), u.x());
        if (!is_free(c.doorway.centre() - across, c.doorway.centre() + across)) continue;
      }
      candidates.push_back(c);
    }
  }
  std::stable_sort(
      candidates.begin(), candidates.end(),
      [](const Candidate& s, const Candidate& t) { return s.doorway.width < t.doorway.width; });
  std::vector<Doorway> doorways;
  std::set<int> used_ends;
  for (const Candidate& c : candidates) {
    if (used_ends.count(c.end_id_a) || used_ends.count(c.end_id_b)) continue;
    used_ends.insert(c.end_id_a);
    used_ends.insert(c.end_id_b);
    doorways.push_back(c.doorway);
  }
  return doorways;
}

std::string RoomMapOptions::validate() const {
  const std::string error = checkFields(*this);
  if (!error.empty()) return "RoomMapOptions." + error;
  if (wall_inflation < resolution) {
    return "RoomMapOptions.wall_inflation must be >= resolution (a thinner barrier leaks)";
  }
  return "";
}

std::string RoomMap::build(const std::vector<Segment2>& walls, const std::vector<Doorway>& doorways,
                           const RoomMapOptions& options) {
  *this = RoomMap();
  const std::string error = options.validate();
  if (!error.empty()) return error;
  if (walls.empty()) return "RoomMap: no walls";
  std::vector<Segment2> barriers;
  for (std::size_t i = 0; i < walls.size(); ++i) {
    if (!isFinite(walls[i])) return "RoomMap: wall " + std::to_string(i) + " is not finite";
    barriers.push_back(walls[i]);
  }
  for (std::size_t i = 0; i < doorways.size(); ++i) {
    if (!isFinite(doorways[i].opening())) {
      return "RoomMap: doorway " + std::to_string(i) + " is not finite";
    }
    barriers.push_back(doorways[i].opening());
  }
  Vector2 low = barriers[0].start, high = low;
  for (const Segment2& s : barriers) {
    low = low.cwiseMin(s.start).cwiseMin(s.end);
    high = high.cwiseMax(s.start).cwiseMax(s.end);
  }
  const double border = options.margin + options.wall_inflation;
  low -= Vector2::Constant(border);
  high += Vector2::Constant(border);
  const double cells_x = std::ceil((high.x() - low.x()) / options.resolution);
  const double cells_y = std::ceil((high.y() - low.y()) / options.resolution);
  if (cells_x * cells_y > options.max_cells) {
    return "RoomMap: the walls span " + std::to_string(cells_x * cells_y) +
           " cells, more than max_cells";
  }
  origin_ = low;
  resolution_ = options.resolution;
  width_ = static_cast<int>(cells_x);
  height_ = static_cast<int>(cells_y);
  const std::size_t size = static_cast<std::size_t>(width_) * height_;
  // Barriers: every cell whose centre lies within wall_inflation of a
  // segment. As wall_inflation >= resolution, every cell the segment
  // crosses is a barrier, and a 4-connected path cannot cross the band.
  constexpr int kFree = -2, kBarrier = -1;
  std::vector<int> labels(size, kFree);
  const double r = options.wall_inflation;
  for (const Segment2& s : barriers) {
    const Vector2 s_low = s.start.cwiseMin(s.end) - Vector2::Constant(r) - origin_;
    const Vector2 s_high = s.start.cwiseMax(s.end) + Vector2::Constant(r) - origin_;
    const int x0 = std::max(0, static_cast<int>(std::floor(s_low.x() / resolution_)));
    const int y0 = std::max(0, static_cast<int>(std::floor(s_low.y() / resolution_)));
    const int x1 = std::min(width_ - 1, static_cast<int>(std::floor(s_high.x() / resolution_)));
    const int y1 = std::min(height_ - 1, static_cast<int>(std::floor(s_high.y() / resolution_)));
    for (int iy = y0; iy <= y1; ++iy) {
      for (int ix = x0; ix <= x1; ++ix) {
        const Vector2 centre = origin_ + resolution_ * Vector2(ix + 0.5, iy + 0.5);
        if (pointSegmentDistance(centre, s.start, s.end) <= r) {
          labels[static_cast<std::size_t>(iy) * width_ + ix] = kBarrier;
        }
      }
    }
  }
  // Regions: 4-connected flood fill of the free cells.
  int rooms = 0;
  std::deque<std::size_t> queue;
  for (std::size_t seed = 0; seed < size; ++seed) {
    if (labels[seed] != kFree) continue;
    labels[seed] = rooms;
    queue.push_back(seed);
    while (!queue.empty()) {
      const std::size_t cell = queue.front();
      queue.pop_front();
      const int ix = static_cast<int>(cell % width_), iy = static_cast<int>(cell / width_);
      const int nx[4] = {ix - 1, ix + 1, ix, ix};
      const int ny[4] = {iy, iy, iy - 1, iy + 1};
      for (int t = 0; t < 4; ++t) {
        if (nx[t] < 0 || ny[t] < 0 || nx[t] >= width_ || ny[t] >= height_) continue;
        const std::size_t next = static_cast<std::size_t>(ny[t]) * width_ + nx[t];
        if (labels[next] != kFree) continue;
        labels[next] = rooms;
        queue.push_back(next);
      }
    }
    ++rooms;
  }
  labels_ = std::move(labels);
  room_count_ = rooms;
  return "";
}

bool RoomMap::cellOf(const Vector2& point, int* ix, int* iy) const {
  if (labels_.empty() || !point.allFinite()) return false;
  const double fx = std::floor((point.x() - origin_.x()) / resolution_);
  const double fy = std::floor((point.y() - origin_.y()) / resolution_);
  if (fx < 0.0 || fy < 0.0 || fx >= width_ || fy >= height_) return false;
  *ix = static_cast<int>(fx);
  *iy = static_cast<int>(fy);
  return true;
}

int RoomMap::roomAt(const Vector2& point) const {
  int ix, iy;
  return cellOf(point, &ix, &iy) ? labelAt(ix, iy) : -1;
}

int RoomMap::roomOf(const Vector2& point, const Vector2& seen_from) const {
  if (labels_.empty() || !point.allFinite() || !seen_from.allFinite()) return -1;
  const Vector2 step = seen_from - point;
  // Half-cell steps visit every cell on the way.
  const int steps = static_cast<int>(std::ceil(2.0 * step.norm() / resolution_));
  for (int s = 0; s <= steps; ++s) {
    const int room = roomAt(steps == 0 ? point : point + step * (double(s) / steps));
    if (room >= 0) return room;
  }
  return -1;
}

}  // namespace ekf_slam
