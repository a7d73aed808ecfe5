#include "ekf_slam_core/io/trajectory_file.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace ekf_slam {

std::string readTrajectory(const std::string& path, std::vector<StampedPose>* out) {
  std::ifstream in(path);
  if (!in) return path + ": cannot open";
  std::vector<StampedPose> poses;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    StampedPose p;
    double x, y, theta;
    std::string extra;
    const std::string where = path + ":" + std::to_string(number) + ": ";
    if (!(fields >> p.stamp >> x >> y >> theta) || (fields >> extra)) {
      return where + "expected 'stamp x y theta'";
    }
    if (!std::isfinite(p.stamp) || !std::isfinite(x) || !std::isfinite(y) ||
        !std::isfinite(theta)) {
      return where + "non-finite value";
    }
    p.pose = Pose2(x, y, theta);
    poses.push_back(p);
  }
  *out = std::move(poses);
  return "";
}

std::string writeTrajectory(const std::string& path, const std::vector<StampedPose>& poses) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return path + ": cannot write";
  for (const StampedPose& p : poses) {
    std::fprintf(f, "%.6f %.6f %.6f %.6f\n", p.stamp, p.pose.x, p.pose.y, p.pose.theta);
  }
  // A write that failed on the way (a full disk) leaves the error flag;
  // fclose reports only the last buffer's.
  const bool failed = std::ferror(f) != 0;
  return std::fclose(f) == 0 && !failed ? "" : path + ": write error";
}

}  // namespace ekf_slam
