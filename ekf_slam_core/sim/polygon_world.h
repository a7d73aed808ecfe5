// A 2D world of line segments (walls, boxes, cartons) and a ray caster over
// it: the ground truth for synthetic laser scans in tests, the LMS200
// emulator and the simulator.
#pragma once

#include <random>
#include <vector>

#include "ekf_slam_core/geometry/pose2.h"
#include "ekf_slam_core/sensors/scan.h"
#include "ekf_slam_core/sim/ray_caster.h"

namespace ekf_slam {
namespace sim {

struct Segment {
  Vector2 a;
  Vector2 b;
};

class PolygonWorld : public RayCaster {
 public:
  void addSegment(const Vector2& a, const Vector2& b);
  // Consecutive vertices joined by walls; `closed` joins the last to the first.
  void addPolygon(const std::vector<Vector2>& vertices, bool closed = true);
  // An axis-aligned (angle = 0) or rotated rectangle, e.g. a carton.
  void addBox(const Vector2& center, double width, double height, double angle = 0.0);

  // Distance (m) from `origin` along the world-frame direction `angle` (rad)
  // to the nearest segment, or +inf when nothing is hit within `max_range`.
  double castRay(const Vector2& origin, double angle, double max_range) const override;

  const std::vector<Segment>& segments() const { return segments_; }
  // Every polygon/box vertex added (true corners of the world), duplicates
  // removed. Segment end points added with addSegment are included too.
  const std::vector<Vector2>& vertices() const { return vertices_; }

 private:
  void addVertex(const Vector2& v);

  std::vector<Segment> segments_;
  std::vector<Vector2> vertices_;
};

// Geometry of a simulated sweep, in the sensor frame: beam i points at
// angle_min + i * angle_increment.
struct SweepGeometry {
  double angle_min = -kPi / 2.0;       // rad
  double angle_increment = kPi / 180;  // rad
  int count = 181;
  double max_range = 8.0;  // m; beams hitting nothing return +inf
  // rad, the scanner's tilt from level (TiltedBeam, sensors/scan.h): a beam
  // reports its slant distance to the first wall along its direction seen
  // from above. Walls are taller than any beam; there is no floor.
  double roll = 0.0;
  double pitch = 0.0;
};

// Ranges (m) seen from `sensor_pose` (the laser frame in the world). When
// `rng` is given, each finite range gets N(0, range_sigma²) noise; ranges stay
// +inf for no return.
std::vector<double> simulateRanges(const RayCaster& world, const Pose2& sensor_pose,
                                   const SweepGeometry& sweep, double range_sigma = 0.0,
                                   std::mt19937* rng = nullptr);

// The same readings as a Scan: the sweep's angles, range_max = the sweep's
// max_range (a beam that hits nothing stays +inf, "no return"), range_min as
// given, stamp 0.
Scan simulateScan(const RayCaster& world, const Pose2& sensor_pose, const SweepGeometry& sweep,
                  double range_sigma = 0.0, std::mt19937* rng = nullptr, double range_min = 0.0);

}  // namespace sim
}  // namespace ekf_slam
