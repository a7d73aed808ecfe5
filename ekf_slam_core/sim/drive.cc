#include "ekf_slam_core/sim/drive.h"

#include <cmath>
#include <random>

namespace ekf_slam {
namespace sim {

SimulatedDrive simulateDrive(const RayCaster& world, const std::vector<DriveSegment>& segments,
                             const DriveOptions& options) {
  std::mt19937 rng(options.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  SweepGeometry sweep;  // the LMS200's 181 beams over 180°, 8 m (mm mode)
  SimulatedDrive drive;
  Pose2 truth = options.start, odometry;
  double stamp = 0.0;
  for (const DriveSegment& segment : segments) {
    const int steps = static_cast<int>(std::lround(segment.seconds / options.period));
    for (int i = 0; i < steps; ++i) {
      // An arc: the chord of length d at half the turn.
      const double d = segment.v * options.period, a = segment.w * options.period;
      const Pose2 step(d * std::cos(a / 2.0), d * std::sin(a / 2.0), a);
      truth = compose(truth, step);
      const double e = options.wheel_noise;
      const Pose2 seen(step.x * (1.0 + e * unit(rng)), step.y * (1.0 + e * unit(rng)),
                       step.theta * (1.0 + e * unit(rng)) + 0.2 * e * d * unit(rng));
      odometry = compose(odometry, seen);
      stamp += options.period;
      Scan scan =
          simulateScan(world, compose(truth, options.laser), sweep, options.range_sigma, &rng);
      scan.stamp = stamp;
      drive.scans.push_back(std::move(scan));
      drive.odometry.push_back(odometry);
      drive.truth.push_back(truth);
    }
  }
  return drive;
}

PolygonWorld roomWithCartons() {
  PolygonWorld world;
  world.addPolygon({{-6, -4}, {6, -4}, {6, 4}, {-6, 4}});
  world.addBox({2.0, 1.5}, 0.6, 0.4, 0.3);
  world.addBox({-2.5, -1.0}, 0.8, 0.8);
  world.addBox({1.0, -2.5}, 1.0, 0.5, -0.4);
  world.addBox({-1.0, 2.4}, 0.5, 0.5, 0.2);
  return world;
}

std::vector<DriveSegment> mixedDrive() {
  return {{0.3, 0.0, 3.0},    {0.3, 0.0, 6.0},    {0.25, 0.35, 8.0}, {0.0, 0.5, 5.0},
          {0.0, 0.5, 5.0},    {0.25, -0.35, 8.0}, {0.0, -0.5, 4.0},  {0.25, 0.35, 8.0},
          {0.25, -0.35, 8.0}, {0.3, 0.3, 6.0},    {0.0, 0.6, 3.0},   {0.0, 0.6, 3.0}};
}

}  // namespace sim
}  // namespace ekf_slam
