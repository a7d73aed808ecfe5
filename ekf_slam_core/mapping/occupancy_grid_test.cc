#include "ekf_slam_core/mapping/occupancy_grid.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>

#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

Scan scanFrom(const sim::PolygonWorld& world, const Pose2& laser) {
  sim::SweepGeometry sweep;
  sweep.count = 361;
  sweep.angle_increment = kPi / 360;
  sweep.max_range = 8.0;
  return sim::simulateScan(world, laser, sweep, 0.0, nullptr, 0.05);
}

// Largest occupancy within one cell of (x, y): a wall lying exactly on a
// cell boundary may be recorded in the cell on either side.
double nearWall(const OccupancyGrid& grid, double x, double y) {
  const double r = grid.resolution();
  double best = 0.0;
  for (double dx : {-r, 0.0, r}) {
    for (double dy : {-r, 0.0, r}) best = std::max(best, grid.probability(x + dx, y + dy));
  }
  return best;
}

class RoomGrid : public ::testing::Test {
 protected:
  void SetUp() override {
    room_.addPolygon({{0, 0}, {5, 0}, {5, 3.5}, {0, 3.5}});
    for (const Pose2& pose : {Pose2(1, 1, 0), Pose2(4, 2.5, kPi), Pose2(2.5, 1.7, kPi / 2),
                              Pose2(2.5, 1.7, -kPi / 2)}) {
      grid_.insertScan(pose, scanFrom(room_, pose));
    }
  }
  sim::PolygonWorld room_;
  OccupancyGrid grid_;
};

TEST_F(RoomGrid, WallsAreOccupiedInsideIsFreeOutsideUnknown) {
  for (const Vector2& wall :
       {Vector2(2.5, 0.0), Vector2(5.0, 1.7), Vector2(2.5, 3.5), Vector2(0.0, 1.7)}) {
    EXPECT_GT(nearWall(grid_, wall.x(), wall.y()), 0.65) << wall.transpose();
  }
  for (const Vector2& inside : {Vector2(2.5, 1.7), Vector2(1.0, 2.5), Vector2(4.0, 1.0)}) {
    EXPECT_LT(grid_.probability(inside.x(), inside.y()), 0.2) << inside.transpose();
    EXPECT_TRUE(grid_.isKnown(inside.x(), inside.y()));
  }
  EXPECT_FALSE(grid_.isKnown(7.0, 7.0));
  EXPECT_DOUBLE_EQ(grid_.probability(7.0, 7.0), 0.5);
}

TEST_F(RoomGrid, SavesMapServerFiles) {
  const std::string base = "/tmp/occupancy_grid_test_" + std::to_string(::getpid());
  ASSERT_EQ(grid_.save(base), "");
  std::ifstream pgm(base + ".pgm", std::ios::binary);
  std::string magic, comment;
  int w = 0, h = 0, maxval = 0;
  pgm >> magic;
  pgm.ignore(1);
  std::getline(pgm, comment);
  pgm >> w >> h >> maxval;
  pgm.ignore(1);
  EXPECT_EQ(magic, "P5");
  EXPECT_EQ(w, grid_.width());
  EXPECT_EQ(h, grid_.height());
  EXPECT_EQ(maxval, 255);
  std::vector<char> pixels(static_cast<size_t>(w) * h);
  pgm.read(pixels.data(), pixels.size());
  EXPECT_EQ(pgm.gcount(), static_cast<std::streamsize>(pixels.size()));
  // The room's centre pixel (image rows run from the top) is free (white).
  const int ix = static_cast<int>((2.5 - grid_.origin().x()) / grid_.resolution());
  const int iy = static_cast<int>((1.7 - grid_.origin().y()) / grid_.resolution());
  EXPECT_GT(static_cast<uint8_t>(pixels[static_cast<size_t>(h - 1 - iy) * w + ix]), 200);

  std::ifstream yaml(base + ".yaml");
  std::stringstream text;
  text << yaml.rdbuf();
  EXPECT_NE(text.str().find("image: occupancy_grid_test_"), std::string::npos);
  EXPECT_NE(text.str().find("resolution: 0.05"), std::string::npos);
  EXPECT_NE(text.str().find("origin: ["), std::string::npos);
  ::unlink((base + ".pgm").c_str());
  ::unlink((base + ".yaml").c_str());
  EXPECT_NE(grid_.save("/nonexistent/dir/map"), "");
}

