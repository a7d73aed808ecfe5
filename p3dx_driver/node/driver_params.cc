#include "p3dx_driver/node/driver_params.h"

#include "ros_params/private_params.h"
#include "serial_io/serial_port.h"

namespace p3dx {

bool loadDriverParams(const ros::NodeHandle& node, DriverParams* params, std::string* error) {
  ekf_slam::PrivateParams load(node);
  LinkOptions& link = params->link;
  load.text("port", &link.port);
  load.integer("baud", &link.baud, 1200, 4000000);
  if (load.ok() && !serial_io::isStandardBaud(link.baud)) {
    load.fail("baud", "is " + std::to_string(link.baud) + ", not a standard serial rate");
  }
  load.flag("probe_baud", &link.probe_baud);
  load.number("reconnect_min_delay", &link.reconnect_min_delay, 0.01, 60.0);
  load.number("reconnect_max_delay", &link.reconnect_max_delay, 0.01, 300.0);
  load.flag("motors_enabled_at_start", &link.motors_enabled_at_start);
  load.flag("sonar_enabled", &link.sonar_enabled);
  load.number("max_linear_velocity", &link.max_linear_velocity, 0.0, 2.2);
  load.number("max_angular_velocity", &link.max_angular_velocity, 0.0, 8.73);
  load.number("linear_acceleration", &link.linear_acceleration, 0.001, 10.0);
  load.number("linear_deceleration", &link.linear_deceleration, 0.001, 10.0);
  load.number("angular_acceleration", &link.angular_acceleration, 0.001, 50.0);
  load.number("cmd_vel_timeout", &link.cmd_vel_timeout, 0.0, 60.0);
  load.number("pulse_period", &link.pulse_period, 0.05, 1.9);
  load.number("distance_conversion", &link.distance_conversion, 0.0, 10.0);
  load.text("odom_frame", &params->odom_frame);
  load.text("base_frame", &params->base_frame);
  load.flag("publish_tf", &params->publish_tf);
  load.text("sonar_frame_prefix", &params->sonar_frame_prefix);
  load.number("position_variance_per_metre", &params->position_variance_per_metre, 0.0, 1.0);
  load.number("yaw_variance_per_radian", &params->yaw_variance_per_radian, 0.0, 1.0);
  load.number("yaw_variance_per_metre", &params->yaw_variance_per_metre, 0.0, 1.0);
  load.number("linear_velocity_variance", &params->linear_velocity_variance, 0.0, 10.0);
  load.number("angular_velocity_variance", &params->angular_velocity_variance, 0.0, 10.0);
  load.number("battery_warn_voltage", &params->battery_warn_voltage, 0.0, 100.0);
  load.number("battery_error_voltage", &params->battery_error_voltage, 0.0, 100.0);
  if (link.reconnect_max_delay < link.reconnect_min_delay) {
    load.fail("reconnect_max_delay", "must not be smaller than reconnect_min_delay");
  }
  if (params->battery_error_voltage > params->battery_warn_voltage) {
    load.fail("battery_error_voltage", "must not exceed battery_warn_voltage");
  }
  if (params->odom_frame == params->base_frame) {
    load.fail("base_frame", "must differ from odom_frame");
  }
  load.allow("diagnostic_period");  // diagnostic_updater's own
  load.rejectUnknown();
  *error = load.errors();
  return load.ok();
}

}  // namespace p3dx
