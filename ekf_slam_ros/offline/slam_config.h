// The project's parameter file (config/ekf_slam.yaml) → core options. One
// loader serves the offline runner (yaml-cpp from a file) and, later, the
// live node (its private parameters converted to YAML), so both accept the
// same keys with the same checks.
#pragma once

#include <string>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/mapping/occupancy_grid.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"

namespace YAML {
class Node;
}

namespace ekf_slam {

struct InputOptions {
  std::string scan_topic = "/scan";
  std::string odom_topic = "/odom";
  std::string odometry_source = "odom";  // "odom" (nav_msgs/Odometry) or "tf"
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  double max_odometry_gap = 0.5;  // s: larger gaps between odometry samples are not interpolated

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.text("scan_topic", scan_topic, {});
    v.text("odom_topic", odom_topic, {});
    v.text("odometry_source", odometry_source, {"odom", "tf"});
    v.text("odom_frame", odom_frame, {});
    v.text("base_frame", base_frame, {});
    v.number("max_odometry_gap", max_odometry_gap, Bounds::above(0.0, "s"));
  }
  std::string validate() const { return checkFields(*this); }
};

struct SlamConfig {
  PipelineOptions pipeline;
  OccupancyGridOptions map;
  InputOptions input;
  bool laser_pose_given = false;  // filter.laser_pose set in the file (else from tf)
};

// Empty on success, else every problem found, one per line, each naming its key.
std::string loadSlamConfig(const YAML::Node& root, SlamConfig* config);
std::string loadSlamConfigFile(const std::string& path, SlamConfig* config);

// Every key the loader knows with the value `config` holds, one
// "section.key: value" line each in binding order, numbers to full
// precision: the effective configuration, printable and comparable.
std::string describeSlamConfig(const SlamConfig& config);

}  // namespace ekf_slam
