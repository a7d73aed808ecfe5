#include "ekf_slam_core/sim/polygon_world.h"

#include <cmath>
#include <limits>

namespace ekf_slam {
namespace sim {

void PolygonWorld::addVertex(const Vector2& v) {
  for (const Vector2& existing : vertices_) {
    if ((existing - v).norm() < 1e-9) return;
  }
  vertices_.push_back(v);
}

void PolygonWorld::addSegment(const Vector2& a, const Vector2& b) {
  segments_.push_back({a, b});
  addVertex(a);
  addVertex(b);
}

void PolygonWorld::addPolygon(const std::vector<Vector2>& vertices, bool closed) {
  const size_t n = vertices.size();
  if (n < 2) return;
  for (size_t i = 0; i + 1 < n; ++i) addSegment(vertices[i], vertices[i + 1]);
  if (closed && n > 2) addSegment(vertices[n - 1], vertices[0]);
}

void PolygonWorld::addBox(const Vector2& center, double width, double height, double angle) {
  const Pose2 frame(center.x(), center.y(), angle);
  const double hw = width / 2.0, hh = height / 2.0;
  addPolygon({transformFrom(frame, Vector2(-hw, -hh)), transformFrom(frame, Vector2(hw, -hh)),
              transformFrom(frame, Vector2(hw, hh)), transformFrom(frame, Vector2(-hw, hh))});
}

double PolygonWorld::castRay(const Vector2& origin, double angle, double max_range) const {
  const Vector2 direction(std::cos(angle), std::sin(angle));
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& s : segments_) {
    // Solve origin + t d = a + u (b - a) for t >= 0, u in [0, 1].
    const Vector2 e = s.b - s.a;
    const double denom = direction.x() * e.y() - direction.y() * e.x();
    if (std::abs(denom) < 1e-12) continue;  // parallel
    const Vector2 w = s.a - origin;
    const double t = (w.x() * e.y() - w.y() * e.x()) / denom;
    const double u = (w.x() * direction.y() - w.y() * direction.x()) / denom;
    if (t > 1e-9 && u >= 0.0 && u <= 1.0 && t < best) best = t;
  }
  return best <= max_range ? best : std::numeric_limits<double>::infinity();
}

std::vector<double> simulateRanges(const RayCaster& world, const Pose2& sensor_pose,
                                   const SweepGeometry& sweep, double range_sigma,
                                   std::mt19937* rng) {
  std::vector<double> ranges(sweep.count > 0 ? sweep.count : 0);
  std::normal_distribution<double> noise(0.0, range_sigma);
  const bool tilted = sweep.roll != 0.0 || sweep.pitch != 0.0;
  for (int i = 0; i < sweep.count; ++i) {
    double r;
    if (tilted) {
      const TiltedBeam tilted_beam =
          tiltedBeam(sweep.angle_min + i * sweep.angle_increment, sweep.roll, sweep.pitch);
      r = world.castRay(sensor_pose.translation(), sensor_pose.theta + tilted_beam.level_bearing,
                        sweep.max_range * tilted_beam.horizontal) /
          tilted_beam.horizontal;
    } else {
      const double beam = sensor_pose.theta + sweep.angle_min + i * sweep.angle_increment;
      r = world.castRay(sensor_pose.translation(), beam, sweep.max_range);
    }
    if (std::isfinite(r) && rng != nullptr && range_sigma > 0.0) r = std::max(0.0, r + noise(*rng));
    ranges[i] = r;
  }
  return ranges;
}

Scan simulateScan(const RayCaster& world, const Pose2& sensor_pose, const SweepGeometry& sweep,
                  double range_sigma, std::mt19937* rng, double range_min) {
  Scan scan;
  scan.ranges = simulateRanges(world, sensor_pose, sweep, range_sigma, rng);
  scan.angle_min = sweep.angle_min;
  scan.angle_increment = sweep.angle_increment;
  scan.range_min = range_min;
  scan.range_max = sweep.max_range;
  return scan;
}

}  // namespace sim
}  // namespace ekf_slam
