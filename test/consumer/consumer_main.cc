// Runs ekf_slam's pipeline on three synthetic scans of a box room, through
// nothing but the package's export, and reads its landmark map file back
// (yaml-cpp, which the export brings along). Exit status 0 when the first
// scan initialised the map (kIterated), every pose is finite and the map
// file loads with every landmark.
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "ekf_slam_core/geometry/angle.h"
#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/io/landmark_map.h"
#include "ekf_slam_core/pipeline/map_file_conversion.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_core/sensors/scan.h"

// The export holds the core's production headers and no more: not the
// core's test helpers or simulator, not the ROS adapters, not the tools.
#if __has_include("ekf_slam_core/testing/jacobian_assertions.h") ||                       \
                  __has_include(                                                          \
                      "ekf_slam_core/sim/polygon_world.h") ||                             \
                      __has_include("ekf_slam_ros/conversions/scan_conversion.h") ||      \
                                    __has_include("ros_conversions/pose_conversion.h") || \
                                                  __has_include("tools/dev/experiment_options.h")
#error "ekf_slam exports more include paths than the core's headers"
#endif

namespace {

struct Segment {
  double ax, ay, bx, by;
};

// An 8 m x 6 m room with a square pillar, as wall segments (m).
std::vector<Segment> boxRoom() {
  const std::vector<std::vector<std::pair<double, double>>> polygons = {
      {{-4.0, -3.0}, {4.0, -3.0}, {4.0, 3.0}, {-4.0, 3.0}},
      {{1.3, 0.8}, {1.7, 0.8}, {1.7, 1.2}, {1.3, 1.2}},
  };
  std::vector<Segment> segments;
  for (const auto& corners : polygons) {
    for (size_t i = 0; i < corners.size(); ++i) {
      const auto& a = corners[i];
      const auto& b = corners[(i + 1) % corners.size()];
      segments.push_back({a.first, a.second, b.first, b.second});
    }
  }
  return segments;
}

// The distance from (x, y) along `angle` to the nearest wall, max_range when none.
double cast(const std::vector<Segment>& walls, double x, double y, double angle, double max_range) {
  const double dx = std::cos(angle), dy = std::sin(angle);
  double best = max_range;
  for (const Segment& s : walls) {
    const double ex = s.bx - s.ax, ey = s.by - s.ay;
    const double denominator = dx * ey - dy * ex;
    if (std::abs(denominator) < 1e-12) continue;
    const double t = ((s.ax - x) * ey - (s.ay - y) * ex) / denominator;  // along the beam
    const double u = ((s.ax - x) * dy - (s.ay - y) * dx) / denominator;  // along the wall
    if (t > 0.0 && t < best && u >= 0.0 && u <= 1.0) best = t;
  }
  return best;
}

// A 181-beam sweep over ±90° from a laser at the robot's centre.
ekf_slam::Scan scanFrom(const std::vector<Segment>& walls, const ekf_slam::Pose2& robot,
                        double stamp) {
  ekf_slam::Scan scan;
  scan.angle_min = -ekf_slam::kPi / 2.0;
  scan.angle_increment = ekf_slam::kPi / 180.0;
  scan.range_min = 0.1;
  scan.range_max = 8.0;
  scan.stamp = stamp;
  for (int i = 0; i < 181; ++i) {
    scan.ranges.push_back(
        cast(walls, robot.x, robot.y, robot.theta + scan.angle(i), scan.range_max));
  }
  return scan;
}

bool finite(const ekf_slam::Pose2& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta);
}

}  // namespace

int main() {
  const ekf_slam::PipelineOptions options;
  const std::string invalid = options.validate();
  if (!invalid.empty()) {
    std::printf("ekf_slam_consumer: the default PipelineOptions are invalid: %s\n",
                invalid.c_str());
    return 1;
  }
  ekf_slam::SlamPipeline pipeline(options);
  std::printf("ekf_slam_consumer: SlamPipeline with the default PipelineOptions\n");

  const std::vector<Segment> walls = boxRoom();
  // The robot starts at `start` in the room and drives 0.1 m forward, turning
  // 2 degrees, between scans; its odometry is exact. The map frame is the
  // robot's first pose (the default initial_pose), as the odometry's is.
  const ekf_slam::Pose2 start(-1.0, -1.5, 0.3);
  ekf_slam::Pose2 odometry;
  bool ok = true;
  for (int k = 0; k < 3; ++k) {
    const ekf_slam::Pose2 robot = ekf_slam::compose(start, odometry);
    const ekf_slam::Scan scan = scanFrom(walls, robot, 100.0 + 0.2 * k);
    const ekf_slam::ScanResult result = pipeline.processScan(scan, odometry);
    std::printf(
        "  scan %d at %.1f s, odometry (%.3f, %.3f, %.3f): %s, pose (%.4f, %.4f, %.4f), "
        "%zu landmark candidates, %d landmarks\n",
        k, scan.stamp, odometry.x, odometry.y, odometry.theta, ekf_slam::toString(result.outcome),
        result.pose.x, result.pose.y, result.pose.theta, result.observations.size(),
        pipeline.filter().landmarkCount());
    if (k == 0 && result.outcome != ekf_slam::ScanOutcome::kIterated) {
      std::printf("ekf_slam_consumer: the first scan was not iterated (%s)\n",
                  result.message.c_str());
      ok = false;
    }
    if (!finite(result.pose)) {
      std::printf("ekf_slam_consumer: scan %d has a pose that is not finite\n", k);
      ok = false;
    }
    odometry = ekf_slam::compose(odometry, ekf_slam::Pose2(0.1, 0.0, ekf_slam::degToRad(2.0)));
  }
  const ekf_slam::LandmarkMapFile map =
      ekf_slam::toLandmarkMapFile(pipeline.filter(), pipeline.lineSupport(), "map");
  ekf_slam::LandmarkMapFile loaded;
  const std::string error =
      ekf_slam::parseLandmarkMap(ekf_slam::formatLandmarkMap(map), "landmarks.yaml", &loaded);
  std::printf("  landmark map file: %zu landmarks written, %zu read%s%s\n", map.size(),
              loaded.size(), error.empty() ? "" : ": ", error.c_str());
  if (!error.empty() || loaded.size() != map.size() || map.size() == 0) ok = false;
  std::printf("ekf_slam_consumer: %s\n", ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
