#include "p3dx_driver/node/driver_params.h"

#include <cmath>
#include <set>
#include <sstream>

#include "serial_io/serial_port.h"

namespace p3dx {
namespace {

class Loader {
 public:
  Loader(const ros::NodeHandle& node, std::string* error) : node_(node), error_(error) {}

  // Reads `key` if set; rejects values outside [low, high].
  void number(const std::string& key, double* value, double low, double high) {
    known_.insert(key);
    if (!node_.getParam(key, *value) && node_.hasParam(key)) {
      int integer = 0;
      if (node_.getParam(key, integer)) {
        *value = integer;
      } else {
        fail(key, "must be a number");
      }
    }
    if (!std::isfinite(*value) || *value < low || *value > high) {
      std::ostringstream text;
      text << "is " << *value << ", allowed [" << low << ", " << high << "]";
      fail(key, text.str());
    }
  }
  void integer(const std::string& key, int* value, int low, int high) {
    double number_value = *value;
    this->number(key, &number_value, low, high);
    *value = static_cast<int>(number_value);
  }
  void flag(const std::string& key, bool* value) {
    known_.insert(key);
    if (!node_.getParam(key, *value) && node_.hasParam(key)) fail(key, "must be true or false");
  }
  void text(const std::string& key, std::string* value) {
    known_.insert(key);
    if (!node_.getParam(key, *value) && node_.hasParam(key)) fail(key, "must be a string");
    if (value->empty()) fail(key, "must not be empty");
  }
  void fail(const std::string& key, const std::string& why) {
    if (error_->empty()) *error_ = "parameter " + node_.resolveName(key) + " " + why;
  }
  // Flags private parameters this node does not know (typos).
  void rejectUnknown() {
    std::vector<std::string> names;
    node_.getParamNames(names);
    const std::string prefix = node_.getNamespace() + "/";
    for (const std::string& name : names) {
      if (name.rfind(prefix, 0) != 0) continue;
      const std::string key = name.substr(prefix.size());
      if (key.find('/') != std::string::npos) continue;  // nested: not ours
      if (!known_.count(key)) fail(key, "is not a parameter of p3dx_driver_node (typo?)");
    }
  }

 private:
  const ros::NodeHandle& node_;
  std::string* error_;
  std::set<std::string> known_;
};

}  // namespace

bool loadDriverParams(const ros::NodeHandle& node, DriverParams* params, std::string* error) {
  error->clear();
  Loader load(node, error);
  LinkOptions& link = params->link;
  load.text("port", &link.port);
  load.integer("baud", &link.baud, 1200, 4000000);
  if (error->empty() && !serial_io::isStandardBaud(link.baud)) {
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
  load.rejectUnknown();
  return error->empty();
}

}  // namespace p3dx
