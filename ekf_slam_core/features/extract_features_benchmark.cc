// Extraction time per scan (targets: 361 beams <= 50 us, 181 beams
// <= 25 us on one core). The scans are ray-cast from the carton layout of
// thesis §5.1.2 inside a 9 m x 6 m lab, with 1 cm range noise: a cluttered,
// feature-rich sweep (about 20 lines and 30 point features at 361 beams).
#include <benchmark/benchmark.h>

#include <random>

#include "ekf_slam_core/features/extract_features.h"
#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

Scan cartonScan(int beams) {
  sim::PolygonWorld world;
  world.addBox(Vector2(2.5, 0.0), 9.0, 6.0);
  const double xs[] = {0.6, 1.9, 3.2, 4.5};
  for (int i = 0; i < 4; ++i) {
    world.addBox(Vector2(xs[i], 1.4), 0.5, 0.35, 0.15 * i);
    world.addBox(Vector2(xs[i] + 0.4, -1.4), 0.5, 0.35, -0.2 * i + 0.3);
  }
  sim::SweepGeometry sweep;
  sweep.angle_min = -kPi / 2.0;
  sweep.angle_increment = kPi / (beams - 1);
  sweep.count = beams;
  sweep.max_range = 15.0;
  std::mt19937 rng(11);
  return sim::simulateScan(world, Pose2(-0.5, 0.0, 0.0), sweep, 0.01, &rng, 0.02);
}

void BM_ExtractFeatures(benchmark::State& state) {
  const Scan scan = cartonScan(static_cast<int>(state.range(0)));
  const FeatureOptions options;
  size_t lines = 0, points = 0;
  for (auto _ : state) {
    const FeatureSet set = extractFeatures(scan, options);
    lines = set.lines.size();
    points = set.points_of_interest.size();
    benchmark::DoNotOptimize(set.lines.data());
  }
  state.counters["lines"] = static_cast<double>(lines);
  state.counters["point_features"] = static_cast<double>(points);
}
BENCHMARK(BM_ExtractFeatures)->Arg(181)->Arg(361)->Arg(721)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace ekf_slam

BENCHMARK_MAIN();
