// Reader for CARMEN text logs, the format in which the thesis-era datasets
// (Intel, ACES, ...) circulate. Understood lines:
//   FLASER n r1..rn  x y θ  odom_x odom_y odom_θ  ipc_timestamp host logger_timestamp
//   ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode
//               n r1..rn  m rem1..remm  laser_x laser_y laser_θ  robot_x robot_y robot_θ
//               tv rv forward_safety side_safety turn_axis  ipc_timestamp host logger_timestamp
//   ODOM x y θ tv rv accel  ipc_timestamp host logger_timestamp
// Other message types (PARAM, TRUEPOS, SYNC, ...) and comments (#) are
// skipped. A FLASER scan spans 180° from −90° in n beams (increment π/(n−1),
// as in the Freiburg logs); its odometry pose is the robot's, the laser pose
// gives the mounting (laser relative to robot).
#pragma once

#include <string>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

struct CarmenLaser {
  Scan scan;             // stamp = ipc_timestamp
  Pose2 robot_odometry;  // odom → base_link at the scan
  Pose2 laser_in_robot;  // base_link → laser
};

struct CarmenOdometry {
  double stamp = 0.0;
  Pose2 pose;
};

struct CarmenLog {
  std::vector<CarmenLaser> lasers;       // file order
  std::vector<CarmenOdometry> odometry;  // file order
  int skipped_lines = 0;                 // unknown message types
};

// Parses a whole log. Returns an empty string on success, else
// "<path>:<line>: <problem>" for the first malformed line (wrong field count,
// non-numeric value), and then `log` holds no partial result.
std::string readCarmenLog(const std::string& path, CarmenLog* log, double max_range = 80.0);

// Parses one line (without the trailing newline); for tests and streaming.
// Returns empty on success or a problem description; *kind gets the message
// type ("FLASER", "ODOM", "ROBOTLASER1", or "" for skipped lines).
std::string parseCarmenLine(const std::string& line, double max_range, std::string* kind,
                            CarmenLaser* laser, CarmenOdometry* odometry);

}  // namespace ekf_slam
