#include "ekf_slam_ros/slam_node/slam_node_params.h"

#include <xmlrpcpp/XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

#include "ekf_slam_core/geometry/angle.h"
#include "ros_params/private_params.h"

namespace ekf_slam {
namespace {

// A parameter-server value as the YAML node the configuration loader reads.
// Doubles keep every digit (yaml-cpp writes max_digits10), so a file loaded
// with rosparam gives the loader the numbers the file holds.
YAML::Node toYaml(XmlRpc::XmlRpcValue& value) {
  switch (value.getType()) {
    case XmlRpc::XmlRpcValue::TypeStruct: {
      YAML::Node map(YAML::NodeType::Map);
      for (auto& [key, member] : value) map[key] = toYaml(member);
      return map;
    }
    case XmlRpc::XmlRpcValue::TypeArray: {
      YAML::Node list(YAML::NodeType::Sequence);
      for (int i = 0; i < value.size(); ++i) list.push_back(toYaml(value[i]));
      return list;
    }
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return YAML::Node(static_cast<bool>(value));
    case XmlRpc::XmlRpcValue::TypeInt:
      return YAML::Node(static_cast<int>(value));
    case XmlRpc::XmlRpcValue::TypeDouble:
      return YAML::Node(static_cast<double>(value));
    case XmlRpc::XmlRpcValue::TypeString:
      return YAML::Node(static_cast<std::string>(value));
    default:
      return YAML::Node();  // the loader names the key whose value is missing
  }
}

}  // namespace

bool loadNodeSlamConfig(const ros::NodeHandle& private_node, const std::string& config_file,
                        SlamConfig* config, std::string* source, std::string* error) {
  XmlRpc::XmlRpcValue tree;
  if (private_node.getParam("slam", tree)) {
    *source = private_node.getNamespace() + "/slam" +
              (config_file.empty() ? std::string() : " (loaded from " + config_file + ")");
    if (tree.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
      *error = "slam: must be a dictionary of the configuration's sections";
      return false;
    }
    *error = loadSlamConfig(toYaml(tree), config);
    return error->empty();
  }
  if (config_file.empty()) {
    *source = "the built-in defaults";
    *error = "";
    return true;
  }
  *source = config_file;
  *error = loadSlamConfigFile(config_file, config);
  return error->empty();
}

bool loadSlamNodeParams(const ros::NodeHandle& node, SlamNodeParams* p, std::string* error) {
  PrivateParams read(node);
  read.text("config_file", &p->config_file, /*required=*/false);
  read.allow("slam");  // the SLAM configuration (loadNodeSlamConfig)
  read.text("map_frame", &p->map_frame, /*required=*/true);
  read.text("odom_frame", &p->odom_frame, /*required=*/true);
  read.text("base_frame", &p->base_frame, /*required=*/true);
  read.text("scan_topic", &p->scan_topic, /*required=*/true);
  read.text("input", &p->input, /*required=*/true);
  read.text("features_topic", &p->features_topic, /*required=*/true);
  if (p->input != "scan" && p->input != "features") {
    read.fail("input", "must be 'scan' or 'features', not '" + p->input + "'");
  }
  read.number("tf_timeout", &p->tf_timeout, 0.0, 60.0);
  read.integer("scan_queue_size", &p->scan_queue_size, 1, 10000);
  read.number("tf_cache_time", &p->tf_cache_time, 1.0, 3600.0);
  read.number("transform_tolerance", &p->transform_tolerance, 0.0, 10.0);
  read.number("tf_publish_rate", &p->tf_publish_rate, 0.1, 1000.0);
  read.integer("min_valid_readings", &p->min_valid_readings, 2, 100000);
  read.number("laser_pose_tolerance", &p->laser_pose_tolerance, 0.0, 10.0);
  read.integer("nis_window", &p->nis_window, 1, 1000000);
  read.number("ellipse_probability", &p->ellipse_probability, 0.01, 0.9999);
  read.flag("localize_only", &p->localize_only);
  read.flag("start_paused", &p->start_paused);
  read.text("initial_map", &p->initial_map, /*required=*/false);
  read.number("diagnostic_period", &p->diagnostic_period, 0.01, 60.0);
  read.integer("path_max_poses", &p->path_max_poses, 0, 100000000);
  read.integer("history_max_scans", &p->history_max_scans, 0, 100000000);
  read.number("map_update_interval", &p->map_update_interval, 0.0, 3600.0);
  read.number("max_future_stamp", &p->max_future_stamp, 0.0, 1e6);
  read.text("rear_scan_topic", &p->rear_scan_topic, /*required=*/false);
  read.number("rear_scan_tolerance", &p->rear_scan_tolerance, 0.0, 10.0);
  read.number("merged_angle_increment", &p->merged_angle_increment, 0.0, kPi / 4.0);
  if (p->merged_angle_increment > 0.0 && p->merged_angle_increment < 1e-4) {
    read.fail("merged_angle_increment",
              "must be 0 (the scan's own increment) or in [0.0001, pi/4] rad, got " +
                  std::to_string(p->merged_angle_increment));
  }
  if (!p->rear_scan_topic.empty()) {
    if (p->input != "scan") {
      read.fail("rear_scan_topic",
                "needs input 'scan' (the rear scan is merged into the raw scans), not '" +
                    p->input + "'");
    }
    if (p->rear_scan_topic == p->scan_topic) {
      read.fail("rear_scan_topic", "must differ from scan_topic (" + p->scan_topic + ")");
    }
  }
  if (p->map_frame == p->odom_frame) read.fail("map_frame", "must differ from odom_frame");
  if (p->odom_frame == p->base_frame) read.fail("base_frame", "must differ from odom_frame");
  read.rejectUnknown();
  *error = read.errors();
  return read.ok();
}

bool loadFeatureNodeParams(const ros::NodeHandle& node, FeatureNodeParams* p, std::string* error) {
  PrivateParams read(node);
  read.text("config_file", &p->config_file, /*required=*/false);
  read.allow("slam");  // the SLAM configuration (loadNodeSlamConfig)
  read.text("scan_topic", &p->scan_topic, /*required=*/true);
  read.rejectUnknown();
  *error = read.errors();
  return read.ok();
}

}  // namespace ekf_slam
