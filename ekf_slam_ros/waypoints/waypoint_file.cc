#include "ekf_slam_ros/waypoints/waypoint_file.h"

#include <yaml-cpp/yaml.h>

#include <cmath>

namespace ekf_slam {
namespace waypoints {

std::string loadWaypointFile(const std::string& path, WaypointFile* file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return path + ": cannot read the waypoint file";
  } catch (const YAML::Exception& error) {
    return path + ": not valid YAML: " + error.what();
  }
  if (!root.IsMap()) return path + ": must be a mapping with a `waypoints` list";
  std::string errors;
  auto fail = [&](const std::string& message) {
    errors += (errors.empty() ? "" : "\n") + path + ": " + message;
  };
  WaypointFile read;
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    if (key != "world" && key != "closed" && key != "waypoints") {
      fail(key + ": unknown key (typo?); known: world, closed, waypoints");
    }
  }
  try {
    if (root["world"]) read.world = root["world"].as<std::string>();
  } catch (const YAML::Exception&) {
    fail("world: must be a world name");
  }
  try {
    if (root["closed"]) read.closed = root["closed"].as<bool>();
  } catch (const YAML::Exception&) {
    fail("closed: must be true or false");
  }
  const YAML::Node list = root["waypoints"];
  if (!list || !list.IsSequence() || list.size() == 0) {
    fail("waypoints: must be a non-empty list of [x, y]");
  } else {
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string name = "waypoints[" + std::to_string(i) + "]";
      try {
        if (!list[i].IsSequence() || list[i].size() != 2) {
          fail(name + ": must be [x, y]");
          continue;
        }
        const Vector2 point(list[i][0].as<double>(), list[i][1].as<double>());
        if (!point.allFinite() || point.cwiseAbs().maxCoeff() > 1e4) {
          fail(name + ": coordinates must be finite and within 10 km");
          continue;
        }
        read.waypoints.push_back(point);
      } catch (const YAML::Exception&) {
        fail(name + ": x and y must be numbers");
      }
    }
  }
  if (!errors.empty()) return errors;
  *file = read;
  return "";
}

}  // namespace waypoints
}  // namespace ekf_slam
