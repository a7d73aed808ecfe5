#include "ekf_slam_ros/slam_node/slam_node_params.h"

#include <cmath>
#include <set>
#include <sstream>
#include <vector>

namespace ekf_slam {
namespace {

// Reads keys one by one, remembering the first problem and every key asked
// for, so that typos (unknown keys) can be reported at the end.
class ParamReader {
 public:
  ParamReader(const ros::NodeHandle& node, const std::string& owner, std::string* error)
      : node_(node), owner_(owner), error_(error) {}

  void number(const std::string& key, double* value, double low, double high) {
    known_.insert(key);
    if (node_.hasParam(key) && !node_.getParam(key, *value)) {
      int integer = 0;
      if (node_.getParam(key, integer)) {
        *value = integer;
      } else {
        fail(key, "must be a number");
        return;
      }
    }
    if (!std::isfinite(*value) || *value < low || *value > high) {
      std::ostringstream text;
      text << "is " << *value << ", allowed [" << low << ", " << high << "]";
      fail(key, text.str());
    }
  }
  void integer(const std::string& key, int* value, int low, int high) {
    known_.insert(key);
    if (node_.hasParam(key) && !node_.getParam(key, *value)) {
      fail(key, "must be an integer");
      return;
    }
    if (*value < low || *value > high) {
      fail(key, "is " + std::to_string(*value) + ", allowed [" + std::to_string(low) + ", " +
                    std::to_string(high) + "]");
    }
  }
  void flag(const std::string& key, bool* value) {
    known_.insert(key);
    if (node_.hasParam(key) && !node_.getParam(key, *value)) fail(key, "must be true or false");
  }
  void text(const std::string& key, std::string* value, bool may_be_empty) {
    known_.insert(key);
    if (node_.hasParam(key) && !node_.getParam(key, *value)) fail(key, "must be a string");
    if (!may_be_empty && value->empty()) fail(key, "must not be empty");
  }
  void fail(const std::string& key, const std::string& why) {
    if (error_->empty()) *error_ = "parameter " + node_.resolveName(key) + " " + why;
  }
  void rejectUnknown() {
    std::vector<std::string> names;
    node_.getParamNames(names);
    const std::string prefix = node_.getNamespace() + "/";
    for (const std::string& name : names) {
      if (name.rfind(prefix, 0) != 0) continue;
      const std::string key = name.substr(prefix.size());
      const std::string top = key.substr(0, key.find('/'));
      if (!known_.count(top)) fail(top, "is not a parameter of " + owner_ + " (typo?)");
    }
  }

 private:
  const ros::NodeHandle& node_;
  std::string owner_;
  std::string* error_;
  std::set<std::string> known_;
};

}  // namespace

bool loadSlamNodeParams(const ros::NodeHandle& node, SlamNodeParams* p, std::string* error) {
  error->clear();
  ParamReader read(node, "ekf_slam_node", error);
  read.text("config_file", &p->config_file, true);
  read.text("map_frame", &p->map_frame, false);
  read.text("odom_frame", &p->odom_frame, false);
  read.text("base_frame", &p->base_frame, false);
  read.text("scan_topic", &p->scan_topic, false);
  read.number("tf_timeout", &p->tf_timeout, 0.0, 60.0);
  read.integer("scan_queue_size", &p->scan_queue_size, 1, 10000);
  read.number("transform_tolerance", &p->transform_tolerance, 0.0, 10.0);
  read.number("tf_publish_rate", &p->tf_publish_rate, 0.1, 1000.0);
  read.integer("min_valid_readings", &p->min_valid_readings, 2, 100000);
  read.number("laser_pose_tolerance", &p->laser_pose_tolerance, 0.0, 10.0);
  read.integer("nis_window", &p->nis_window, 1, 1000000);
  read.number("ellipse_probability", &p->ellipse_probability, 0.01, 0.9999);
  read.flag("localize_only", &p->localize_only);
  read.text("initial_map", &p->initial_map, true);
  read.number("diagnostic_period", &p->diagnostic_period, 0.01, 60.0);
  read.integer("path_max_poses", &p->path_max_poses, 0, 100000000);
  if (p->map_frame == p->odom_frame) read.fail("map_frame", "must differ from odom_frame");
  if (p->odom_frame == p->base_frame) read.fail("base_frame", "must differ from odom_frame");
  read.rejectUnknown();
  return error->empty();
}

bool loadFeatureNodeParams(const ros::NodeHandle& node, FeatureNodeParams* p, std::string* error) {
  error->clear();
  ParamReader read(node, "feature_node", error);
  read.text("config_file", &p->config_file, true);
  read.text("scan_topic", &p->scan_topic, false);
  read.rejectUnknown();
  return error->empty();
}

}  // namespace ekf_slam
