// The node parameters' one declaration (SlamNodeParams::visitFields)
// against the file that documents them: config/ekf_slam_node.yaml lists
// every parameter with its default, each admitted by its bounds.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <memory>
#include <string>
#include <vector>

#include "ekf_slam_ros/offline/yaml_binder.h"
#include "ekf_slam_ros/slam_node/slam_node_params.h"

namespace ekf_slam {
namespace {

// The names a visitFields() declares, in order.
struct FieldNames {
  std::vector<std::string> names;
  void number(const char* name, double&, const Bounds&) { names.emplace_back(name); }
  void integer(const char* name, int&, const Bounds&) { names.emplace_back(name); }
  void flag(const char* name, bool&) { names.emplace_back(name); }
  void text(const char* name, std::string&, std::initializer_list<const char*> = {}) {
    names.emplace_back(name);
  }
};

// Every field's value after binding `node` (defaults where it is silent);
// the binding's errors in `errors`.
YamlBinder::Values bindYaml(const YAML::Node& node, SlamNodeParams* params,
                            std::vector<std::string>* errors) {
  auto messages = std::make_shared<std::vector<std::string>>();
  auto values = std::make_shared<YamlBinder::Values>();
  YamlBinder binder(node, "", messages, values);
  params->visitFields(binder);
  binder.rejectUnknownKeys();
  *errors = *messages;
  return *values;
}

TEST(SlamNodeParams, TheNodeYamlListsEveryParameterWithItsDefault) {
  const YAML::Node file =
      YAML::LoadFile(std::string(EKF_SLAM_SOURCE_DIR) + "/config/ekf_slam_node.yaml");
  SlamNodeParams from_file, defaults;
  std::vector<std::string> errors;
  const YamlBinder::Values file_values = bindYaml(file, &from_file, &errors);
  for (const std::string& error : errors) ADD_FAILURE() << error;
  const YamlBinder::Values default_values =
      bindYaml(YAML::Node(YAML::NodeType::Map), &defaults, &errors);
  EXPECT_TRUE(errors.empty());
  EXPECT_EQ(file_values, default_values) << "the file's values differ from the defaults";

  FieldNames fields;
  defaults.visitFields(fields);
  for (const std::string& name : fields.names) {
    // config_file is the launch file's to set (slam.launch, arg config).
    if (name == "config_file") continue;
    EXPECT_TRUE(file[name].IsDefined()) << name << " is not in config/ekf_slam_node.yaml";
  }
}

TEST(SlamNodeParams, TheDefaultsKeepTheirOwnRules) {
  EXPECT_EQ(checkFields(SlamNodeParams()), "");
  EXPECT_TRUE(SlamNodeParams().problems().empty());
  EXPECT_TRUE(FeatureNodeParams().problems().empty());
}

TEST(SlamNodeParams, TheRulesBetweenFieldsNameTheirKey) {
  SlamNodeParams params;
  params.odom_frame = params.map_frame;
  params.scan_topic = "";
  params.rear_scan_topic = "scan_rear";
  params.input = "features";
  const ParamProblems problems = params.problems();
  std::vector<std::string> keys;
  for (const auto& [key, why] : problems) keys.push_back(key);
  EXPECT_EQ(keys, (std::vector<std::string>{"scan_topic", "rear_scan_topic", "map_frame"}));
  // A YAML value beyond the declared bounds is refused with its rule.
  SlamNodeParams bound;
  std::vector<std::string> errors;
  YAML::Node node(YAML::NodeType::Map);
  node["tf_timeout"] = 100.0;
  bindYaml(node, &bound, &errors);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("tf_timeout: must be in [0, 60] (s), got 100"), std::string::npos)
      << errors[0];
}

}  // namespace
}  // namespace ekf_slam
