// A simulated drive for calibration tests and tools: the robot follows
// (v, w) segments in a polygon world; each 0.1 s step gives a scan ray-cast
// from the true laser pose and the odometry, whose increments carry a
// relative wheel error. No ROS.
#pragma once

#include <cstdint>
#include <vector>

#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace sim {

struct DriveSegment {
  double v = 0.0;        // m/s
  double w = 0.0;        // rad/s
  double seconds = 0.0;  // duration
};

struct DriveOptions {
  Pose2 start;                // robot pose in the world at the start
  Pose2 laser;                // base_link → laser, the true mount
  double period = 0.1;        // s between scans
  double wheel_noise = 0.01;  // relative 1-sigma error of each increment's x, y and turn
  double range_sigma = 0.01;  // m
  uint32_t seed = 1;
};

struct SimulatedDrive {
  std::vector<Scan> scans;      // stamped 0.1, 0.2, … s
  std::vector<Pose2> odometry;  // odom → base_link at each scan
  std::vector<Pose2> truth;     // robot pose in the world at each scan
};

SimulatedDrive simulateDrive(const RayCaster& world, const std::vector<DriveSegment>& segments,
                             const DriveOptions& options);

// A 12 m × 8 m room centred on the origin with four cartons: structure in
// every direction for the scan matcher.
PolygonWorld roomWithCartons();

// Straights, arcs both ways and turns on the spot, 68 s (12.5 m, 1350°
// of turns) from kMixedDriveStart in roomWithCartons(), the robot's centre
// never nearer than 0.79 m to a wall or a carton.
constexpr double kMixedDriveStartX = 0.0, kMixedDriveStartY = -1.0, kMixedDriveStartYaw = 0.0;
std::vector<DriveSegment> mixedDrive();

}  // namespace sim
}  // namespace ekf_slam
