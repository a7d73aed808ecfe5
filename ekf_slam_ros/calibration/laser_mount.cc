#include "ekf_slam_ros/calibration/laser_mount.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <sstream>
#include <vector>

#include "ekf_slam_core/io/atomic_file.h"

namespace ekf_slam {
namespace calibration {
namespace {

// Collects the problems of one file so that the user sees all of them at once.
class Reader {
 public:
  Reader(const YAML::Node& root, const std::string& file) : root_(root), file_(file) {}

  // `optional`: a missing key leaves `value` as it is.
  void number(const char* key, double* value, double limit, bool optional = false) {
    known_.insert(key);
    if (!root_[key]) {
      if (optional) return;
      return fail(key, "missing (every key of this file is required)");
    }
    try {
      const double v = root_[key].as<double>();
      if (!std::isfinite(v) || std::abs(v) > limit) {
        std::ostringstream text;
        text << "must be in [" << -limit << ", " << limit << "], got " << v;
        return fail(key, text.str());
      }
      *value = v;
    } catch (const YAML::Exception&) {
      fail(key, "must be a number");
    }
  }

  void frame(const char* key, std::string* value) {
    known_.insert(key);
    if (!root_[key]) return fail(key, "missing (every key of this file is required)");
    try {
      const std::string v = root_[key].as<std::string>();
      if (v.empty() || v.front() == '/') return fail(key, "must be a frame name without '/'");
      *value = v;
    } catch (const YAML::Exception&) {
      fail(key, "must be a frame name");
    }
  }

  void rejectUnknownKeys() {
    for (const auto& entry : root_) {
      const std::string key = entry.first.as<std::string>();
      if (!known_.count(key)) fail(key.c_str(), "unknown key (typo?)");
    }
  }

  std::string errors() const { return errors_; }

 private:
  void fail(const char* key, const std::string& why) {
    if (!errors_.empty()) errors_ += "\n";
    errors_ += file_ + ": " + key + ": " + why;
  }

  YAML::Node root_;
  std::string file_;
  std::set<std::string> known_;
  std::string errors_;
};

}  // namespace

std::string loadLaserMount(const std::string& path, LaserMount* mount) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return path + ": cannot read the calibration file";
  } catch (const YAML::Exception& error) {
    return path + ": not valid YAML: " + error.what();
  }
  if (!root.IsMap())
    return path + ": must be a mapping of keys (parent_frame, child_frame, x, ...)";
  LaserMount read;
  Reader reader(root, path);
  reader.frame("parent_frame", &read.parent_frame);
  reader.frame("child_frame", &read.child_frame);
  // A mount more than 2 m from the axle is a unit mistake (mm for m).
  reader.number("x", &read.x, 2.0);
  reader.number("y", &read.y, 2.0);
  reader.number("z", &read.z, 2.0);
  reader.number("yaw", &read.yaw, kPi);
  // The tilt: 0 (level) when absent, as in files written before it was kept.
  reader.number("roll", &read.roll, kPi, true);
  reader.number("pitch", &read.pitch, kPi / 2.0, true);
  reader.rejectUnknownKeys();
  if (reader.errors().empty() && read.parent_frame == read.child_frame) {
    return path + ": child_frame: must differ from parent_frame";
  }
  if (!reader.errors().empty()) return reader.errors();
  *mount = read;
  return "";
}

std::string saveLaserMount(const std::string& path, const LaserMount& mount,
                           const std::string& comment) {
  std::ostringstream text;
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) text << "# " << line << "\n";
  text.setf(std::ios::fixed);
  text.precision(4);
  text << "parent_frame: " << mount.parent_frame << "\n"
       << "child_frame: " << mount.child_frame << "\n"
       << "x: " << mount.x << "     # m, forward\n"
       << "y: " << mount.y << "     # m, left\n"
       << "z: " << mount.z << "     # m, up (display only)\n";
  text.precision(5);
  text << "yaw: " << mount.yaw << "   # rad, counter-clockwise\n"
       << "roll: " << mount.roll << "  # rad, left side up\n"
       << "pitch: " << mount.pitch << " # rad, front down\n";
  return writeFileAtomically(path, text.str());
}

}  // namespace calibration
}  // namespace ekf_slam
