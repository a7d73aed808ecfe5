// Doorways and rooms (thesis §4.4, §4.4.5): room interfaces are two walls on
// one line with a door-sized gap between their facing ends and free space
// across it; every landmark carries the label of its room, and association
// never pairs landmarks of different rooms.
//
// Doorway test for walls a and b (segments in the map frame):
//   - parallel: the angle between their lines is at most max_angle;
//   - on one line: each facing end lies within max_offset of the other
//     wall's line;
//   - apart: along a's direction, b lies wholly beyond a's end (or wholly
//     before its start); the facing ends are e_a, e_b;
//   - door-sized: min_width <= |e_b − e_a| <= max_width;
//   - open: no other wall comes within `clearance` of the opening e_a–e_b
//     away from its ends (a wall piece in the gap closes it; a wall meeting
//     the jamb does not), and, if a free-space test is given, the path
//     across the gap's middle, free_space_depth to either side, is free.
// A wall end takes part in at most one doorway, the narrowest.
//
// Rooms: the walls and the doorways' openings are drawn as barriers, each
// inflated by wall_inflation, into a grid of `resolution` cells; the
// 4-connected regions of free cells are the rooms (the space outside the
// building is a region too). Inflation closes the small breaks the
// extraction leaves between wall segments (up to about twice the inflation);
// a wider gap that is not a doorway (an open arch, a gap too wide for a
// door) joins the spaces either side into one room, which is what
// association should do there. Landmarks lie on walls, inside barrier
// cells, where the wall's two sides meet: a landmark takes the room of the
// first free cell on the way from it toward the place it was seen from (the
// robot's position when it was observed).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {

// A wall segment, map frame (m).
struct Segment2 {
  Vector2 start = Vector2::Zero();
  Vector2 end = Vector2::Zero();
};

struct DoorwayOptions {
  double min_width = 0.7;            // m, narrowest opening taken for a door
  double max_width = 1.2;            // m, widest (wider: an opening between rooms' parts)
  double max_angle = degToRad(8.0);  // rad, between the two walls' lines
  double max_offset = 0.10;          // m, of each facing end from the other wall's line
  double clearance = 0.05;           // m, another wall this close to the opening closes it
  double free_space_depth = 0.5;     // m, the free-space test's reach either side of the gap

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("min_width", min_width, Bounds::above(0.0, "m"));
    v.number("max_width", max_width, Bounds::above(0.0, "m"));
    v.number("max_angle", max_angle, Bounds::closedOpen(0.0, kPi / 2, "rad"));
    v.number("max_offset", max_offset, Bounds::atLeast(0.0, "m"));
    v.number("clearance", clearance, Bounds::above(0.0, "m"));
    v.number("free_space_depth", free_space_depth, Bounds::above(0.0, "m"));
  }
  // Empty when usable, else names the bad field (also min_width > max_width).
  std::string validate() const;
};

struct Doorway {
  int wall_a = -1;                  // index of one wall in the input
  int wall_b = -1;                  // ... and of the other
  Vector2 end_a = Vector2::Zero();  // m, wall_a's end facing wall_b (a jamb)
  Vector2 end_b = Vector2::Zero();  // m, wall_b's end facing wall_a
  double width = 0.0;               // m, |end_b − end_a|

  Segment2 opening() const { return {end_a, end_b}; }
  Vector2 centre() const { return 0.5 * (end_a + end_b); }
};

// Whether the straight path `from` → `to` (map frame) is free space, e.g.
// from an occupancy grid.
using FreeSpaceTest = std::function<bool(const Vector2& from, const Vector2& to)>;

// The free-space test a map of walls alone gives: the path is free when it
// crosses none of `walls`. With it a gap that has a wall standing across it
// within free_space_depth (a niche, an alcove behind a break in a wall) is
// no door: nothing could pass through it.
FreeSpaceTest crossesNoWall(std::vector<Segment2> walls);

// The doorways among `walls`, narrowest first. Empty when the options are
// invalid or a wall has a non-finite end; zero-length walls are skipped.
std::vector<Doorway> findDoorways(const std::vector<Segment2>& walls, const DoorwayOptions& options,
                                  const FreeSpaceTest& is_free = nullptr);

struct RoomMapOptions {
  double resolution = 0.05;      // m per cell
  double wall_inflation = 0.10;  // m, barrier half-thickness; >= resolution, so no cell leaks
  double margin = 1.0;           // m, free border around the walls' bounding box
  double max_cells = 4.0e6;      // cells: a larger extent (a stray wall far off) is refused

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.number("resolution", resolution, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("wall_inflation", wall_inflation, Bounds::above(0.0, "m"));
    v.number("margin", margin, Bounds::above(0.0, "m"));
    v.number("max_cells", max_cells, Bounds::closed(1.0, 1e9, "cells"));
  }
  // Empty when usable, else names the bad field (also wall_inflation < resolution).
  std::string validate() const;
};

// The rooms of a map: which region of free space a point belongs to.
class RoomMap {
 public:
  // Draws `walls` and the openings of `doorways` and labels the regions.
  // Returns an error message (the map is then empty: every query gives −1),
  // or "" on success.
  std::string build(const std::vector<Segment2>& walls, const std::vector<Doorway>& doorways,
                    const RoomMapOptions& options = {});

  int roomCount() const { return room_count_; }

  // Room of a free point; −1 on a barrier or outside the map.
  int roomAt(const Vector2& point) const;

  // Room of a landmark seen from `seen_from`: that of the first free cell on
  // the segment from `point` toward `seen_from`; −1 when there is none.
  int roomOf(const Vector2& point, const Vector2& seen_from) const;

 private:
  bool cellOf(const Vector2& point, int* ix, int* iy) const;
  int labelAt(int ix, int iy) const { return labels_[static_cast<std::size_t>(iy) * width_ + ix]; }

  Vector2 origin_ = Vector2::Zero();  // m, corner of cell (0, 0)
  double resolution_ = 1.0;
  int width_ = 0, height_ = 0;
  std::vector<int> labels_;  // per cell: room, or −1 for a barrier
  int room_count_ = 0;
};

}  // namespace ekf_slam
