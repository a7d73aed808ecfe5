// libFuzzer target: what a LaserScan becomes at the node's boundary (the
// core's Scan struct with the geometry checks the node applies) and the
// whole pipeline behind it (features, scan matching, filter, loop closer),
// with the shipped core defaults.
//
// Each input is a short drive through a 10 m × 8 m room: the input decides
// the odometry increments, the stamps, the scan geometry and which beams
// are replaced by hostile values (NaN, ±inf, negative, huge), including
// non-finite odometry and stamps. Properties: no crash, no UB, and the
// pipeline's answer for every scan, its poses and covariance, stays finite.
// Built by `make fuzz` (clang, -DEKF_SLAM_FUZZ=ON).
#include <fuzzer/FuzzedDataProvider.h>

#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_core/sensors/scan.h"

namespace {

using namespace ekf_slam;

constexpr double kHalfWidth = 5.0;  // m, room along x
constexpr double kHalfDepth = 4.0;  // m, room along y
constexpr double kPillar = 0.3;     // m, radius of a pillar at (1.5, 1)

// Distance from `origin` along `bearing` (map frame) to the first wall or
// the pillar.
double castRay(const Vector2& origin, double bearing) {
  const Vector2 d(std::cos(bearing), std::sin(bearing));
  double best = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 2; ++axis) {
    const double half = axis == 0 ? kHalfWidth : kHalfDepth;
    for (double wall : {-half, half}) {
      if (std::abs(d[axis]) < 1e-12) continue;
      const double t = (wall - origin[axis]) / d[axis];
      if (t > 0.0) best = std::min(best, t);
    }
  }
  const Vector2 to_centre = Vector2(1.5, 1.0) - origin;
  const double along = to_centre.dot(d);
  const double miss2 = to_centre.squaredNorm() - along * along;
  if (along > 0.0 && miss2 < kPillar * kPillar) {
    best = std::min(best, along - std::sqrt(kPillar * kPillar - miss2));
  }
  return best;
}

// A value chosen by the input: an ordinary one or a hostile one.
double hostile(FuzzedDataProvider& input, double ordinary) {
  switch (input.ConsumeIntegralInRange<int>(0, 9)) {
    case 0:
      return std::numeric_limits<double>::quiet_NaN();
    case 1:
      return std::numeric_limits<double>::infinity();
    case 2:
      return -std::numeric_limits<double>::infinity();
    case 3:
      return 0.0;
    case 4:
      return -ordinary;
    case 5:
      return 1e300;
    case 6:
      return input.ConsumeFloatingPoint<double>();
    default:
      return ordinary;
  }
}

bool finite(const Pose2& pose) {
  return std::isfinite(pose.x) && std::isfinite(pose.y) && std::isfinite(pose.theta);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider input(data, size);
  PipelineOptions options;
  options.loop_closure.enabled = input.ConsumeBool();
  assert(options.validate().empty());
  SlamPipeline pipeline(options);

  Pose2 truth(-2.0, -1.0, 0.2);
  Pose2 odometry(0.0, 0.0, 0.0);
  double stamp = 100.0;
  const int scans = input.ConsumeIntegralInRange<int>(1, 6);
  for (int k = 0; k < scans && input.remaining_bytes() > 0; ++k) {
    // Motion: a small step the room can hold, seen by the wheels with an
    // error (or a hostile value).
    const Pose2 step(input.ConsumeIntegralInRange<int>(-20, 40) * 0.01,
                     input.ConsumeIntegralInRange<int>(-10, 10) * 0.01,
                     input.ConsumeIntegralInRange<int>(-30, 30) * 0.01);
    const Pose2 moved = compose(truth, step);
    if (std::abs(moved.x) < kHalfWidth - 0.5 && std::abs(moved.y) < kHalfDepth - 0.5) {
      truth = moved;
    }
    const bool bad_odometry = input.ConsumeIntegralInRange<int>(0, 15) == 0;
    odometry = compose(odometry, step);
    Pose2 reported = odometry;
    if (bad_odometry) {
      reported.x = hostile(input, odometry.x);
      reported.theta = hostile(input, odometry.theta);
    }
    stamp += input.ConsumeIntegralInRange<int>(-1, 10) * 0.1;

    Scan scan;
    const int beams = input.ConsumeIntegralInRange<int>(0, 181);
    scan.angle_min = -kPi / 2.0;
    scan.angle_increment = beams > 1 ? kPi / (beams - 1) : 0.0;
    scan.range_min = 0.0;
    scan.range_max = 80.0;
    scan.stamp = stamp;
    if (input.ConsumeIntegralInRange<int>(0, 15) == 0) {
      switch (input.ConsumeIntegralInRange<int>(0, 4)) {
        case 0:
          scan.angle_min = hostile(input, scan.angle_min);
          break;
        case 1:
          scan.angle_increment = hostile(input, scan.angle_increment);
          break;
        case 2:
          scan.range_min = hostile(input, scan.range_min);
          break;
        case 3:
          scan.range_max = hostile(input, scan.range_max);
          break;
        default:
          scan.stamp = hostile(input, scan.stamp);
          break;
      }
    }
    scan.ranges.resize(beams);
    for (int i = 0; i < beams; ++i) {
      const double bearing = truth.theta + (-kPi / 2.0 + i * (beams > 1 ? kPi / (beams - 1) : 0.0));
      scan.ranges[i] = castRay(truth.translation(), bearing);
    }
    // Hostile readings at input-chosen beams.
    const int damaged = beams > 0 ? input.ConsumeIntegralInRange<int>(0, 8) : 0;
    for (int j = 0; j < damaged; ++j) {
      const int i = input.ConsumeIntegralInRange<int>(0, beams - 1);
      scan.ranges[i] = hostile(input, scan.ranges[i]);
    }

    // The node's boundary: geometry and usable readings, then the pipeline,
    // which must survive what passes (and what would not).
    const bool usable = validateScan(scan).empty() && countValidReadings(scan) >= 10;
    if (!usable && input.ConsumeBool()) continue;
    const ScanResult result = pipeline.processScan(scan, reported);
    assert(finite(result.pose));
    assert(finite(result.causal_pose));
    assert(result.pose_covariance.allFinite());
    assert(pipeline.mapToOdom().x == pipeline.mapToOdom().x);  // not NaN
  }
  if (options.loop_closure.enabled) pipeline.finishLoopClosure();
  for (const ScanRecord& record : pipeline.scans()) {
    assert(finite(record.filtered));
    assert(finite(record.causal));
  }
  return 0;
}
