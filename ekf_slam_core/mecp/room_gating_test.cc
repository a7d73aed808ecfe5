// Room gating on two rooms joined by a door: a landmark on the far side of
// the wall is never a candidate, however close it is; a landmark seen
// through the door still is; door jambs belong to both rooms.
#include "ekf_slam_core/mecp/room_gating.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace ekf_slam {
namespace {

// Rooms A (x in [0, 4]) and B (x in [4, 8]), y in [0, 3]; the wall between
// them at x = 4 has a door from y = 1 to y = 2.
std::vector<Segment2> twoRooms() {
  return {{{0, 0}, {8, 0}}, {{8, 0}, {8, 3}}, {{8, 3}, {0, 3}},
          {{0, 3}, {0, 0}}, {{4, 0}, {4, 1}}, {{4, 3}, {4, 2}}};
}

RoomGate twoRoomGate() {
  const std::vector<Segment2> walls = twoRooms();
  std::vector<Doorway> doorways = findDoorways(walls, DoorwayOptions());
  EXPECT_EQ(doorways.size(), 1u);
  RoomMap rooms;
  EXPECT_EQ(rooms.build(walls, doorways), "");
  return RoomGate(rooms, doorways);
}

std::vector<int> sorted(std::vector<int> v) {
  std::sort(v.begin(), v.end());
  return v;
}

TEST(RoomGate, PointsTakeTheRoomTheyAreSeenFromAndJambsBoth) {
  RoomGate gate = twoRoomGate();
  const int a = gate.rooms().roomAt({2.0, 1.5}), b = gate.rooms().roomAt({6.0, 1.5});
  ASSERT_GE(a, 0);
  ASSERT_GE(b, 0);
  ASSERT_NE(a, b);
  // The two faces of the wall, each seen from its side; a face point that
  // has drifted 0.06 m across the wall's line keeps the side it was seen from.
  EXPECT_EQ(gate.roomsOf({3.95, 2.6}, {2.0, 2.6}), std::vector<int>{a});
  EXPECT_EQ(gate.roomsOf({4.05, 2.6}, {6.0, 2.6}), std::vector<int>{b});
  EXPECT_EQ(gate.roomsOf({4.01, 2.6}, {2.0, 2.6}), std::vector<int>{a});
  // A point of B seen from A through the door is in B.
  EXPECT_EQ(gate.roomsOf({5.5, 1.5}, {2.0, 1.5}), std::vector<int>{b});
  // A jamb borders both rooms, from either side.
  EXPECT_EQ(gate.roomsOf({4.0, 2.05}, {2.0, 2.0}), sorted({a, b}));
  EXPECT_EQ(gate.roomsOf({4.05, 0.95}, {6.0, 1.0}), sorted({a, b}));
  // From the doorway along the wall no free cell lies on the way: the
  // doorway's two rooms.
  EXPECT_EQ(gate.roomsOf({4.02, 0.0}, {4.0, 1.5}), sorted({a, b}));
  // Outside the map: unknown.
  EXPECT_TRUE(gate.roomsOf({40.0, 0.0}, {41.0, 1.5}).empty());

  gate.labelLandmark(0, {3.95, 2.6}, {2.0, 2.6});
  gate.labelLandmark(1, {4.05, 2.6}, {6.0, 2.6});
  gate.labelLandmark(2, {4.0, 2.05}, {2.0, 2.0});
  EXPECT_EQ(gate.landmarkRooms(0), std::vector<int>{a});
  EXPECT_EQ(gate.landmarkRooms(2), sorted({a, b}));
  EXPECT_TRUE(gate.landmarkRooms(7).empty());
  EXPECT_TRUE(gate.allows(0, {a}));
  EXPECT_FALSE(gate.allows(1, {a}));
  EXPECT_TRUE(gate.allows(2, {a}));
  EXPECT_TRUE(gate.allows(2, {b}));
  EXPECT_FALSE(gate.allows(0, {b}));
  EXPECT_TRUE(gate.allows(7, {a}));  // unlabelled: never excluded
  EXPECT_TRUE(gate.allows(1, {}));   // an observation of unknown room: no gate
}

TEST(RoomGate, ALandmarkInAnotherRoomIsNeverACandidate) {
  RoomGate gate = twoRoomGate();
  // The robot in A, 1 m from the wall; its map holds B's face of the wall
  // (id 0, loosely known), a post in A (id 1) and a post in B (id 2).
  const Pose2 robot(3.0, 2.6, 0.0);
  FilterOptions options;
  options.tentative_max_age = 0;
  EkfSlam filter(options, robot, Matrix3::Identity() * 1e-4);
  ASSERT_EQ(filter.addLandmark(0, {4.1, 2.6}, Matrix2::Identity() * 0.04), FilterStatus::kOk);
  ASSERT_EQ(filter.addLandmark(1, {1.0, 1.0}, Matrix2::Identity() * 0.01), FilterStatus::kOk);
  ASSERT_EQ(filter.addLandmark(2, {5.5, 1.5}, Matrix2::Identity() * 0.01), FilterStatus::kOk);
  gate.labelLandmark(0, {4.1, 2.6}, {6.0, 2.6});
  gate.labelLandmark(1, {1.0, 1.0}, {2.0, 2.0});
  gate.labelLandmark(2, {5.5, 1.5}, {6.0, 2.0});

  // Readings of A's face of the wall, 0.2 m from landmark 0, of the post,
  // and of landmark 2 in B, seen through the door.
  std::vector<PointObservation> scan(3);
  for (PointObservation& obs : scan) obs.covariance = Matrix2::Identity() * 1e-4;
  ASSERT_TRUE(predictPointObservation(robot, options.laser_pose, {3.9, 2.6}, &scan[0].z));
  ASSERT_TRUE(predictPointObservation(robot, options.laser_pose, {1.0, 1.0}, &scan[1].z));
  ASSERT_TRUE(predictPointObservation(robot, options.laser_pose, {5.5, 1.5}, &scan[2].z));

  // Without gating the wall's far face is the match: the trap is real.
  const AssociationOptions association;
  const AssociationResult open = associate(filter, scan, association);
  ASSERT_EQ(open.observations[0].decision, AssociationDecision::kMatched);
  ASSERT_EQ(open.observations[0].landmark_id, 0);

  std::vector<std::vector<int>> rooms;
  const AssociationResult gated = associateInRooms(filter, scan, association, gate, &rooms);
  ASSERT_EQ(gated.observations.size(), 3u);
  EXPECT_EQ(rooms[0], gate.landmarkRooms(1));
  EXPECT_EQ(rooms[2], gate.landmarkRooms(2));
  for (const ObservationAssociation& o : gated.observations) {
    EXPECT_NE(o.landmark_id, 0);
    for (const AssociationCandidate& c : o.candidates) EXPECT_NE(c.landmark_id, 0);
  }
  EXPECT_EQ(gated.observations[0].decision, AssociationDecision::kNewLandmark);
  EXPECT_EQ(gated.observations[1].decision, AssociationDecision::kMatched);
  EXPECT_EQ(gated.observations[1].landmark_id, 1);
  EXPECT_EQ(gated.observations[2].decision, AssociationDecision::kMatched);
  EXPECT_EQ(gated.observations[2].landmark_id, 2);
  EXPECT_EQ(gated.gate, open.gate);
  // The filter itself is untouched.
  EXPECT_EQ(filter.landmarkCount(), 3);
}

TEST(RoomGateOptions, ANegativeRadiusIsRefusedByName) {
  EXPECT_EQ(RoomGateOptions().validate(), "");
  RoomGateOptions options;
  options.doorway_radius = -0.1;
  EXPECT_NE(options.validate().find("doorway_radius"), std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
