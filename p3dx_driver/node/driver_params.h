// Parameters of p3dx_driver_node: read from the node's private namespace,
// validated (unknown keys and out-of-range values are errors that name the
// key). Defaults and units: docs/p3dx_driver.md and config/p3dx_driver.yaml.
#pragma once

#include <string>

#include <ros/node_handle.h>

#include "p3dx_driver/protocol/robot_link.h"

namespace p3dx {

struct DriverParams {
  LinkOptions link;
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  bool publish_tf = true;
  std::string sonar_frame_prefix = "sonar_";  // frames sonar_0 .. sonar_15
  // Odometry covariance grows with the distance and angle driven.
  double position_variance_per_metre = 1e-4;  // m² per m travelled
  double yaw_variance_per_radian = 1e-3;      // rad² per rad turned
  double yaw_variance_per_metre = 1e-4;       // rad² per m travelled
  double linear_velocity_variance = 1e-3;     // (m/s)²
  double angular_velocity_variance = 3e-3;    // (rad/s)²
  double battery_warn_voltage = 11.5;         // V
  double battery_error_voltage = 11.0;        // V
};

// Fills `params` from `private_node`. Returns false with `error` naming the
// offending key.
bool loadDriverParams(const ros::NodeHandle& private_node, DriverParams* params,
                      std::string* error);

}  // namespace p3dx