TEST(OccupancyGrid, NoReturnBeamsAndBadValuesNeverMarkHits) {
  Scan scan;
  scan.angle_min = -0.1;
  scan.angle_increment = 0.1;
  scan.range_min = 0.1;
  scan.range_max = 80.0;
  scan.ranges = {81.83, std::numeric_limits<double>::infinity(), std::nan("")};
  OccupancyGrid grid;
  grid.insertScan(Pose2(), scan);
  EXPECT_EQ(grid.width(), 0) << "nothing inserted by default";
  OccupancyGridOptions clear;
  clear.no_return_free_range = 3.0;
  OccupancyGrid cleared(clear);
  cleared.insertScan(Pose2(), scan);
  EXPECT_LT(cleared.probability(2.0, 0.0), 0.5);
  EXPECT_FALSE(cleared.isKnown(3.5, 0.0));
  for (int8_t v : cleared.occupancyValues()) EXPECT_LE(v, 50);
}

TEST(OccupancyGrid, BeamsWithoutAFiniteBearingAreLeftOut) {
  Scan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 1e308;  // beam 0 at 0 rad, beam 2 at +inf
  scan.range_min = 0.1;
  scan.range_max = 80.0;
  scan.ranges = {2.0, 2.0, 2.0};
  OccupancyGrid grid;
  grid.insertScan(Pose2(), scan);
  EXPECT_GT(grid.probability(2.0, 0.0), 0.5) << "the beam with a finite bearing is a hit";
  EXPECT_EQ(grid.raysBeyondLimit(), 0) << "an unusable bearing is not a ray beyond the limit";
}

TEST(OccupancyGrid, GrowingKeepsEarlierCells) {
  sim::PolygonWorld wall;
  wall.addSegment({3, -5}, {3, 5});
  OccupancyGrid grid;
  grid.insertScan(Pose2(), scanFrom(wall, Pose2()));
  const double before = grid.probability(2.99, 0.0);
  EXPECT_GT(nearWall(grid, 3.0, 0.0), 0.65);
  sim::PolygonWorld far;
  far.addSegment({-30, -5}, {-30, 5});
  grid.insertScan(Pose2(-25, 0, kPi), scanFrom(far, Pose2(-25, 0, kPi)));
  EXPECT_DOUBLE_EQ(grid.probability(2.99, 0.0), before);
  EXPECT_GT(nearWall(grid, -30.0, 0.0), 0.65);
  EXPECT_EQ(OccupancyGridOptions().validate(), "");
  OccupancyGridOptions bad;
  bad.hit_probability = 0.3;
  EXPECT_NE(bad.validate().find("hit_probability"), std::string::npos);
}

}  // namespace
}  // namespace ekf_slam

