// Parameters of simulator_node: read from its private namespace and
// validated (unknown keys and out-of-range values are errors naming the
// key). Defaults and units: config/simulator.yaml and docs/simulation.md.
#pragma once

#include <ros/node_handle.h>

#include <string>

namespace ekf_slam {
namespace sim {

struct SimulatorParams {
  std::string world_file;        // map_server YAML with start_pose
  std::string calibration_file;  // config/calibration.yaml
  std::string p3dx_link = "/tmp/ekf_slam_sim/p3dx";
  std::string lms200_link = "/tmp/ekf_slam_sim/lms200";
  // A second, rear LMS200 on its own pseudo-terminal: empty for none. Its
  // mount: rear_calibration_file (required with it), e.g.
  // config/calibration_rear.yaml.
  std::string rear_lms200_link;
  std::string rear_calibration_file;
  double robot_radius = 0.26;     // m, P3-DX body: 455 mm x 381 mm (plus wheels)
  double wheel_noise = 0.03;      // std of each wheel's distance error per robot_step, fraction
  double range_noise = 0.01;      // m, 1-sigma of each laser range
  int seed = 1;                   // random seed of both noise models
  double robot_step = 0.01;       // s, P3-DX integration period
  double ground_truth_rate = 50;  // Hz
  double path_spacing = 0.05;     // m between ground_truth/path poses
  std::string truth_frame = "ground_truth";
  std::string truth_child_frame = "base_link_truth";
  std::string map_frame = "map";
};

// Fills `params` from `private_node`; false with every problem in `error`.
bool loadSimulatorParams(const ros::NodeHandle& private_node, SimulatorParams* params,
                         std::string* error);

}  // namespace sim
}  // namespace ekf_slam
