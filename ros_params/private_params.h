// Reads a node's private parameters into option structs with the checks the
// project asks of every node: each value range-checked, unknown keys
// (typos) rejected, and every message naming the full parameter, e.g.
//   "/simulator/robot_radius: must be in [0.05, 1], got 3".
// Keys that are not set keep the struct's default. Used by simulator_node,
// waypoint_driver, ekf_slam_node, feature_node, p3dx_driver_node and lms200_node.
#pragma once

#include <ros/node_handle.h>

#include <set>
#include <string>
#include <vector>

namespace ekf_slam {

class PrivateParams {
 public:
  explicit PrivateParams(const ros::NodeHandle& private_node) : node_(private_node) {}

  void number(const std::string& key, double* value, double low, double high);
  void integer(const std::string& key, int* value, int low, int high);
  void flag(const std::string& key, bool* value);
  // `required`: an empty or missing value is an error.
  void text(const std::string& key, std::string* value, bool required = true);

  // A parameter another part of the node reads itself (diagnostic_updater's
  // ~diagnostic_period): not an unknown key, and not checked here.
  void allow(const std::string& key) { known_.insert(key); }
  // Records an error about `key` found by the caller's own checks.
  void fail(const std::string& key, const std::string& why);
  // Every private parameter nobody asked for is an error (a typo must not
  // silently keep a default).
  void rejectUnknown();

  bool ok() const { return errors_.empty(); }
  // All problems, one per line.
  std::string errors() const;

 private:
  ros::NodeHandle node_;
  std::set<std::string> known_;
  std::vector<std::string> errors_;
};

}  // namespace ekf_slam
