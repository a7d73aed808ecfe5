#include "ekf_slam_core/sim/grid_world.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <random>

#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace sim {
namespace {

const std::string kTmp = "/tmp/grid_world_test_" + std::to_string(::getpid());

TEST(GridWorld, RaysStopAtTheFirstOccupiedCellInEveryDirection) {
  // 10 × 10 cells of 0.1 m, walls on the border, origin at (−0.5, −0.5).
  std::vector<bool> occupied(100, false);
  for (int i = 0; i < 10; ++i) {
    occupied[i] = occupied[90 + i] = occupied[i * 10] = occupied[i * 10 + 9] = true;
  }
  const GridWorld world(10, 10, 0.1, Vector2(-0.5, -0.5), occupied);
  const Vector2 centre(0.0, 0.0);
  // The inner faces of the border cells are 0.4 m from the centre.
  EXPECT_NEAR(world.castRay(centre, 0.0, 5.0), 0.4, 1e-9);
  EXPECT_NEAR(world.castRay(centre, kPi / 2, 5.0), 0.4, 1e-9);
  EXPECT_NEAR(world.castRay(centre, kPi, 5.0), 0.4, 1e-9);
  EXPECT_NEAR(world.castRay(centre, -kPi / 2, 5.0), 0.4, 1e-9);
  EXPECT_NEAR(world.castRay(centre, kPi / 4, 5.0), 0.4 * std::sqrt(2.0), 1e-9);
  EXPECT_TRUE(std::isinf(world.castRay(centre, 0.0, 0.3))) << "beyond max_range";
  EXPECT_DOUBLE_EQ(world.castRay(Vector2(0.45, 0.0), 0.0, 5.0), 0.0) << "inside a wall";
  EXPECT_TRUE(world.occupiedAt(Vector2(0.45, 0.0)));
  EXPECT_FALSE(world.occupiedAt(Vector2(0.0, 0.0)));
}

// Writes `world` as a map_server PGM + YAML: every cell a wall passes
// through is black, the rest white.
void rasterize(const PolygonWorld& world, double resolution, const std::string& base) {
  const Vector2 origin(-1.0, -1.0);
  const int width = 80, height = 60;
  std::vector<unsigned char> pixels(width * height, 254);
  for (const Segment& s : world.segments()) {
    const int samples = static_cast<int>((s.b - s.a).norm() / (resolution / 8)) + 1;
    for (int k = 0; k <= samples; ++k) {
      const Vector2 p = s.a + (s.b - s.a) * (static_cast<double>(k) / samples);
      const int ix = static_cast<int>(std::floor((p.x() - origin.x()) / resolution));
      const int iy = static_cast<int>(std::floor((p.y() - origin.y()) / resolution));
      if (ix >= 0 && iy >= 0 && ix < width && iy < height)
        pixels[(height - 1 - iy) * width + ix] = 0;
    }
  }
  std::ofstream pgm(base + ".pgm", std::ios::binary);
  pgm << "P5\n" << width << " " << height << "\n255\n";
  pgm.write(reinterpret_cast<const char*>(pixels.data()), pixels.size());
  const std::string name = base.substr(base.find_last_of('/') + 1);
  std::ofstream(base + ".yaml") << "image: " << name << ".pgm\nresolution: " << resolution
                                << "\norigin: [-1.0, -1.0, 0.0]\nnegate: 0\n"
                                   "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
}

double distanceToWalls(const PolygonWorld& world, const Vector2& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& s : world.segments()) {
    const Vector2 e = s.b - s.a;
    const double t = std::clamp((p - s.a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (s.a + t * e - p).norm());
  }
  return best;
}

TEST(GridWorld, ARasterisedRoomMatchesItsPolygonsWithinACell) {
  PolygonWorld room;
  room.addPolygon({{0, 0}, {5, 0}, {5, 3.5}, {0, 3.5}});
  room.addBox({3.5, 1.2}, 0.5, 0.35, 0.4);  // a rotated carton
  const double resolution = 0.1;
  rasterize(room, resolution, kTmp + "_room");
  GridWorld world;
  ASSERT_EQ(GridWorld::load(kTmp + "_room.yaml", &world), "");
  EXPECT_EQ(world.width(), 80);
  EXPECT_EQ(world.height(), 60);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (const Vector2& from : {Vector2(1.5, 1.5), Vector2(4.2, 2.9), Vector2(0.6, 0.3)}) {
    for (int i = 0; i < 200; ++i) {
      const double a = angle(rng);
      const double expected = room.castRay(from, a, 8.0);
      const double got = world.castRay(from, a, 8.0);
      ASSERT_TRUE(std::isfinite(got)) << "angle " << a;
      // Never through a wall, and the hit lies in a wall's cell: within one
      // cell diagonal of the true geometry (along the ray it can be farther
      // at grazing incidence, where the rasterised wall is a staircase).
      EXPECT_LE(got, expected + 1e-9) << "angle " << a;
      const Vector2 hit = from + got * Vector2(std::cos(a), std::sin(a));
      EXPECT_LE(distanceToWalls(room, hit), resolution * std::sqrt(2.0) + 1e-9) << "angle " << a;
    }
  }
  ::unlink((kTmp + "_room.yaml").c_str());
  ::unlink((kTmp + "_room.pgm").c_str());
}

// Every shipped world loads, its start pose is free, and it is closed: a
// robot cannot see out of it.
TEST(GridWorld, ShippedWorldsLoadAndAreClosed) {
  const std::string dir = std::string(EKF_SLAM_SOURCE_DIR) + "/config/worlds/";
  int worlds = 0;
  for (const char* name : {"carton_layout", "office"}) {
    GridWorld world;
    ASSERT_EQ(GridWorld::load(dir + name + ".yaml", &world), "") << name;
    ASSERT_TRUE(world.hasStartPose()) << name;
    const Pose2 start = world.startPose();
    EXPECT_FALSE(world.occupiedAt(start.translation())) << name;
    for (int i = 0; i < 360; ++i) {
      const double range = world.castRay(start.translation(), degToRad(i), 50.0);
      EXPECT_TRUE(std::isfinite(range)) << name << " open towards " << i << " deg";
      EXPECT_GT(range, 0.2) << name << ": start pose too close to an obstacle";
    }
    ++worlds;
  }
  EXPECT_EQ(worlds, 2);
}

TEST(GridWorld, BadFilesAreNamed) {
  GridWorld world;
  EXPECT_NE(GridWorld::load("/nonexistent.yaml", &world).find("cannot open"), std::string::npos);
  {
    std::ofstream(kTmp + "_bad.yaml")
        << "image: missing.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  }
  EXPECT_NE(GridWorld::load(kTmp + "_bad.yaml", &world).find("missing.pgm: cannot open"),
            std::string::npos);
  { std::ofstream(kTmp + "_bad.yaml") << "image: x.pgm\nresolution: 0\norigin: [0, 0, 0]\n"; }
  EXPECT_NE(GridWorld::load(kTmp + "_bad.yaml", &world).find("resolution"), std::string::npos);
  {
    std::ofstream(kTmp + "_bad.yaml")
        << "image: " << kTmp << "_bad.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n";
    std::ofstream(kTmp + "_bad.pgm") << "P5\n4 4\n255\n\x01\x02";
  }
  EXPECT_NE(GridWorld::load(kTmp + "_bad.yaml", &world).find("truncated"), std::string::npos);
  // An ASCII PGM works too.
  { std::ofstream(kTmp + "_bad.pgm") << "P2\n# comment\n2 2\n255\n0 255\n255 255\n"; }
  ASSERT_EQ(GridWorld::load(kTmp + "_bad.yaml", &world), "");
  EXPECT_TRUE(world.occupied(0, 1)) << "top-left pixel is row 1 (top) of a 2-row map";
  EXPECT_FALSE(world.occupied(0, 0));
  ::unlink((kTmp + "_bad.yaml").c_str());
  ::unlink((kTmp + "_bad.pgm").c_str());
}

}  // namespace
}  // namespace sim
}  // namespace ekf_slam
