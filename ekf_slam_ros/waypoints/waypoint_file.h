// A waypoint file (config/waypoints/*.yaml). No ROS.
//
//   world: office          # the world of config/worlds/ the loop is laid out in
//   closed: true           # a loop: each lap ends back at the first waypoint
//   waypoints:             # x, y in m, in the driver's global_frame
//     - [2.0, 0.25]
//     - [17.6, 0.25]
//
// Coordinates are relative to the robot's start pose: that is the origin of
// the SLAM map frame and of the odometry frame, so one file serves both
// (docs/simulation.md).
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"

namespace ekf_slam {
namespace waypoints {

struct WaypointFile {
  std::string world;  // informational: which world the loop was checked against
  bool closed = true;
  std::vector<Vector2> waypoints;
};

// Returns "" on success, else messages naming the file, the key and, for a
// bad waypoint, its index. Unknown keys are errors; at least one waypoint.
std::string loadWaypointFile(const std::string& path, WaypointFile* file);

}  // namespace waypoints
}  // namespace ekf_slam
