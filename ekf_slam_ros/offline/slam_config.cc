#include "ekf_slam_ros/offline/slam_config.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <vector>

#include "ekf_slam_ros/offline/yaml_binder.h"

namespace ekf_slam {
namespace {

// The laser mount, when the file gives it (else it comes from tf).
void bindLaserPose(YamlBinder& b, FilterOptions* f, bool* laser_pose_given) {
  std::vector<double> laser;
  if (*laser_pose_given) laser = {f->laser_pose.x, f->laser_pose.y, f->laser_pose.theta};
  b.numbers("laser_pose", &laser, 3);
  if (!laser.empty()) {
    f->laser_pose = Pose2(laser[0], laser[1], laser[2]);
    *laser_pose_given = true;
  }
}

// The initial pose covariance as three standard deviations.
void bindInitialPoseSigma(YamlBinder& b, PipelineOptions* p) {
  const Vector3 variance = p->initial_pose_covariance.diagonal();
  std::vector<double> sigma = {std::sqrt(variance(0)), std::sqrt(variance(1)),
                               std::sqrt(variance(2))};
  b.numbers("initial_pose_sigma", &sigma, 3);
  if (!sigma.empty()) {
    p->initial_pose_covariance =
        Vector3(sigma[0] * sigma[0], sigma[1] * sigma[1], sigma[2] * sigma[2]).asDiagonal();
  }
}

// Binds every key of `root` onto `c`; errors and (if given) the final values
// are collected. The sections follow the options structs (their fields and
// bounds come from each struct's visitFields), except where the file groups
// them for the reader: the filter section carries the laser mount, the
// pipeline section the initial pose sigmas, and the scan-matching section the
// motion noise of scan-matched increments.
void bindAll(const YAML::Node& root, SlamConfig* config,
             std::shared_ptr<std::vector<std::string>> errors,
             std::shared_ptr<YamlBinder::Values> values) {
  YamlBinder top(root, "", errors, values);
  SlamConfig& c = *config;
  top.section("features", c.pipeline.features);
  YamlBinder filter = top.child("filter");
  bindLaserPose(filter, &c.pipeline.filter, &c.laser_pose_given);
  c.pipeline.filter.visitFields(filter);
  filter.rejectUnknownKeys();
  top.section("association", c.pipeline.association);
  YamlBinder pipeline = top.child("pipeline");
  c.pipeline.visitFields(pipeline);
  bindInitialPoseSigma(pipeline, &c.pipeline);
  pipeline.rejectUnknownKeys();
  YamlBinder scan_matching = top.child("scan_matching");
  c.pipeline.scan_matching.visitFields(scan_matching);
  scan_matching.section("motion_noise", c.pipeline.scan_matched_motion_noise);
  scan_matching.rejectUnknownKeys();
  top.section("loop_closure", c.pipeline.loop_closure);
  top.section("smoother", c.pipeline.smoother);
  top.section("map", c.map);
  top.section("input", c.input);
  top.rejectUnknownKeys();
}

}  // namespace

std::string loadSlamConfig(const YAML::Node& root, SlamConfig* config) {
  auto errors = std::make_shared<std::vector<std::string>>();
  SlamConfig c = *config;
  bindAll(root, &c, errors, nullptr);
  if (errors->empty()) {
    // Cross-field checks of the components themselves.
    const std::string pipeline = c.pipeline.validate();
    if (!pipeline.empty()) errors->push_back(pipeline);
    const std::string map = c.map.validate();
    if (!map.empty()) errors->push_back("map: " + map);
  }
  if (!errors->empty()) {
    std::string all;
    for (const std::string& e : *errors) all += (all.empty() ? "" : "\n") + e;
    return all;
  }
  *config = c;
  return "";
}

std::string describeSlamConfig(const SlamConfig& config) {
  auto errors = std::make_shared<std::vector<std::string>>();
  auto values = std::make_shared<YamlBinder::Values>();
  SlamConfig copy = config;
  bindAll(YAML::Node(), &copy, errors, values);
  std::string out;
  for (const auto& [key, value] : *values) out += key + ": " + value + "\n";
  return out;
}

std::string loadSlamConfigFile(const std::string& path, SlamConfig* config) {
  try {
    return loadSlamConfig(YAML::LoadFile(path), config);
  } catch (const YAML::Exception& e) {
    return path + ": " + e.what();
  }
}

}  // namespace ekf_slam
