// Doorways and room labels on small drawn worlds: two rooms with a door in
// the wall between them, walls without a gap, gaps too narrow or too wide,
// staggered walls and blocked openings.
#include "ekf_slam_core/mecp/doorways.h"

#include <gtest/gtest.h>

#include <limits>

namespace ekf_slam {
namespace {

// Two 4 × 3 m rooms side by side, x in [0, 4] and [4, 8], y in [0, 3]. The
// wall between them at x = 4 has a door from y = door_low to door_high. The
// outer walls come in pieces, as the extraction gives them: the top wall
// in two pieces meeting at x = 4, the bottom one with a 0.15 m break.
std::vector<Segment2> twoRooms(double door_low = 1.0, double door_high = 2.0) {
  return {
      {{0, 0}, {1.9, 0}},      {{2.05, 0}, {8, 0}},                         // bottom, with a break
      {{8, 0}, {8, 3}},        {{8, 3}, {4, 3}},         {{4, 3}, {0, 3}},  // right, top
      {{0, 3}, {0, 0}},                                                     // left
      {{4, 0}, {4, door_low}}, {{4, 3}, {4, door_high}},  // the wall with the door
  };
}

TEST(FindDoorways, TheDoorBetweenTwoRoomsIsTheOnlyOne) {
  const std::vector<Doorway> doorways = findDoorways(twoRooms(), DoorwayOptions());
  ASSERT_EQ(doorways.size(), 1u);
  const Doorway& door = doorways[0];
  EXPECT_EQ(std::min(door.wall_a, door.wall_b), 6);
  EXPECT_EQ(std::max(door.wall_a, door.wall_b), 7);
  EXPECT_NEAR(door.width, 1.0, 1e-12);
  EXPECT_LT((door.centre() - Vector2(4.0, 1.5)).norm(), 1e-12);
  // The jambs are the walls' facing ends.
  EXPECT_LT(std::min((door.end_a - Vector2(4, 1)).norm(), (door.end_b - Vector2(4, 1)).norm()),
            1e-12);
  EXPECT_LT(std::min((door.end_a - Vector2(4, 2)).norm(), (door.end_b - Vector2(4, 2)).norm()),
            1e-12);
}

TEST(FindDoorways, NoDoorInAWallWithoutAGapOrWithAGapOfTheWrongWidth) {
  const DoorwayOptions options;
  // One wall; two pieces meeting end to end; a gap of 0.3 m, 1.6 m, 2 m.
  EXPECT_TRUE(findDoorways({{{4, 0}, {4, 3}}}, options).empty());
  EXPECT_TRUE(findDoorways({{{4, 0}, {4, 1.5}}, {{4, 1.5}, {4, 3}}}, options).empty());
  EXPECT_TRUE(findDoorways({{{4, 0}, {4, 1.35}}, {{4, 1.65}, {4, 3}}}, options).empty());
  EXPECT_TRUE(findDoorways({{{4, 0}, {4, 0.7}}, {{4, 2.3}, {4, 3}}}, options).empty());
  EXPECT_TRUE(findDoorways(twoRooms(0.5, 2.5), options).empty());
  // Pieces that overlap along the line (a double wall) are no door either.
  EXPECT_TRUE(findDoorways({{{4, 0}, {4, 2}}, {{4.05, 1.5}, {4.05, 3}}}, options).empty());
  // The width limits are inclusive.
  DoorwayOptions exact;
  exact.min_width = 0.75;
  exact.max_width = 1.25;
  EXPECT_EQ(findDoorways({{{4, 0}, {4, 1}}, {{4, 2.25}, {4, 3}}}, exact).size(), 1u);
  EXPECT_EQ(findDoorways({{{4, 0}, {4, 1}}, {{4, 1.75}, {4, 3}}}, exact).size(), 1u);
}

TEST(FindDoorways, WallsMustBeParallelAndOnOneLine) {
  const DoorwayOptions options;
  // Staggered: parallel but 0.5 m apart.
  EXPECT_TRUE(findDoorways({{{4, 0}, {4, 1}}, {{4.5, 2}, {4.5, 3}}}, options).empty());
  // Turned by 20°.
  const Vector2 jamb(4, 2);
  const Vector2 turned = jamb + Vector2(std::sin(degToRad(20)), std::cos(degToRad(20)));
  EXPECT_TRUE(findDoorways({{{4, 0}, {4, 1}}, {jamb, turned}}, options).empty());
  // A few centimetres and a few degrees off is still a door; so is any
  // direction of travel along the walls.
  const Vector2 tilted = jamb + Vector2(std::sin(degToRad(3)), std::cos(degToRad(3)));
  EXPECT_EQ(
      findDoorways({{{4, 0}, {4, 1}}, {{4.04, 2}, tilted + Vector2(0.04, 0)}}, options).size(), 1u);
  EXPECT_EQ(findDoorways({{{4, 1}, {4, 0}}, {{4, 3}, {4, 2}}}, options).size(), 1u);
  EXPECT_EQ(findDoorways({{{4, 3}, {4, 2}}, {{4, 1}, {4, 0}}}, options).size(), 1u);
}

TEST(FindDoorways, AWallInTheGapClosesItAndAWallAtTheJambDoesNot) {
  const DoorwayOptions options;
  // Three pieces on one line: the outer two are 1.0 m apart, but the middle
  // piece stands in between (its gaps to them, 0.4 m, are too narrow).
  EXPECT_TRUE(
      findDoorways({{{0, 0}, {1, 0}}, {{1.4, 0}, {1.6, 0}}, {{2, 0}, {3, 0}}}, options).empty());
  // A wall across the opening.
  EXPECT_TRUE(
      findDoorways({{{0, 0}, {1, 0}}, {{2, 0}, {3, 0}}, {{1.5, -1}, {1.5, 1}}}, options).empty());
  // Walls turning away at both jambs (the door's reveal) leave it open.
  EXPECT_EQ(
      findDoorways({{{0, 0}, {1, 0}}, {{2, 0}, {3, 0}}, {{1, 0}, {1, -0.2}}, {{2, 0}, {2, -0.2}}},
                   options)
          .size(),
      1u);
}

TEST(FindDoorways, TheFreeSpaceTestIsAskedAcrossTheGap) {
  const std::vector<Segment2> walls{{{4, 0}, {4, 1}}, {{4, 2}, {4, 3}}};
  std::vector<std::pair<Vector2, Vector2>> asked;
  const auto blocked = [&asked](const Vector2& from, const Vector2& to) {
    asked.emplace_back(from, to);
    return false;
  };
  EXPECT_TRUE(findDoorways(walls, DoorwayOptions(), blocked).empty());
  ASSERT_EQ(asked.size(), 1u);
  // Perpendicular to the wall, through the gap's middle, 0.5 m each side.
  const Vector2 from = asked[0].first, to = asked[0].second;
  EXPECT_LT((0.5 * (from + to) - Vector2(4, 1.5)).norm(), 1e-12);
  EXPECT_NEAR(std::abs((to - from).x()), 1.0, 1e-12);
  EXPECT_NEAR((to - from).y(), 0.0, 1e-12);
  EXPECT_EQ(
      findDoorways(walls, DoorwayOptions(), [](const Vector2&, const Vector2&) { return true; })
          .size(),
      1u);
}

// A break in a corridor's wall with a wall 0.3 m behind it (a niche): the
// walls alone say nothing can pass, so it is no door; with the back wall
// 0.8 m away, beyond free_space_depth, it is one.
TEST(FindDoorways, AGapWithAWallJustBehindItIsNoDoorByTheWallsAlone) {
  auto walls = [](double behind) {
    return std::vector<Segment2>{
        {{0, 0}, {2, 0}}, {{3, 0}, {5, 0}}, {{1.5, -behind}, {3.5, -behind}}};
  };
  EXPECT_EQ(findDoorways(walls(0.3), DoorwayOptions()).size(), 1u);  // no test: a door
  EXPECT_TRUE(findDoorways(walls(0.3), DoorwayOptions(), crossesNoWall(walls(0.3))).empty());
  EXPECT_EQ(findDoorways(walls(0.8), DoorwayOptions(), crossesNoWall(walls(0.8))).size(), 1u);
}

TEST(FindDoorways, BadInputGivesNoDoorways) {
  const std::vector<Segment2> walls{{{4, 0}, {4, 1}}, {{4, 2}, {4, 3}}};
  DoorwayOptions options;
  options.min_width = 1.5;  // above max_width
  EXPECT_NE(options.validate().find("min_width"), std::string::npos);
  EXPECT_TRUE(findDoorways(walls, options).empty());
  options = DoorwayOptions();
  options.max_offset = -0.1;
  EXPECT_NE(options.validate().find("max_offset"), std::string::npos);
  std::vector<Segment2> with_nan = walls;
  with_nan.push_back({{std::numeric_limits<double>::quiet_NaN(), 0}, {1, 1}});
  EXPECT_TRUE(findDoorways(with_nan, DoorwayOptions()).empty());
  // A zero-length wall is skipped, not a door jamb.
  std::vector<Segment2> with_point = walls;
  with_point.push_back({{4, 1.5}, {4, 1.5}});
  EXPECT_EQ(findDoorways(with_point, DoorwayOptions()).size(), 1u);
}

TEST(RoomMap, TheDoorSeparatesTheRooms) {
  const std::vector<Segment2> walls = twoRooms();
  const std::vector<Doorway> doorways = findDoorways(walls, DoorwayOptions());
  ASSERT_EQ(doorways.size(), 1u);
  RoomMap rooms;
  ASSERT_EQ(rooms.build(walls, doorways), "");
  EXPECT_EQ(rooms.roomCount(), 3);  // the two rooms and the outside
  const int left = rooms.roomAt(Vector2(1, 1));
  const int right = rooms.roomAt(Vector2(7, 2));
  ASSERT_GE(left, 0);
  ASSERT_GE(right, 0);
  EXPECT_NE(left, right);
  // The same room everywhere inside it, up to the door from either side.
  for (const Vector2& p : {Vector2(3, 2.5), Vector2(0.3, 0.3), Vector2(3.8, 1.5)}) {
    EXPECT_EQ(rooms.roomAt(p), left) << p.transpose();
  }
  for (const Vector2& p : {Vector2(5, 1), Vector2(7.7, 2.7), Vector2(4.2, 1.5)}) {
    EXPECT_EQ(rooms.roomAt(p), right) << p.transpose();
  }
  // Close to the wall on either side: different rooms.
  EXPECT_EQ(rooms.roomAt(Vector2(3.8, 0.5)), left);
  EXPECT_EQ(rooms.roomAt(Vector2(4.2, 0.5)), right);
  // Outside the building.
  const int outside = rooms.roomAt(Vector2(-0.5, 1));
  EXPECT_GE(outside, 0);
  EXPECT_NE(outside, left);
  EXPECT_NE(outside, right);
  // The break in the bottom wall (0.15 m) is closed by the inflation.
  EXPECT_EQ(rooms.roomAt(Vector2(1.975, -0.5)), outside);
  EXPECT_EQ(rooms.roomAt(Vector2(1.975, 0.5)), left);
}

TEST(RoomMap, LandmarksOnWallsTakeTheRoomTheyAreSeenFrom) {
  const std::vector<Segment2> walls = twoRooms();
  RoomMap rooms;
  ASSERT_EQ(rooms.build(walls, findDoorways(walls, DoorwayOptions())), "");
  const int left = rooms.roomAt(Vector2(1, 1));
  const int right = rooms.roomAt(Vector2(7, 2));
  // A landmark on a wall is inside a barrier cell.
  EXPECT_EQ(rooms.roomAt(Vector2(0, 0)), -1);
  // Room corners, seen from inside.
  EXPECT_EQ(rooms.roomOf(Vector2(0, 0), Vector2(1, 1)), left);
  EXPECT_EQ(rooms.roomOf(Vector2(8, 3), Vector2(6, 2)), right);
  // A door jamb belongs to the room it is seen from.
  EXPECT_EQ(rooms.roomOf(Vector2(4, 1), Vector2(2, 1.5)), left);
  EXPECT_EQ(rooms.roomOf(Vector2(4, 1), Vector2(6, 1.5)), right);
  // A corner of the left room seen through the door from the right room
  // stays in the left room.
  EXPECT_EQ(rooms.roomOf(Vector2(0, 3), Vector2(6, 1.0)), left);
  // The outer side of the same corner, seen from outside.
  EXPECT_EQ(rooms.roomOf(Vector2(0, 0), Vector2(-1, -1)), rooms.roomAt(Vector2(-0.5, 1)));
  // A free point is its cell's room; off the map, none.
  EXPECT_EQ(rooms.roomOf(Vector2(1, 1), Vector2(2, 2)), left);
  EXPECT_EQ(rooms.roomOf(Vector2(100, 100), Vector2(101, 101)), -1);
  EXPECT_EQ(rooms.roomOf(Vector2(std::numeric_limits<double>::quiet_NaN(), 0), Vector2(1, 1)), -1);
}

TEST(RoomMap, WithoutTheDoorwayTheRoomsAreOne) {
  const std::vector<Segment2> walls = twoRooms();
  RoomMap rooms;
  ASSERT_EQ(rooms.build(walls, {}), "");
  EXPECT_EQ(rooms.roomCount(), 2);  // the building and the outside
  EXPECT_EQ(rooms.roomAt(Vector2(1, 1)), rooms.roomAt(Vector2(7, 2)));
}

TEST(RoomMap, BadInputIsRefusedWithAMessage) {
  RoomMap rooms;
  EXPECT_NE(rooms.build({}, {}), "");
  RoomMapOptions options;
  options.wall_inflation = 0.01;  // thinner than a cell
  EXPECT_NE(rooms.build(twoRooms(), {}, options).find("wall_inflation"), std::string::npos);
  options = RoomMapOptions();
  options.resolution = 0.0;
  EXPECT_NE(rooms.build(twoRooms(), {}, options).find("resolution"), std::string::npos);
  std::vector<Segment2> far = twoRooms();
  far.push_back({{1e5, 1e5}, {1e5 + 1, 1e5}});
  EXPECT_NE(rooms.build(far, {}).find("max_cells"), std::string::npos);
  EXPECT_EQ(rooms.roomCount(), 0);
  EXPECT_EQ(rooms.roomAt(Vector2(1, 1)), -1);
  std::vector<Segment2> with_nan = twoRooms();
  with_nan[2].end.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(rooms.build(with_nan, {}).find("wall 2"), std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