namespace ekf_slam {
namespace {

// Beams given by their end points (a key scan's readings): free before the
// end, occupied at it, unknown beyond; readings past max_insert_range left out.
// Covered to the extent extendToScan gives, a grid holds every ray of the
// scans without growing, no wider than the rays reach (a cell of rounding
// each side), and knows the room as a grid that grew ray by ray does.
TEST(OccupancyGrid, CoveredToTheRaysExtentItHoldsThemAllWithoutGrowing) {
  sim::PolygonWorld room;
  room.addPolygon({{0, 0}, {5, 0}, {5, 3.5}, {0, 3.5}});
  const Pose2 poses[] = {Pose2(1, 1, 0), Pose2(4, 2.5, kPi), Pose2(2.5, 1.7, kPi / 2)};
  OccupancyGrid covered, grown;
  Vector2 low = Vector2::Constant(std::numeric_limits<double>::infinity());
  Vector2 high = -low;
  for (const Pose2& pose : poses) covered.extendToScan(pose, scanFrom(room, pose), &low, &high);
  // The walls the rays end on, and nothing beyond them.
  EXPECT_NEAR(low.x(), 0.0, 0.06);
  EXPECT_NEAR(low.y(), 0.0, 0.06);
  EXPECT_NEAR(high.x(), 5.0, 0.06);
  EXPECT_NEAR(high.y(), 3.5, 0.06);
  ASSERT_TRUE(covered.cover(low, high));
  const int width = covered.width(), height = covered.height();
  EXPECT_LE(width * covered.resolution(), high.x() - low.x() + 2 * covered.resolution());
  EXPECT_LE(height * covered.resolution(), high.y() - low.y() + 2 * covered.resolution());
  for (const Pose2& pose : poses) {
    covered.insertScan(pose, scanFrom(room, pose));
    grown.insertScan(pose, scanFrom(room, pose));
  }
  EXPECT_EQ(covered.width(), width);
  EXPECT_EQ(covered.height(), height);
  EXPECT_EQ(covered.raysBeyondLimit(), 0);
  // The same room on another lattice (the grown grid's starts at its first
  // ray): as many cells known, to the cells a lattice shift moves.
  const auto known = [](const OccupancyGrid& grid) {
    int count = 0;
    for (int8_t v : grid.trinaryValues()) count += v >= 0;
    return count;
  };
  EXPECT_NEAR(known(covered), known(grown), 0.02 * known(grown));
  EXPECT_GT(nearWall(covered, 2.5, 0.0), 0.65);
  EXPECT_GT(nearWall(covered, 5.0, 1.7), 0.65);
}

TEST(OccupancyGrid, HitsGivenAsEndPointsMarkFreeSpaceAndTheEnd) {
  OccupancyGridOptions options;
  options.max_insert_range = 5.0;
  OccupancyGrid grid(options);
  grid.insertHits(Vector2(1.0, 1.0), {Vector2(3.0, 1.0), Vector2(1.0, 9.0)});
  EXPECT_GT(grid.probability(3.01, 1.01), 0.5);
  EXPECT_LT(grid.probability(2.0, 1.01), 0.5);
  EXPECT_FALSE(grid.isKnown(3.6, 1.01));
  EXPECT_FALSE(grid.isKnown(1.01, 4.0));  // the 8 m reading was not inserted
}

// A cell whose hits and misses cancel to a log-odds of exactly 0 is known
// (p = 0.5, grey 127 in the file), not unknown (205): with a hit of
// log-odds +l and a miss of −l, one of each sums to 0. Unknown cells have
// no flag of their own, so this tells them apart.
TEST(OccupancyGrid, ACellWhoseEvidenceCancelsIsKnownNotUnknown) {
  OccupancyGridOptions options;
  options.hit_probability = 0.6;
  options.miss_probability = 0.4;
  OccupancyGrid grid(options);
  const Vector2 origin(0.0, 0.0);
  grid.insertHits(origin, {Vector2(1.0, 0.01)});  // a hit at 1 m ...
  grid.insertHits(origin, {Vector2(2.0, 0.01)});  // ... then a beam through it
  EXPECT_EQ(grid.probability(1.0, 0.01), 0.5);
  EXPECT_TRUE(grid.isKnown(1.0, 0.01));
  EXPECT_FALSE(grid.isKnown(1.0, 1.0));
  int known_at_half = 0;
  for (int8_t v : grid.occupancyValues()) known_at_half += v == 50;
  EXPECT_EQ(known_at_half, 1);
  const std::string base = ::testing::TempDir() + "cancelling_cell";
  ASSERT_EQ(grid.save(base), "");
  std::ifstream pgm(base + ".pgm", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(pgm)), std::istreambuf_iterator<char>());
  EXPECT_EQ(std::count(bytes.begin(), bytes.end(), static_cast<char>(127)), 1);
}

}  // namespace
}  // namespace ekf_slam

namespace ekf_slam {
namespace {

// Published maps hold only -1, 0 and 100, decided at map_server's thresholds.
TEST(OccupancyGrid, TrinaryValuesAreUnknownFreeOrOccupied) {
  OccupancyGrid grid;
  const Vector2 origin(0.0, 0.0);
  for (int k = 0; k < 5; ++k) grid.insertHits(origin, {Vector2(2.0, 0.01)});
  grid.insertHits(origin, {Vector2(0.01, 1.0)});  // one sighting: p = 0.7 at its end
  const std::vector<int8_t> values = grid.trinaryValues();
  const std::vector<int8_t> probabilities = grid.occupancyValues();
  int occupied = 0, free_cells = 0, unknown = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    ASSERT_TRUE(values[i] == -1 || values[i] == 0 || values[i] == 100) << int(values[i]);
    occupied += values[i] == 100;
    free_cells += values[i] == 0;
    unknown += values[i] == -1;
    if (probabilities[i] > 65) EXPECT_EQ(values[i], 100);
    if (probabilities[i] >= 0 && probabilities[i] < 19) EXPECT_EQ(values[i], 0);
  }
  EXPECT_EQ(occupied, 2);     // both ends (0.7 after one hit is above 0.65)
  EXPECT_GT(free_cells, 30);  // the 2 m beam, passed 5 times (4 misses make a cell free)
  EXPECT_GT(unknown, free_cells);
}

}  // namespace
}  // namespace ekf_slam
