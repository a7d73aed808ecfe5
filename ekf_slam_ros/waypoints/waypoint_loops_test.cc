// The shipped waypoint files: they load, and each loop is collision-free in
// its world for the simulated robot, both along the straight segments
// between waypoints and along the path the pure pursuit really drives.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ekf_slam_core/sim/grid_world.h"
#include "ekf_slam_ros/simulator/footprint.h"
#include "ekf_slam_ros/waypoints/pure_pursuit.h"
#include "ekf_slam_ros/waypoints/waypoint_file.h"

namespace ekf_slam {
namespace waypoints {
namespace {

const std::string kSource = EKF_SLAM_SOURCE_DIR;
// The simulator's robot_radius (config/simulator.yaml).
constexpr double kRobotRadius = 0.26;
// Room left for pursuit corner cutting and odometry drift when the loop is
// followed in the odom frame.
constexpr double kSegmentMargin = 0.15;
constexpr double kDrivenMargin = 0.10;

std::vector<std::string> shippedFiles() {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(kSource + "/config/waypoints")) {
    if (entry.path().extension() == ".yaml") files.push_back(entry.path().string());
  }
  return files;
}

struct Loop {
  WaypointFile file;
  sim::GridWorld world;
};

void loadLoop(const std::string& path, Loop* loop) {
  ASSERT_EQ(loadWaypointFile(path, &loop->file), "");
  ASSERT_FALSE(loop->file.world.empty()) << path << ": names no world to check against";
  const std::string world = kSource + "/config/worlds/" + loop->file.world + ".yaml";
  ASSERT_EQ(sim::GridWorld::load(world, &loop->world), "");
  ASSERT_TRUE(loop->world.hasStartPose());
}

TEST(WaypointLoopsTest, BothShippedLoopsExist) {
  const std::vector<std::string> files = shippedFiles();
  EXPECT_GE(files.size(), 2u);
  for (const char* name : {"office_loop.yaml", "carton_loop.yaml"}) {
    EXPECT_TRUE(std::filesystem::exists(kSource + "/config/waypoints/" + name)) << name;
  }
}

TEST(WaypointLoopsTest, SegmentsKeepTheRobotClearOfWalls) {
  for (const std::string& path : shippedFiles()) {
    SCOPED_TRACE(path);
    Loop loop;
    loadLoop(path, &loop);
    // The robot starts at the map origin; waypoints are map coordinates.
    std::vector<Vector2> points{Vector2::Zero()};
    const std::vector<Vector2> lap = expandLaps(loop.file.waypoints, 1, loop.file.closed);
    points.insert(points.end(), lap.begin(), lap.end());
    const Pose2 start = loop.world.startPose();
    for (size_t i = 0; i + 1 < points.size(); ++i) {
      const double length = (points[i + 1] - points[i]).norm();
      const int samples = std::max(1, static_cast<int>(length / 0.01));
      double tightest = 1e9;
      Vector2 where;
      for (int k = 0; k <= samples; ++k) {
        const Vector2 in_map = points[i] + (points[i + 1] - points[i]) * (double(k) / samples);
        const Vector2 in_world = transformFrom(start, in_map);
        const double room = sim::clearance(loop.world, in_world, 2.0);
        if (room < tightest) tightest = room, where = in_map;
      }
      EXPECT_GE(tightest, kRobotRadius + kSegmentMargin)
          << "segment " << i << " (" << points[i].transpose() << ") -> ("
          << points[i + 1].transpose() << ") passes " << tightest << " m from a wall at map ("
          << where.transpose() << ")";
    }
  }
}

TEST(WaypointLoopsTest, PursuitDrivesTwoLapsWithoutTouchingAWall) {
  for (const std::string& path : shippedFiles()) {
    SCOPED_TRACE(path);
    Loop loop;
    loadLoop(path, &loop);
    std::vector<Vector2> points{Vector2::Zero()};
    const std::vector<Vector2> laps = expandLaps(loop.file.waypoints, 2, loop.file.closed);
    points.insert(points.end(), laps.begin(), laps.end());
    const PursuitOptions options;  // waypoint_driver's defaults
    PurePursuit pursuit(points, options);
    const Pose2 start = loop.world.startPose();
    Pose2 pose;  // in the map frame: starts at its origin
    const double dt = 0.05;
    double tightest = 1e9;
    int step = 0;
    for (; step < 40000 && !pursuit.done(); ++step) {
      const VelocityCommand command = pursuit.update(pose, dt);
      const double distance = command.linear * dt, turn = command.angular * dt;
      pose =
          compose(pose, Pose2(distance * std::cos(turn / 2), distance * std::sin(turn / 2), turn));
      tightest = std::min(
          tightest, sim::clearance(loop.world, transformFrom(start, pose.translation()), 2.0));
    }
    EXPECT_TRUE(pursuit.done()) << "not finished after " << step * dt << " s";
    EXPECT_GE(tightest, kRobotRadius + kDrivenMargin);
    std::printf("%s: 2 laps in %.0f s (simulated), tightest clearance %.2f m\n",
                loop.file.world.c_str(), step * dt, tightest);
  }
}

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(WaypointFileTest, ReadsAValidFile) {
  WaypointFile file;
  ASSERT_EQ(loadWaypointFile(writeTemp("wp_ok.yaml",
                                       "world: office\nclosed: false\n"
                                       "waypoints:\n  - [1, 2]\n  - [3.5, -4]\n"),
                             &file),
            "");
  EXPECT_EQ(file.world, "office");
  EXPECT_FALSE(file.closed);
  ASSERT_EQ(file.waypoints.size(), 2u);
  EXPECT_EQ(file.waypoints[1], Vector2(3.5, -4.0));
}

TEST(WaypointFileTest, ErrorsNameTheFileKeyAndIndex) {
  WaypointFile file;
  std::string error = loadWaypointFile("/nonexistent/loop.yaml", &file);
  EXPECT_NE(error.find("/nonexistent/loop.yaml"), std::string::npos) << error;

  error =
      loadWaypointFile(writeTemp("wp_typo.yaml", "clossed: true\nwaypoints:\n  - [1, 2]\n"), &file);
  EXPECT_NE(error.find("clossed"), std::string::npos) << error;

  error = loadWaypointFile(
      writeTemp("wp_bad.yaml", "waypoints:\n  - [1, 2]\n  - [1, 2, 3]\n  - [a, 1]\n"), &file);
  EXPECT_NE(error.find("waypoints[1]"), std::string::npos) << error;
  EXPECT_NE(error.find("waypoints[2]"), std::string::npos) << error;

  error = loadWaypointFile(writeTemp("wp_empty.yaml", "waypoints: []\n"), &file);
  EXPECT_NE(error.find("non-empty"), std::string::npos) << error;

  error =
      loadWaypointFile(writeTemp("wp_closed.yaml", "closed: maybe\nwaypoints: [[0, 1]]\n"), &file);
  EXPECT_NE(error.find("closed"), std::string::npos) << error;
}

}  // namespace
}  // namespace waypoints
}  // namespace ekf_slam
