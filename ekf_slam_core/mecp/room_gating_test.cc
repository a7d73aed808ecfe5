// Room gating on two rooms joined by a door: a landmark on the far side of
// the wall is never a candidate, however close it is; the doorway sees
// both rooms; door jambs belong to both.
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

TEST(RoomGate, TheRobotIsInItsRoomAndInBothAtTheDoor) {
  RoomGate gate = twoRoomGate();
  const int a = gate.rooms().roomAt({2.0, 1.5}), b = gate.rooms().roomAt({6.0, 1.5});
  ASSERT_GE(a, 0);
  ASSERT_GE(b, 0);
  ASSERT_NE(a, b);
  EXPECT_EQ(gate.moveRobot({2.0, 2.5}), std::vector<int>{a});
  EXPECT_EQ(sorted(gate.moveRobot({4.0, 1.5})), sorted({a, b}));
  EXPECT_EQ(sorted(gate.moveRobot({3.5, 1.4})), sorted({a, b}));
  EXPECT_EQ(gate.moveRobot({6.0, 0.5}), std::vector<int>{b});
  // On the wall itself (a drifting estimate) the robot stays where it was.
  EXPECT_EQ(gate.moveRobot({4.0, 2.7}), std::vector<int>{b});
}

TEST(RoomGate, LandmarksTakeTheRoomTheyWereSeenFromAndJambsBoth) {
  RoomGate gate = twoRoomGate();
  const int a = gate.rooms().roomAt({2.0, 1.5}), b = gate.rooms().roomAt({6.0, 1.5});
  gate.labelLandmark(0, {3.95, 2.6}, {2.0, 2.6});  // on A's face of the wall
  gate.labelLandmark(1, {4.05, 2.6}, {6.0, 2.6});  // on B's face
  gate.labelLandmark(2, {4.0, 2.05}, {2.0, 2.0});  // a jamb
  EXPECT_EQ(gate.landmarkRooms(0), std::vector<int>{a});
  EXPECT_EQ(gate.landmarkRooms(1), std::vector<int>{b});
  EXPECT_EQ(sorted(gate.landmarkRooms(2)), sorted({a, b}));
  EXPECT_TRUE(gate.landmarkRooms(7).empty());

  gate.moveRobot({2.0, 2.6});
  EXPECT_TRUE(gate.allows(0));
  EXPECT_FALSE(gate.allows(1));
  EXPECT_TRUE(gate.allows(2));
  EXPECT_TRUE(gate.allows(7));  // unlabelled: never excluded
  gate.moveRobot({6.0, 2.6});
  EXPECT_FALSE(gate.allows(0));
  EXPECT_TRUE(gate.allows(1));
  EXPECT_TRUE(gate.allows(2));
}

TEST(RoomGate, ALandmarkInAnotherRoomIsNeverACandidate) {
  RoomGate gate = twoRoomGate();
  // The robot in A, 1 m from the wall; its map holds B's face of the wall
  // (id 0, loosely known) and a post in A (id 1).
  const Pose2 robot(3.0, 2.6, 0.0);
  FilterOptions options;
  options.tentative_max_age = 0;
  EkfSlam filter(options, robot, Matrix3::Identity() * 1e-4);
  ASSERT_EQ(filter.addLandmark(0, {4.1, 2.6}, Matrix2::Identity() * 0.04), FilterStatus::kOk);
  ASSERT_EQ(filter.addLandmark(1, {1.0, 1.0}, Matrix2::Identity() * 0.01), FilterStatus::kOk);
  gate.labelLandmark(0, {4.1, 2.6}, {6.0, 2.6});
  gate.labelLandmark(1, {1.0, 1.0}, {2.0, 2.0});
  gate.moveRobot(robot.translation());

  // Readings of A's face of the wall, 0.2 m from landmark 0, and of the post.
  std::vector<PointObservation> scan(2);
  for (PointObservation& obs : scan) obs.covariance = Matrix2::Identity() * 1e-4;
  ASSERT_TRUE(predictPointObservation(robot, options.laser_pose, {3.9, 2.6}, &scan[0].z));
  ASSERT_TRUE(predictPointObservation(robot, options.laser_pose, {1.0, 1.0}, &scan[1].z));

  // Without gating the wall's far face is the match: the trap is real.
  const AssociationOptions association;
  const AssociationResult open = associate(filter, scan, association);
  ASSERT_EQ(open.observations[0].decision, AssociationDecision::kMatched);
  ASSERT_EQ(open.observations[0].landmark_id, 0);

  const AssociationResult gated = associateInRooms(filter, scan, association, gate);
  ASSERT_EQ(gated.observations.size(), 2u);
  for (const ObservationAssociation& o : gated.observations) {
    EXPECT_NE(o.landmark_id, 0);
    for (const AssociationCandidate& c : o.candidates) EXPECT_NE(c.landmark_id, 0);
  }
  EXPECT_EQ(gated.observations[0].decision, AssociationDecision::kNewLandmark);
  EXPECT_EQ(gated.observations[1].decision, AssociationDecision::kMatched);
  EXPECT_EQ(gated.observations[1].landmark_id, 1);
  // The filter itself is untouched.
  EXPECT_EQ(filter.landmarkCount(), 2);
}

}  // namespace
}  // namespace ekf_slam
