// Where to explore next on a live occupancy grid (the thesis's next step,
// §6.5): frontiers, a robot's reach over the grid, and the path to a goal.
//
// - The grid is the SLAM node's `/map` as GridMapFile holds it: -1 unknown,
//   0..100 occupancy; a cell up to `free_max` is free.
// - A cell is traversable when it is free and no cell above `free_max`
//   (occupied or uncertain) lies within `robot_radius` of its centre: the
//   grid inflated by the robot. Unknown cells are not traversable.
// - reachFrom() runs Dijkstra over the traversable cells (8-connected, steps
//   of 1 or √2 cells) from the robot's cell: every reachable cell's path
//   cost and its predecessor. A step costs its length, lengthened near
//   obstacles: by wall_penalty × (wall_clearance − clearance) / wall_clearance
//   of it where the cell's clearance (distance to the nearest non-free known
//   cell) is below wall_clearance, so paths keep to the middle of a
//   corridor or a door rather than grazing the inflation's edge; a step
//   where the clearance is below goal_clearance (no room to turn on the
//   spot) costs narrow_penalty times more again, so that the robot squeezes
//   past furniture only where there is no way round.
// - A frontier is a connected group (8-neighbours) of free cells that touch
//   an unknown cell (4-neighbours) and keep `frontier_clearance` from every
//   known non-free cell (a wall mapped twice, its copies a cell or two
//   apart, leaves free cells between them that touch the unknown behind
//   the wall: the laser can never see there), at least `min_frontier_length` long, cut
//   into pieces of at most `max_frontier_length` along its length (a room's
//   whole unseen edge is many places to look from, not one); its goal is
//   the reachable cell nearest its centroid among its cells and those
//   within twice goal_clearance of them that keep goal_clearance from
//   obstacles and from the unknown (room for the robot to turn there, even
//   beside a wall not seen yet: a goal in the unseen gap behind furniture
//   would wedge the robot).
// - chooseFrontier() prefers finishing the robot's current room (a room
//   label per position, e.g. from the walls and doorways of
//   mecp/room_gating.h), then the lowest cost: path length minus
//   `gain_weight` times the frontier's length. planExploration() remembers
//   the rooms left finished and goes back into one only for a frontier at
//   least `reopen_length` long.
// No ROS; the node that drives the robot (its planner loop, the path
// follower and the safety gate) is above.
#pragma once

#include <deque>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/io/grid_map_file.h"

namespace ekf_slam {

struct ExplorationOptions {
  int free_max = 25;                 // occupancy value up to which a cell is free (0..100)
  double robot_radius = 0.4;         // m: cells nearer a non-free known cell are not traversable
  double wall_clearance = 0.8;       // m: cells nearer an obstacle than this cost more to cross
  double wall_penalty = 3.0;         // extra cost of a step at the inflation's edge (× its length)
  double goal_clearance = 0.5;       // m from obstacles a goal keeps: room to turn on the spot
  double narrow_penalty = 10.0;      // cost factor of a step with less than goal_clearance
  double frontier_clearance = 0.1;   // m from known non-free cells a frontier cell keeps
  double min_frontier_length = 0.5;  // m of frontier (cells times resolution)
  double max_frontier_length = 2.0;  // m: longer frontiers are cut into pieces this long
  double gain_weight = 1.0;          // m of path a metre of frontier is worth
  double door_width = 1.2;  // m: free space splits into rooms at passages this narrow; 0: no rooms
  double reopen_length = 2.0;  // m of frontier that draws the robot back into a finished room

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.integer("free_max", free_max, Bounds::closed(0, 99, ""));
    v.number("robot_radius", robot_radius, Bounds::closed(0.0, 5.0, "m"));
    v.number("wall_clearance", wall_clearance, Bounds::closed(0.0, 10.0, "m"));
    v.number("wall_penalty", wall_penalty, Bounds::closed(0.0, 100.0, ""));
    v.number("goal_clearance", goal_clearance, Bounds::closed(0.0, 5.0, "m"));
    v.number("narrow_penalty", narrow_penalty, Bounds::closed(1.0, 1000.0, ""));
    v.number("frontier_clearance", frontier_clearance, Bounds::closed(0.0, 1.0, "m"));
    v.number("min_frontier_length", min_frontier_length, Bounds::closed(0.0, 100.0, "m"));
    v.number("max_frontier_length", max_frontier_length, Bounds::closed(0.1, 1000.0, "m"));
    v.number("gain_weight", gain_weight, Bounds::closed(0.0, 1000.0, "m/m"));
    v.number("door_width", door_width, Bounds::closed(0.0, 10.0, "m"));
    v.number("reopen_length", reopen_length, Bounds::closed(0.0, 1000.0, "m"));
  }
};

