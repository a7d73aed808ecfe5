#include "ekf_slam_ros/slam_node/slam_node_params.h"

#include <xmlrpcpp/XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

#include "ekf_slam_core/geometry/angle.h"
#include "ros_params/param_fields.h"
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

namespace {

// Every parameter of `params` from the private namespace of `node` (its
// visitFields), then its rules; unknown keys are errors.
template <class Params>
bool loadParams(const ros::NodeHandle& node, Params* params, std::string* error) {
  PrivateParams read(node);
  read.allow("slam");  // the SLAM configuration (loadNodeSlamConfig)
  PrivateParamFields fields(read);
  params->visitFields(fields);
  for (const auto& [key, why] : params->problems()) read.fail(key, why);
  read.rejectUnknown();
  *error = read.errors();
  return read.ok();
}

void requireText(const char* key, const std::string& value, ParamProblems* problems) {
  if (value.empty()) problems->emplace_back(key, "is required and must not be empty");
}

}  // namespace

ParamProblems SlamNodeParams::problems() const {
  ParamProblems out;
  requireText("map_frame", map_frame, &out);
  requireText("odom_frame", odom_frame, &out);
  requireText("base_frame", base_frame, &out);
  requireText("scan_topic", scan_topic, &out);
  requireText("input", input, &out);
  requireText("features_topic", features_topic, &out);
  if (merged_angle_increment > 0.0 && merged_angle_increment < 1e-4) {
    out.emplace_back("merged_angle_increment",
                     "must be 0 (the scan's own increment) or in [0.0001, pi/4] rad, got " +
                         std::to_string(merged_angle_increment));
  }
  if (!rear_scan_topic.empty()) {
    if (input != "scan") {
      out.emplace_back(
          "rear_scan_topic",
          "needs input 'scan' (the rear scan is merged into the raw scans), not '" + input + "'");
    }
    if (rear_scan_topic == scan_topic) {
      out.emplace_back("rear_scan_topic", "must differ from scan_topic (" + scan_topic + ")");
    }
  }
  if (!initial_map.empty() && !initial_state.empty()) {
    out.emplace_back("initial_state", "give initial_map or initial_state, not both");
  }
  if (map_frame == odom_frame) out.emplace_back("map_frame", "must differ from odom_frame");
  if (odom_frame == base_frame) out.emplace_back("base_frame", "must differ from odom_frame");
  return out;
}

ParamProblems FeatureNodeParams::problems() const {
  ParamProblems out;
  requireText("scan_topic", scan_topic, &out);
  return out;
}

bool loadSlamNodeParams(const ros::NodeHandle& node, SlamNodeParams* params, std::string* error) {
  return loadParams(node, params, error);
}

bool loadFeatureNodeParams(const ros::NodeHandle& node, FeatureNodeParams* params,
                           std::string* error) {
  return loadParams(node, params, error);
}

}  // namespace ekf_slam
