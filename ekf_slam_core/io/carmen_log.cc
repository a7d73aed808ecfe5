#include "ekf_slam_core/io/carmen_log.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace ekf_slam {
namespace {

// Splits on whitespace.
std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  std::string t;
  while (in >> t) out.push_back(t);
  return out;
}

bool toDouble(const std::string& s, double* value) {
  errno = 0;
  char* end = nullptr;
  *value = std::strtod(s.c_str(), &end);
  return errno == 0 && end != s.c_str() && *end == '\0';
}

class Fields {
 public:
  explicit Fields(const std::vector<std::string>& t) : t_(t) {}
  size_t remaining() const { return t_.size() - next_; }
  bool number(double* v) { return next_ < t_.size() && toDouble(t_[next_++], v); }
  bool count(int* n) {
    double v;
    if (!number(&v) || v < 0 || v > 100000 || v != static_cast<int>(v)) return false;
    *n = static_cast<int>(v);
    return true;
  }
  bool skip(size_t k) {
    if (remaining() < k) return false;
    next_ += k;
    return true;
  }

 private:
  const std::vector<std::string>& t_;
  size_t next_ = 1;  // after the message type
};

std::string fieldCountError(const std::string& kind, size_t got, size_t expected) {
  return kind + " line has " + std::to_string(got) + " fields, expected " +
         std::to_string(expected);
}

}  // namespace

std::string parseCarmenLine(const std::string& line, double max_range, std::string* kind,
                            CarmenLaser* laser, CarmenOdometry* odometry) {
  kind->clear();
  const std::vector<std::string> t = tokens(line);
  if (t.empty() || t[0][0] == '#') return "";
  Fields f(t);
  if (t[0] == "ODOM") {
    if (t.size() != 10) return fieldCountError("ODOM", t.size(), 10);
    double x, y, th, tv, rv, acc, stamp;
    if (!f.number(&x) || !f.number(&y) || !f.number(&th) || !f.number(&tv) || !f.number(&rv) ||
        !f.number(&acc) || !f.number(&stamp)) {
      return "ODOM line has a non-numeric value";
    }
    *kind = "ODOM";
    odometry->stamp = stamp;
    odometry->pose = Pose2(x, y, th);
    return "";
  }
  if (t[0] == "FLASER") {
    int n = 0;
    if (!f.count(&n)) return "FLASER line: bad reading count";
    const size_t expected = 1 + 1 + n + 6 + 3;
    if (t.size() != expected) return fieldCountError("FLASER", t.size(), expected);
    Scan scan;
    scan.ranges.resize(n);
    for (int i = 0; i < n; ++i) {
      if (!f.number(&scan.ranges[i])) return "FLASER line: non-numeric range";
    }
    double lx, ly, lth, ox, oy, oth, stamp;
    if (!f.number(&lx) || !f.number(&ly) || !f.number(&lth) || !f.number(&ox) || !f.number(&oy) ||
        !f.number(&oth) || !f.number(&stamp)) {
      return "FLASER line has a non-numeric pose or timestamp";
    }
    scan.angle_min = -kPi / 2.0;
    scan.angle_increment = n > 1 ? kPi / (n - 1) : 0.0;
    scan.range_min = 0.0;
    scan.range_max = max_range;
    scan.stamp = stamp;
    *kind = "FLASER";
    laser->scan = std::move(scan);
    laser->robot_odometry = Pose2(ox, oy, oth);
    // FLASER gives the laser pose in the odometry frame: mounting = robot⁻¹ ⊕ laser.
    laser->laser_in_robot = between(laser->robot_odometry, Pose2(lx, ly, lth));
    return "";
  }
  if (t[0] == "ROBOTLASER1") {
    double type, start, fov, resolution, range_limit, accuracy, remission_mode;
    if (!f.number(&type) || !f.number(&start) || !f.number(&fov) || !f.number(&resolution) ||
        !f.number(&range_limit) || !f.number(&accuracy) || !f.number(&remission_mode)) {
      return "ROBOTLASER1 line: bad header fields";
    }
    int n = 0;
    if (!f.count(&n)) return "ROBOTLASER1 line: bad reading count";
    Scan scan;
    scan.ranges.resize(n);
    for (int i = 0; i < n; ++i) {
      if (!f.number(&scan.ranges[i])) return "ROBOTLASER1 line: non-numeric range";
    }
    int m = 0;
    if (!f.count(&m) || !f.skip(m)) return "ROBOTLASER1 line: bad remission count";
    if (f.remaining() != 14) {
      return fieldCountError("ROBOTLASER1", t.size(), t.size() - f.remaining() + 14);
    }
    double lx, ly, lth, rx, ry, rth, tv, rv, fs, ss, ta, stamp;
    if (!f.number(&lx) || !f.number(&ly) || !f.number(&lth) || !f.number(&rx) || !f.number(&ry) ||
        !f.number(&rth) || !f.number(&tv) || !f.number(&rv) || !f.number(&fs) || !f.number(&ss) ||
        !f.number(&ta) || !f.number(&stamp)) {
      return "ROBOTLASER1 line has a non-numeric pose or timestamp";
    }
    scan.angle_min = start;
    scan.angle_increment = resolution;
    scan.range_min = 0.0;
    scan.range_max = std::min(range_limit > 0 ? range_limit : max_range, max_range);
    scan.stamp = stamp;
    *kind = "ROBOTLASER1";
    laser->scan = std::move(scan);
    laser->robot_odometry = Pose2(rx, ry, rth);
    laser->laser_in_robot = between(laser->robot_odometry, Pose2(lx, ly, lth));
    return "";
  }
  return "";  // another message type: skipped
}

std::string readCarmenLog(const std::string& path, CarmenLog* log, double max_range) {
  *log = CarmenLog();
  std::ifstream in(path);
  if (!in) return path + ": cannot open";
  CarmenLog result;
  std::string line, kind;
  for (int number = 1; std::getline(in, line); ++number) {
    CarmenLaser laser;
    CarmenOdometry odom;
    const std::string error = parseCarmenLine(line, max_range, &kind, &laser, &odom);
    if (!error.empty()) return path + ":" + std::to_string(number) + ": " + error;
    if (kind == "FLASER" || kind == "ROBOTLASER1") {
      result.lasers.push_back(std::move(laser));
    } else if (kind == "ODOM") {
      result.odometry.push_back(odom);
    } else if (!line.empty() && line[0] != '#') {
      ++result.skipped_lines;
    }
  }
  *log = std::move(result);
  return "";
}

}  // namespace ekf_slam
