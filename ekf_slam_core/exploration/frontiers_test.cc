#include "ekf_slam_core/exploration/frontiers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace ekf_slam {
namespace {

// A grid drawn in text, top row first: '#' occupied, '.' free, '?' unknown.
// 0.1 m cells, the lower left corner at the origin.
GridMapFile drawn(const std::vector<std::string>& rows) {
  GridMapFile g;
  g.resolution = 0.1;
  g.height = static_cast<int>(rows.size());
  g.width = static_cast<int>(rows[0].size());
  g.cells.resize(static_cast<size_t>(g.width) * g.height);
  for (int r = 0; r < g.height; ++r) {
    for (int x = 0; x < g.width; ++x) {
      const char c = rows[g.height - 1 - r][x];
      g.cells[r * g.width + x] = c == '#' ? 100 : (c == '.' ? 0 : -1);
    }
  }
  return g;
}

// A room of free cells 2 m × 1 m, walled, open to unknown space on its
// right, with a two-cell pocket of unknown in its floor.
std::vector<std::string> roomOpenToTheRight() {
  std::vector<std::string> rows;
  rows.push_back(std::string(22, '#') + std::string(8, '?'));
  for (int r = 0; r < 10; ++r) {
    std::string row = "#" + std::string(21, '.') + std::string(8, '?');
    if (r == 5) row[6] = row[7] = '?';
    rows.push_back(row);
  }
  rows.push_back(std::string(22, '#') + std::string(8, '?'));
  return rows;
}

TEST(Frontiers, FoundAlongTheEdgeOfTheKnownAndSmallOnesLeftOut) {
  ExplorationOptions options;
  options.robot_radius = 0.15;
  const ExplorationGrid grid(drawn(roomOpenToTheRight()), options);
  const Reach reach = reachFrom(grid, Vector2(0.55, 0.65));
  const std::vector<Frontier> frontiers = findFrontiers(grid, reach, options);
  // The open side (ten cells, 1 m) and the pocket (the six free cells
  // around it, 0.6 m); a 0.9 m minimum leaves the pocket out.
  ASSERT_EQ(frontiers.size(), 2u);
  EXPECT_EQ(frontiers[0].cells.size(), 10u);
  EXPECT_NEAR(frontiers[0].centroid.x(), 2.15, 1e-9);
  EXPECT_NEAR(frontiers[0].centroid.y(), 0.6, 1e-9);
  EXPECT_GE(frontiers[0].goal, 0);
  EXPECT_GT(frontiers[0].distance, 1.4);
  options.min_frontier_length = 0.9;
  EXPECT_EQ(findFrontiers(grid, reach, options).size(), 1u);
}

// A room 1.45 m × 1 m on 5 cm cells, open to the unknown on its right; its
// top wall mapped twice, the outer copy with a 1.3 m gap through which the
// free cells between the copies touch the unknown beyond the wall.
TEST(Frontiers, AWallMappedTwiceIsNoFrontier) {
  std::vector<std::string> rows;
  rows.push_back(std::string(34, '?'));
  rows.push_back("####" + std::string(26, '.') + "####");
  rows.push_back(std::string(34, '#'));
  for (int r = 0; r < 20; ++r) rows.push_back("#" + std::string(29, '.') + "????");
  rows.push_back(std::string(30, '#') + "????");
  GridMapFile map = drawn(rows);
  map.resolution = 0.05;
  ExplorationOptions options;
  options.robot_radius = 0.1;
  options.frontier_clearance = 0.0;
  const ExplorationGrid all(map, options);
  const Vector2 robot(0.5, 0.5);
  ASSERT_EQ(findFrontiers(all, reachFrom(all, robot), options).size(), 2u);
  options.frontier_clearance = 0.1;
  const ExplorationGrid open(map, options);
  const std::vector<Frontier> frontiers = findFrontiers(open, reachFrom(open, robot), options);
  ASSERT_EQ(frontiers.size(), 1u);
  EXPECT_NEAR(frontiers[0].centroid.x(), 1.475, 1e-9) << "the open side, not the wall";
  EXPECT_EQ(frontiers[0].cells.size(), 18u) << "less the cells beside the walls";
}

// Two rooms joined by a door in a wall; whether the robot gets through
// depends on the door's width against its radius.
std::vector<std::string> twoRoomsWithADoor(int door_cells) {
  std::vector<std::string> rows;
  const int height = 20;
  for (int r = 0; r < height; ++r) {
    std::string row(41, '.');
    row[0] = row[40] = '#';
    if (r == 0 || r == height - 1) row = std::string(41, '#');
    const int door_from = height / 2 - door_cells / 2;
    if (r > 0 && r < height - 1 && (r < door_from || r >= door_from + door_cells)) row[20] = '#';
    rows.push_back(row);
  }
  return rows;
}

TEST(Planner, PassesADoorWiderThanTheRobotAndNotANarrowerOne) {
  ExplorationOptions options;
  options.robot_radius = 0.25;
  options.wall_penalty = 0.0;  // path lengths in plain metres
  options.narrow_penalty = 1.0;
  const Vector2 left(0.85, 1.05), right(3.35, 1.05);  // cell centres, 25 cells apart
  {
    const ExplorationGrid grid(drawn(twoRoomsWithADoor(8)), options);  // 0.8 m
    const Reach reach = reachFrom(grid, left);
    const int goal = grid.cellAt(right);
    ASSERT_TRUE(reach.reachable(goal));
    const std::vector<Vector2> path = pathTo(grid, reach, goal);
    ASSERT_GE(path.size(), 2u);
    EXPECT_LT((path.front() - left).norm(), 1e-9);
    EXPECT_LT((path.back() - right).norm(), 1e-9);
    // Through the door, and no step longer than a diagonal cell.
    bool through_door = false;
    for (size_t i = 0; i < path.size(); ++i) {
      if (std::abs(path[i].x() - 2.05) < 0.06) through_door = std::abs(path[i].y() - 1.0) < 0.4;
      if (i > 0) {
        EXPECT_LE((path[i] - path[i - 1]).norm(), 0.1 * std::sqrt(2.0) + 1e-9);
      }
    }
    EXPECT_TRUE(through_door);
    EXPECT_NEAR(reach.distance[goal], 2.5, 1e-9);  // straight through the door's middle
  }
  {
    const ExplorationGrid grid(drawn(twoRoomsWithADoor(4)), options);  // 0.4 m
    const Reach reach = reachFrom(grid, left);
    EXPECT_FALSE(reach.reachable(grid.cellAt(right)));
    EXPECT_TRUE(pathTo(grid, reach, grid.cellAt(right)).empty());
  }
}

TEST(Planner, ARobotInADoorCanBackOutOfItWhereTheFloorIsKnown) {
  // A 0.7 m door (y 0.6 to 1.3) in the wall at x = 2.05; the robot stands
  // in its middle heading +x, and backs 0.5 m towards -x.
  const ExplorationGrid grid(drawn(twoRoomsWithADoor(7)), ExplorationOptions{});
  const Vector2 in_door(2.05, 0.95), behind(1.55, 0.95);
  // Its body (0.25 m either side) fits; its turning circle (0.4 m) does not.
  EXPECT_TRUE(stripFree(grid, in_door, behind, 0.25));
  EXPECT_FALSE(stripFree(grid, in_door, behind, 0.4));
  // Off the door's middle by 0.15 m, the body meets the door's jamb.
  EXPECT_FALSE(stripFree(grid, in_door + Vector2(0.0, 0.15), behind + Vector2(0.0, 0.15), 0.25));
  // Floor the map does not know is no room either.
  GridMapFile unknown_behind = drawn(twoRoomsWithADoor(7));
  unknown_behind.cells[grid.cellAt(Vector2(1.75, 0.95))] = -1;
  EXPECT_FALSE(
      stripFree(ExplorationGrid(unknown_behind, ExplorationOptions{}), in_door, behind, 0.25));
}

TEST(Planner, FloorTheRobotDroveOverCountsAsRoomToBackOffWhereTheMapDoesNotKnowIt) {
  // The door of the test above, the floor behind the robot unknown to the
  // map (the laser never looked back): the robot came through the door
  // along y = 0.95 heading +x, and stands in it.
  GridMapFile map = drawn(twoRoomsWithADoor(7));
  const Vector2 in_door(2.05, 0.95), behind(1.55, 0.95);
  ExplorationGrid probe(map, ExplorationOptions{});
  for (double x = 0.6; x < 2.0; x += 0.5 * probe.resolution()) {
    for (double y = 0.6; y <= 1.3; y += 0.5 * probe.resolution()) {
      map.cells[probe.cellAt(Vector2(x, y))] = -1;
    }
  }
  const ExplorationGrid grid(map, ExplorationOptions{});
  ASSERT_FALSE(stripFree(grid, in_door, behind, 0.25));
  // Its body, 0.25 m ahead and 0.35 m behind its centre, 0.25 m either
  // side, at poses 5 cm apart on the way in.
  SweptFloor came_in(0.25, 0.35, 0.25, 100);
  for (int k = 0; k <= 125; ++k) came_in.add(Pose2(0.8 + 0.01 * k, 0.95, 0.0));
  // A pose is kept every 5 cm (or 0.1 rad) only.
  EXPECT_GE(came_in.size(), 20u);
  EXPECT_LE(came_in.size(), 26u);
  const auto covered = [&](const Vector2& p) { return came_in.covers(p); };
  EXPECT_TRUE(stripFree(grid, in_door, behind, 0.25, covered));
  // Its body is no wider than it was: a wider strip reaches floor it never
  // covered.
  EXPECT_FALSE(stripFree(grid, in_door, behind, 0.3, covered));
  // Forgotten (the odometry was reset), the floor is unknown again.
  SweptFloor forgotten = came_in;
  forgotten.clear();
  EXPECT_FALSE(stripFree(grid, in_door, behind, 0.25,
                         [&](const Vector2& p) { return forgotten.covers(p); }));
  // Came in along another line (turned in the door since), the floor
  // straight behind it is not covered.
  SweptFloor from_below(0.25, 0.35, 0.25, 100);
  for (int k = 0; k <= 29; ++k) from_below.add(Pose2(1.5, -0.5 + 0.05 * k, M_PI / 2));
  EXPECT_FALSE(stripFree(grid, in_door, behind, 0.25,
                         [&](const Vector2& p) { return from_below.covers(p); }));
  // Only the newest poses are kept: those of the last 12 cm reach 0.47 m
  // behind the centre, short of the 0.5 m.
  SweptFloor short_memory(0.25, 0.35, 0.25, 3);
  for (int k = 20; k >= 0; --k) short_memory.add(Pose2(2.05 - 0.06 * k, 0.95, 0.0));
  EXPECT_EQ(short_memory.size(), 3u);
  EXPECT_FALSE(stripFree(grid, in_door, behind, 0.25,
                         [&](const Vector2& p) { return short_memory.covers(p); }));
  // A known obstacle is never floor: the jamb off the door's middle stays.
  EXPECT_FALSE(stripFree(grid, in_door + Vector2(0.0, 0.15), behind + Vector2(0.0, 0.15), 0.25,
                         [](const Vector2&) { return true; }));
}

TEST(Planner, AStartBesideAWallStillGetsOutAndAStartInTheUnknownReachesNothing) {
  ExplorationOptions options;
  options.robot_radius = 0.25;
  const ExplorationGrid grid(drawn(twoRoomsWithADoor(8)), options);
  const Reach near_wall = reachFrom(grid, Vector2(0.15, 1.0));  // 0.05 m from the wall
  EXPECT_TRUE(near_wall.reachable(grid.cellAt(Vector2(1.0, 1.0))));
  const GridMapFile blank = drawn({"????", "????"});
  const ExplorationGrid unknown(blank, options);
  const Reach none = reachFrom(unknown, Vector2(0.15, 0.15));
  for (int c = 0; c < unknown.cellCount(); ++c) EXPECT_FALSE(none.reachable(c));
  EXPECT_TRUE(findFrontiers(unknown, none, options).empty());
}

// Two frontiers: one in the robot's own room, farther; one through the
// door, nearer. With rooms known the robot finishes its own room first.
// The laser does not see the floor under the robot: its footprint is
// marked free where unknown, and walls stay walls.
TEST(Planner, TheFootprintUnderTheRobotIsFreeWhereTheMapDoesNotKnowIt) {
  GridMapFile grid = drawn({"??????????", "??????????", "????##????", "??????????", "??????????"});
  clearFootprint(&grid, Vector2(0.5, 0.25), 0.2);
  int free = 0;
  for (int c = 0; c < grid.width * grid.height; ++c) {
    const Vector2 centre(0.1 * (c % grid.width) + 0.05, 0.1 * (c / grid.width) + 0.05);
    const bool inside = (centre - Vector2(0.5, 0.25)).norm() <= 0.2;
    if (grid.cells[c] == 100) {
      EXPECT_EQ(c / grid.width, 2) << "the wall stays";
      continue;
    }
    EXPECT_EQ(grid.cells[c], inside ? 0 : -1) << c;
    free += grid.cells[c] == 0;
  }
  EXPECT_GT(free, 6);
  ExplorationOptions options;
  options.robot_radius = 0.0;
  const ExplorationGrid explored(grid, options);
  EXPECT_TRUE(
      reachFrom(explored, Vector2(0.55, 0.15)).reachable(explored.cellAt(Vector2(0.35, 0.15))));
}

TEST(Frontiers, TheRobotsOwnRoomComesFirst) {
  std::vector<std::string> rows = twoRoomsWithADoor(8);
  // Unknown beyond the far end of the left room's top wall (its left part)
  // and beyond the right room's top wall near the door.
  for (int x = 1; x < 8; ++x) rows[0][x] = '?';
  for (int x = 21; x < 28; ++x) rows[0][x] = '?';
  ExplorationOptions options;
  options.robot_radius = 0.15;
  options.wall_penalty = 0.0;  // plain path lengths: the door's frontier is the nearer
  options.narrow_penalty = 1.0;
  const ExplorationGrid grid(drawn(rows), options);
  const Vector2 robot(1.9, 0.5);  // left room, near the door
  const Reach reach = reachFrom(grid, robot);
  const std::vector<Frontier> frontiers = findFrontiers(grid, reach, options);
  ASSERT_EQ(frontiers.size(), 2u);
  const RoomOf room_of = [](const Vector2& p) { return p.x() < 2.0 ? 0 : 1; };
  const std::optional<size_t> without_rooms =
      chooseFrontier(frontiers, grid, robot, nullptr, options);
  const std::optional<size_t> with_rooms = chooseFrontier(frontiers, grid, robot, room_of, options);
  ASSERT_TRUE(without_rooms && with_rooms);
  EXPECT_GT(frontiers[*without_rooms].centroid.x(), 2.0) << "the nearer one, through the door";
  EXPECT_LT(frontiers[*with_rooms].centroid.x(), 2.0) << "the robot's own room first";

  // Driving to the other room's frontier, the robot keeps to it while it
  // lasts; a goal whose frontier is gone leaves the choice to the rooms.
  const Vector2 other = grid.centre(frontiers[*without_rooms].goal);
  const ExplorationPlan kept =
      planExploration(grid, robot, room_of, nullptr, options, other + Vector2(0.3, 0.0), 0.5);
  ASSERT_TRUE(kept.chosen);
  EXPECT_LT((grid.centre(kept.frontiers[*kept.chosen].goal) - other).norm(), 1e-9);
  EXPECT_LT((kept.path.back() - other).norm(), 1e-9);
  const ExplorationPlan gone =
      planExploration(grid, robot, room_of, nullptr, options, Vector2(3.0, 1.0), 0.5);
  ASSERT_TRUE(gone.chosen);
  EXPECT_LT(gone.frontiers[*gone.chosen].centroid.x(), 2.0);
}

// Two rooms, the right one with a gap of `gap_cells` in its top wall onto
// the unknown; the robot stands in the left one, which holds no frontier.
TEST(Frontiers, ARoomLeftFinishedIsEnteredAgainOnlyForALongFrontier) {
  auto planWith = [](int gap_cells, const Vector2& robot, const std::vector<Vector2>& finished) {
    std::vector<std::string> rows = twoRoomsWithADoor(8);
    for (int x = 30 - gap_cells / 2; x < 30 - gap_cells / 2 + gap_cells; ++x) rows[0][x] = '?';
    ExplorationOptions options;
    options.robot_radius = 0.15;
    options.goal_clearance = 0.3;
    options.reopen_length = 1.0;
    const ExplorationGrid grid(drawn(rows), options);
    const std::vector<int> rooms = segmentRooms(grid, options.door_width);
    const RoomOf room_of = [&grid, rooms](const Vector2& p) {
      const int cell = grid.cellAt(p);
      return cell < 0 ? -1 : rooms[cell];
    };
    EXPECT_NE(room_of(Vector2(1.0, 1.0)), room_of(Vector2(3.0, 1.0))) << "the door splits them";
    return planExploration(grid, robot, room_of, nullptr, options, std::nullopt, 0.0, finished);
  };
  const Vector2 left(1.0, 1.0), right(3.0, 1.0);
  // Crumbs: a frontier shorter than reopen_length (1 m).
  const ExplorationPlan first = planWith(7, left, {});
  ASSERT_EQ(first.frontiers.size(), 1u);
  EXPECT_LT(first.frontiers[0].length, 1.0);
  ASSERT_TRUE(first.chosen) << "a room not yet finished is entered for any frontier";
  ASSERT_TRUE(first.finished_room) << "leaving the left room with nothing in it finishes it";
  EXPECT_LT((*first.finished_room - left).norm(), 1e-9);
  EXPECT_FALSE(planWith(7, left, {left}).finished_room) << "finished once, reported once";

  EXPECT_FALSE(planWith(7, left, {right}).chosen) << "not back into a finished room for crumbs";
  const ExplorationPlan inside = planWith(7, right, {right});
  ASSERT_TRUE(inside.chosen) << "the robot's own room stays open";
  EXPECT_FALSE(inside.finished_room);
  const ExplorationPlan passage = planWith(15, left, {right});
  ASSERT_TRUE(passage.chosen) << "a frontier of 1.5 m reopens the room";
  EXPECT_GE(passage.frontiers[*passage.chosen].length, 1.0);
}

// A corridor 1.4 m wide (y from 0.1 to 1.5 m) and 4 m long.
std::vector<std::string> corridor() {
  std::vector<std::string> rows;
  rows.push_back(std::string(42, '#'));
  for (int r = 0; r < 14; ++r) rows.push_back("#" + std::string(40, '.') + "#");
  rows.push_back(std::string(42, '#'));
  return rows;
}

TEST(Planner, ACostNearTheWallsKeepsThePathToTheCorridorsMiddle) {
  ExplorationOptions options;
  options.robot_radius = 0.25;
  // Start and goal both 0.35 m from the bottom wall's face.
  const Vector2 start(0.45, 0.45), goal(3.65, 0.45);
  auto farthestFromTheWall = [&](const ExplorationOptions& o) {
    const ExplorationGrid grid(drawn(corridor()), o);
    const Reach reach = reachFrom(grid, start);
    const std::vector<Vector2> path = pathTo(grid, reach, grid.cellAt(goal));
    EXPECT_FALSE(path.empty());
    double highest = 0.0;
    for (const Vector2& p : path) highest = std::max(highest, p.y());
    return highest;
  };
  options.wall_penalty = 0.0;
  options.narrow_penalty = 1.0;
  EXPECT_LT(farthestFromTheWall(options), 0.5) << "the shortest path hugs the wall";
  options.wall_penalty = 3.0;
  options.wall_clearance = 0.8;
  EXPECT_NEAR(farthestFromTheWall(options), 0.8, 0.06) << "the middle, 0.7 m from either face";
}

// A frontier across the end of a corridor, 0.4 m before its end wall: its
// goal keeps goal_clearance from the walls, so that the robot can turn on
// the spot there.
TEST(Frontiers, AGoalKeepsRoomToTurnFromTheWalls) {
  std::vector<std::string> rows = corridor();
  for (size_t r = 1; r + 1 < rows.size(); ++r) rows[r].replace(38, 3, "???");
  ExplorationOptions options;
  options.robot_radius = 0.25;
  for (double goal_clearance : {0.0, 0.5}) {
    options.goal_clearance = goal_clearance;
    const ExplorationGrid grid(drawn(rows), options);
    const Reach reach = reachFrom(grid, Vector2(0.7, 0.8));
    const std::vector<Frontier> frontiers = findFrontiers(grid, reach, options);
    ASSERT_EQ(frontiers.size(), 1u);
    ASSERT_GE(frontiers[0].goal, 0);
    EXPECT_GE(grid.clearance(frontiers[0].goal), goal_clearance);
    if (goal_clearance == 0.0) {
      EXPECT_LT(grid.clearance(frontiers[0].goal), 0.5) << "the frontier itself, by the wall";
    }
  }
}

// Goals keep goal_clearance from the unknown as well as from the walls:
// the unknown may hide a wall (the back of furniture), and a goal beside
// it could leave the robot no room to turn.
TEST(Frontiers, AGoalKeepsRoomFromTheUnknownToo) {
  ExplorationOptions options;
  options.robot_radius = 0.15;
  const GridMapFile map = drawn(roomOpenToTheRight());
  const ExplorationGrid grid(map, options);
  const Reach reach = reachFrom(grid, Vector2(0.55, 0.65));
  const std::vector<Frontier> frontiers = findFrontiers(grid, reach, options);
  ASSERT_EQ(frontiers.size(), 2u);
  for (const Frontier& f : frontiers) {
    ASSERT_GE(f.goal, 0);
    for (int c = 0; c < grid.cellCount(); ++c) {
      if (grid.unknown(c)) {
        EXPECT_GE((grid.centre(c) - grid.centre(f.goal)).norm(), options.goal_clearance - 1e-9);
      }
    }
  }
}

// A cabinet in a room: a 0.5 m gap above it, 1 m of floor below it. The
// shortest path squeezes through the gap, where the robot could not turn;
// narrow_penalty sends it round below.
TEST(Planner, ANarrowGapIsCrossedOnlyWithoutAWayRound) {
  std::vector<std::string> rows(22, "#" + std::string(40, '.') + "#");
  rows.front() = rows.back() = std::string(42, '#');
  for (int r = 11; r <= 15; ++r) rows[rows.size() - 1 - r].replace(18, 5, "#####");
  ExplorationOptions options;
  options.robot_radius = 0.2;
  options.wall_penalty = 0.0;
  options.goal_clearance = 0.5;
  auto heightPastTheCabinet = [&](double narrow_penalty) {
    options.narrow_penalty = narrow_penalty;
    const ExplorationGrid grid(drawn(rows), options);
    const Reach reach = reachFrom(grid, Vector2(0.55, 1.85));
    const std::vector<Vector2> path = pathTo(grid, reach, grid.cellAt(Vector2(3.55, 1.85)));
    EXPECT_FALSE(path.empty());
    for (const Vector2& p : path) {
      if (std::abs(p.x() - 2.05) < 0.01) return p.y();
    }
    return -1.0;
  };
  EXPECT_GT(heightPastTheCabinet(1.0), 1.6) << "through the gap";
  EXPECT_LT(heightPastTheCabinet(10.0), 1.1) << "round below";
}

TEST(Planner, ASimplifiedPathKeepsItsCornersAndDropsTheStraightRuns) {
  std::vector<Vector2> path;
  for (int i = 0; i <= 10; ++i) path.emplace_back(0.1 * i, 0.0);
  for (int i = 1; i <= 10; ++i) path.emplace_back(1.0, 0.1 * i);
  const std::vector<Vector2> simple = simplifyPath(path, 0.05);
  ASSERT_EQ(simple.size(), 3u);
  EXPECT_LT((simple[1] - Vector2(1.0, 0.0)).norm(), 1e-9);
  EXPECT_LT((simple[2] - Vector2(1.0, 1.0)).norm(), 1e-9);
  // A staircase of cell steps within the tolerance becomes one segment.
  std::vector<Vector2> stairs;
  for (int i = 0; i <= 20; ++i) stairs.emplace_back(0.05 * i, 0.05 * (i / 2));
  EXPECT_EQ(simplifyPath(stairs, 0.05).size(), 2u);
  EXPECT_EQ(simplifyPath({Vector2(0, 0)}, 0.05).size(), 1u);
}

TEST(Planner, APathAcrossANewWallIsNoLongerClear) {
  ExplorationOptions options;
  options.robot_radius = 0.25;
  std::vector<std::string> rows = corridor();
  const ExplorationGrid open(drawn(rows), options);
  const Vector2 start(0.15, 0.8), goal(3.65, 0.8);  // the start beside the left wall
  const std::vector<Vector2> path =
      simplifyPath(pathTo(open, reachFrom(open, start), open.cellAt(goal)), open.resolution());
  ASSERT_GE(path.size(), 2u);
  EXPECT_TRUE(pathClear(open, path)) << "the start inside the inflation does not count";
  for (size_t r = 1; r + 1 < rows.size(); ++r) rows[r][20] = '#';  // a wall across it
  const ExplorationGrid closed(drawn(rows), options);
  EXPECT_FALSE(pathClear(closed, path));
  EXPECT_FALSE(reachFrom(closed, start).reachable(closed.cellAt(goal)));
}

TEST(Frontiers, AGoalGivenUpIsPassedOver) {
  std::vector<std::string> rows = twoRoomsWithADoor(8);
  for (int x = 1; x < 8; ++x) rows[0][x] = '?';
  for (int x = 21; x < 28; ++x) rows[0][x] = '?';
  ExplorationOptions options;
  options.robot_radius = 0.15;
  const ExplorationGrid grid(drawn(rows), options);
  const Vector2 robot(1.9, 0.5);
  const ExplorationPlan first = planExploration(grid, robot, nullptr, nullptr, options);
  ASSERT_TRUE(first.chosen);
  const Vector2 given_up = grid.centre(first.frontiers[*first.chosen].goal);
  ASSERT_GE(first.path.size(), 2u);
  EXPECT_LT((first.path.back() - given_up).norm(), 1e-9);
  const Excluded excluded = [&](const Vector2& p) { return (p - given_up).norm() < 0.5; };
  const ExplorationPlan second = planExploration(grid, robot, nullptr, excluded, options);
  ASSERT_TRUE(second.chosen);
  EXPECT_GT((grid.centre(second.frontiers[*second.chosen].goal) - given_up).norm(), 0.5);
  const ExplorationPlan none = planExploration(
      grid, robot, nullptr, [](const Vector2&) { return true; }, options);
  EXPECT_FALSE(none.chosen);
  EXPECT_TRUE(none.path.empty());
  EXPECT_EQ(none.frontiers.size(), 2u) << "the frontiers are still reported";
}

TEST(Rooms, ADoorSplitsTheFreeSpaceAndAWideOpeningDoesNot) {
  ExplorationOptions options;
  {
    const ExplorationGrid grid(drawn(twoRoomsWithADoor(8)), options);  // a 0.8 m door
    const std::vector<int> rooms = segmentRooms(grid, 1.2);
    const int left = rooms[grid.cellAt(Vector2(1.0, 1.0))];
    const int right = rooms[grid.cellAt(Vector2(3.0, 1.0))];
    EXPECT_GE(left, 0);
    EXPECT_GE(right, 0);
    EXPECT_NE(left, right);
    // Corners and wall-side cells join their own room, walls none.
    EXPECT_EQ(rooms[grid.cellAt(Vector2(0.15, 0.15))], left);
    EXPECT_EQ(rooms[grid.cellAt(Vector2(1.95, 1.85))], left);
    EXPECT_EQ(rooms[grid.cellAt(Vector2(2.15, 0.15))], right);
    EXPECT_EQ(rooms[grid.cellAt(Vector2(0.05, 1.0))], -1);
    EXPECT_TRUE(segmentRooms(grid, 0.0) == std::vector<int>(grid.cellCount(), -1));
  }
  {
    const ExplorationGrid grid(drawn(twoRoomsWithADoor(16)), options);  // 1.6 m: one room
    const std::vector<int> rooms = segmentRooms(grid, 1.2);
    EXPECT_EQ(rooms[grid.cellAt(Vector2(1.0, 1.0))], rooms[grid.cellAt(Vector2(3.0, 1.0))]);
    EXPECT_GE(rooms[grid.cellAt(Vector2(1.0, 1.0))], 0);
  }
}

}  // namespace
}  // namespace ekf_slam
