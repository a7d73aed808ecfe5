#include "ekf_slam_ros/simulator/simulator_params.h"

#include "ros_params/private_params.h"

namespace ekf_slam {
namespace sim {

bool loadSimulatorParams(const ros::NodeHandle& private_node, SimulatorParams* params,
                         std::string* error) {
  PrivateParams load(private_node);
  load.text("world_file", &params->world_file);
  load.text("calibration_file", &params->calibration_file);
  load.text("p3dx_link", &params->p3dx_link);
  load.text("lms200_link", &params->lms200_link);
  load.text("rear_lms200_link", &params->rear_lms200_link, /*required=*/false);
  load.text("rear_calibration_file", &params->rear_calibration_file, /*required=*/false);
  load.number("robot_radius", &params->robot_radius, 0.05, 1.0);
  load.number("wheel_noise", &params->wheel_noise, 0.0, 0.5);
  load.number("range_noise", &params->range_noise, 0.0, 0.5);
  load.integer("seed", &params->seed, 0, 1000000000);
  load.number("robot_step", &params->robot_step, 0.001, 0.1);
  load.number("ground_truth_rate", &params->ground_truth_rate, 1.0, 500.0);
  load.number("path_spacing", &params->path_spacing, 0.0, 10.0);
  load.text("truth_frame", &params->truth_frame);
  load.text("truth_child_frame", &params->truth_child_frame);
  load.text("map_frame", &params->map_frame);
  if (params->p3dx_link == params->lms200_link) {
    load.fail("lms200_link", "must differ from p3dx_link (" + params->p3dx_link + ")");
  }
  if (!params->rear_lms200_link.empty()) {
    if (params->rear_lms200_link == params->p3dx_link ||
        params->rear_lms200_link == params->lms200_link) {
      load.fail("rear_lms200_link", "must differ from p3dx_link (" + params->p3dx_link +
                                        ") and lms200_link (" + params->lms200_link + ")");
    }
    if (params->rear_calibration_file.empty()) {
      load.fail("rear_calibration_file",
                "is required with rear_lms200_link (where the rear laser sits, e.g. "
                "config/calibration_rear.yaml)");
    }
  }
  load.rejectUnknown();
  *error = load.errors();
  return load.ok();
}

}  // namespace sim
}  // namespace ekf_slam
