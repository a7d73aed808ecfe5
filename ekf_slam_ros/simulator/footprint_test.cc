#include "ekf_slam_ros/simulator/footprint.h"

#include <gtest/gtest.h>

#include <vector>

namespace ekf_slam {
namespace sim {
namespace {

// 20 x 20 cells of 0.1 m, origin (0, 0), one occupied cell: [1.0, 1.1) x [1.0, 1.1).
GridWorld oneCellWorld() {
  std::vector<bool> occupied(400, false);
  occupied[10 * 20 + 10] = true;
  return GridWorld(20, 20, 0.1, Vector2(0.0, 0.0), occupied);
}

TEST(FootprintTest, ClearanceIsTheDistanceToTheNearestCellEdge) {
  const GridWorld world = oneCellWorld();
  // Left of the cell, level with it: the distance to its left edge.
  EXPECT_NEAR(clearance(world, Vector2(0.7, 1.05), 1.0), 0.3, 1e-12);
  // Diagonal from its corner (1.1, 1.1).
  EXPECT_NEAR(clearance(world, Vector2(1.4, 1.5), 1.0), 0.5, 1e-12);
  // Inside the cell.
  EXPECT_NEAR(clearance(world, Vector2(1.05, 1.05), 1.0), 0.0, 1e-12);
  // Nothing within the search distance.
  EXPECT_NEAR(clearance(world, Vector2(0.5, 0.5), 0.2), 0.2, 1e-12);
}

TEST(FootprintTest, DiscTouchingTheCellCollides) {
  const GridWorld world = oneCellWorld();
  EXPECT_TRUE(footprintFree(world, Vector2(0.7, 1.05), 0.29));
  EXPECT_FALSE(footprintFree(world, Vector2(0.7, 1.05), 0.31));
  EXPECT_FALSE(footprintFree(world, Vector2(1.05, 1.05), 0.01));
}

TEST(FootprintTest, OutsideTheImageCountsAsAWall) {
  const GridWorld world = oneCellWorld();
  EXPECT_TRUE(footprintFree(world, Vector2(0.5, 0.5), 0.3));
  EXPECT_FALSE(footprintFree(world, Vector2(0.2, 0.5), 0.3));   // crosses x = 0
  EXPECT_FALSE(footprintFree(world, Vector2(1.9, 0.5), 0.15));  // crosses x = 2
  EXPECT_FALSE(footprintFree(world, Vector2(-1.0, -1.0), 0.1));
}

TEST(FootprintTest, ShippedWorldsStartPosesAreFreeForTheRobot) {
  for (const char* name :
       {"office", "office_turned", "carton_layout", "rooms", "calibration_room"}) {
    GridWorld world;
    const std::string path = std::string(EKF_SLAM_SOURCE_DIR) + "/config/worlds/" + name + ".yaml";
    ASSERT_EQ(GridWorld::load(path, &world), "");
    ASSERT_TRUE(world.hasStartPose()) << name;
    // The simulator refuses a start within robot_radius (0.26 m) of a wall.
    EXPECT_GT(clearance(world, world.startPose().translation(), 2.0), 0.5) << name;
  }
}

}  // namespace
}  // namespace sim
}  // namespace ekf_slam