// The grid as the explorer sees it. Cells are numbered row by row from the
// lower left, as in GridMapFile; the grid's yaw must be 0 (the SLAM node's
// is).
class ExplorationGrid {
 public:
  ExplorationGrid(const GridMapFile& grid, const ExplorationOptions& options);

  int width() const { return width_; }
  int height() const { return height_; }
  int cellCount() const { return width_ * height_; }
  double resolution() const { return resolution_; }
  double robotRadius() const { return robot_radius_; }
  // The cell holding `p` (map frame), or -1 outside the grid.
  int cellAt(const Vector2& p) const;
  Vector2 centre(int cell) const;

  bool unknown(int cell) const { return cells_[cell] < 0; }
  bool free(int cell) const { return cells_[cell] >= 0 && cells_[cell] <= free_max_; }
  bool traversable(int cell) const { return traversable_[cell]; }
  // The cost of one metre through `cell` (1 away from obstacles).
  double stepWeight(int cell) const { return weight_[cell]; }
  // The distance (m) from `cell` to the nearest known, non-free cell, up to
  // max(wall_clearance, goal_clearance); +inf beyond.
  double clearance(int cell) const {
    return clearance_.empty() ? std::numeric_limits<double>::infinity() : clearance_[cell];
  }
  // The same from the nearest cell that is not known free (the unknown as
  // well), up to goal_clearance: where a goal leaves room to turn even
  // beside a wall not seen yet.
  double openClearance(int cell) const {
    return open_clearance_.empty() ? std::numeric_limits<double>::infinity()
                                   : open_clearance_[cell];
  }

 private:
  int width_ = 0, height_ = 0;
  double resolution_ = 0.05;
  Vector2 origin_ = Vector2::Zero();
  int free_max_ = 25;
  double robot_radius_ = 0.0;
  std::vector<int8_t> cells_;
  std::vector<bool> traversable_;
  std::vector<double> weight_;
  std::vector<double> clearance_;       // m; empty when neither option needs it
  std::vector<double> open_clearance_;  // m; empty without goal_clearance
};

// Marks the unknown cells within `radius` of `p` free: the floor under the
// robot, which its laser does not see.
void clearFootprint(GridMapFile* grid, const Vector2& p, double radius);

// The robot's reach: per cell the path cost from the start (m of path,
// lengthened near obstacles by stepWeight; +inf where unreachable) and the previous cell on that
// path (-1 at the start and where unreachable).
struct Reach {
  int start = -1;
  std::vector<double> distance;
  std::vector<int> previous;

  bool reachable(int cell) const;
};

// Dijkstra from the cell of `start`. Inside the inflation (a robot next to
// a wall) the free cells lead out of it: from a cell that is not
// traversable any free neighbour may be taken, from a traversable one only
// traversable ones. A start outside the grid or on an unknown or non-free
// cell reaches nothing.
Reach reachFrom(const ExplorationGrid& grid, const Vector2& start);

// The path from the reach's start to `cell`, cell centres in the map frame
// (start first); empty when `cell` is unreachable.
std::vector<Vector2> pathTo(const ExplorationGrid& grid, const Reach& reach, int cell);

struct Frontier {
  std::vector<int> cells;
  Vector2 centroid = Vector2::Zero();  // map frame
  double length = 0.0;                 // m (cells times resolution)
  int goal = -1;                       // its reachable cell nearest its centroid; -1: none
  double distance = 0.0;               // m of path to `goal`; +inf without one
};

// Every frontier (piece) at least options.min_frontier_length long,
// largest first.
std::vector<Frontier> findFrontiers(const ExplorationGrid& grid, const Reach& reach,
                                    const ExplorationOptions& options);

// The path with the points it does not need left out: every point dropped
// lies within `tolerance` (m) of the straight segment that replaces it
// (Douglas–Peucker). The first and last points are kept.
std::vector<Vector2> simplifyPath(const std::vector<Vector2>& path, double tolerance);

// Whether the path still holds on this grid (one planned on an older grid
// may not): every cell it crosses is free, and traversable beyond the robot's
// radius from its first point (the robot may start beside a wall).
bool pathClear(const ExplorationGrid& grid, const std::vector<Vector2>& path);

