#include "ekf_slam_core/sim/polygon_world.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ekf_slam {
namespace sim {
namespace {

TEST(PolygonWorld, RaysHitTheNearestWallOfARoom) {
  PolygonWorld room;
  room.addPolygon({{0, 0}, {5, 0}, {5, 3.5}, {0, 3.5}});
  const Vector2 origin(1.0, 1.0);
  EXPECT_NEAR(room.castRay(origin, 0.0, 10.0), 4.0, 1e-12);
  EXPECT_NEAR(room.castRay(origin, kPi / 2, 10.0), 2.5, 1e-12);
  EXPECT_NEAR(room.castRay(origin, kPi, 10.0), 1.0, 1e-12);
  EXPECT_NEAR(room.castRay(origin, -kPi / 2, 10.0), 1.0, 1e-12);
  // Diagonal into the corner (5, 5) direction hits the top wall at y = 3.5.
  EXPECT_NEAR(room.castRay(origin, kPi / 4, 10.0), 2.5 * std::sqrt(2.0), 1e-12);
  EXPECT_EQ(room.vertices().size(), 4u);
}

TEST(PolygonWorld, BeyondMaxRangeOrEmptyWorldIsNoReturn) {
  PolygonWorld room;
  room.addPolygon({{0, 0}, {5, 0}, {5, 3.5}, {0, 3.5}});
  EXPECT_TRUE(std::isinf(room.castRay({1, 1}, 0.0, 3.9)));
  PolygonWorld empty;
  EXPECT_TRUE(std::isinf(empty.castRay({0, 0}, 0.3, 100.0)));
}

TEST(PolygonWorld, BoxOccludesTheWallBehindIt) {
  PolygonWorld world;
  world.addPolygon({{-5, -5}, {5, -5}, {5, 5}, {-5, 5}});
  world.addBox({2, 0}, 1.0, 1.0, 0.0);
  EXPECT_NEAR(world.castRay({0, 0}, 0.0, 20.0), 1.5, 1e-12);
  // A rotated box: 45° square of half-diagonal sqrt(0.5) centred at (0, 2).
  world.addBox({0, 2}, 1.0, 1.0, kPi / 4);
  EXPECT_NEAR(world.castRay({0, 0}, kPi / 2, 20.0), 2.0 - std::sqrt(0.5), 1e-12);
}

TEST(PolygonWorld, SimulatedSweepFollowsSensorPoseAndNoise) {
  PolygonWorld room;
  room.addPolygon({{0, 0}, {5, 0}, {5, 3.5}, {0, 3.5}});
  SweepGeometry sweep;                    // 181 beams over ±90°
  const Pose2 sensor(1.0, 1.0, kPi / 2);  // looking along +y
  const std::vector<double> clean = simulateRanges(room, sensor, sweep);
  ASSERT_EQ(clean.size(), 181u);
  EXPECT_NEAR(clean[90], 2.5, 1e-12);   // straight ahead: top wall
  EXPECT_NEAR(clean[0], 4.0, 1e-12);    // rightmost beam (−90°): +x wall
  EXPECT_NEAR(clean[180], 1.0, 1e-12);  // leftmost beam (+90°): −x wall

  std::mt19937 rng(7);
  const std::vector<double> noisy = simulateRanges(room, sensor, sweep, 0.01, &rng);
  double sum_sq = 0.0;
  for (size_t i = 0; i < clean.size(); ++i) sum_sq += std::pow(noisy[i] - clean[i], 2);
  const double rms = std::sqrt(sum_sq / clean.size());
  EXPECT_GT(rms, 0.007);
  EXPECT_LT(rms, 0.013);
}

}  // namespace
}  // namespace sim
}  // namespace ekf_slam