// The floor the robot's own body has covered: its latest poses (in one
// frame, the odometry's: exact over a few metres, and unmoved by loop
// closures), each with the body's rectangle. The laser looks forward only,
// so the map may not know the floor behind the robot, yet where the robot
// stood there was room for it.
class SweptFloor {
 public:
  // The body: `front` ahead of the centre, `rear` behind it, `half_width`
  // either side (m); at most `max_poses` poses are kept, the newest.
  SweptFloor(double front, double rear, double half_width, size_t max_poses);
  // Keeps `pose` when it lies 5 cm or 0.1 rad from the newest pose kept.
  void add(const Pose2& pose);
  // Whether `point` (the poses' frame) lies in the body at a kept pose.
  bool covers(const Vector2& point) const;
  size_t size() const { return poses_.size(); }
  // Forgets every pose (the frame was reset: an odometry jump).
  void clear() { poses_.clear(); }

 private:
  double front_, rear_, half_width_;
  size_t max_poses_;
  std::deque<Pose2> poses_;
};

// Whether the map shows free floor for a straight move the laser does not
// watch (a back-off): every cell of the strip `half_width` either side of
// the segment from `from` to `to`, sampled at half a cell, is known and
// free. The strip is the robot's body, not its turning circle: a robot
// standing in a door can back out of it. A point the map does not know
// counts as free where `swept` (when given) says the robot's body has
// covered it; a known obstacle never does.
bool stripFree(const ExplorationGrid& grid, const Vector2& from, const Vector2& to,
               double half_width, const std::function<bool(const Vector2&)>& swept = nullptr);

// The room of a position (map frame), or -1 where none is known.
using RoomOf = std::function<int(const Vector2&)>;

// Rooms on the grid, the thesis's rooms and doorways (§4.4) found in the
// free space rather than in line features: the cells farther than
// door_width / 2 from every cell that is not free (walls, and the unknown)
// fall apart at each doorway into connected cores, one a room (a corridor
// is one too); every other free cell joins the core nearest it through
// free space. One label per cell (0, 1, …), -1 where not free or cut off.
// Labels are numbered afresh on each grid: compare them within one grid.
std::vector<int> segmentRooms(const ExplorationGrid& grid, double door_width);

// The frontier to go to next, as an index into `frontiers`: among the
// reachable ones, those in the robot's room (room_of at `robot`) first,
// then the lowest distance − gain_weight × length. None when no frontier
// is reachable. `room_of` may be empty (no rooms known).
std::optional<size_t> chooseFrontier(const std::vector<Frontier>& frontiers,
                                     const ExplorationGrid& grid, const Vector2& robot,
                                     const RoomOf& room_of, const ExplorationOptions& options);

// Whether a frontier goal (map frame) is to be passed over: the explorer
// gave up on one there.
using Excluded = std::function<bool(const Vector2&)>;

// One planning round from the robot's position: its reach, the frontiers
// (those whose goal `excluded` names keep no goal), the one chosen and the
// path to its goal (simplified to within a cell). No choice when no
// frontier is reachable.
// - `current`: the goal the robot is driving to; the frontier whose goal
//   lies within `same_goal` (m) of it is kept while it lasts and can be
//   reached, whatever chooseFrontier would prefer on the newer map: the
//   robot finishes what it set out for (a room it is heading into) rather
//   than turning round at every map.
// - `finished_rooms`: a position in each room the robot has left finished
//   (the plan's `finished_room` of earlier rounds). A frontier in one of
//   them, other than the robot's own, keeps no goal unless it is at least
//   reopen_length long: the map still changes in a room the robot has left
//   (a SLAM correction redraws it, the laser looks in through its door),
//   and the crumbs that come and go behind its furniture are not worth
//   driving back for; a passage found is.
struct ExplorationPlan {
  Reach reach;
  std::vector<Frontier> frontiers;
  std::optional<size_t> chosen;
  std::vector<Vector2> path;
  // The robot's position when the choice leaves its room and no frontier
  // in that room keeps a goal (the room is finished), unless the room is
  // among `finished_rooms` already.
  std::optional<Vector2> finished_room;
};
ExplorationPlan planExploration(const ExplorationGrid& grid, const Vector2& robot,
                                const RoomOf& room_of, const Excluded& excluded,
                                const ExplorationOptions& options,
                                const std::optional<Vector2>& current = std::nullopt,
                                double same_goal = 0.0,
                                const std::vector<Vector2>& finished_rooms = {});

}  // namespace ekf_slam
