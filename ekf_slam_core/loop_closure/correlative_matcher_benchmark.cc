// The loop closer's verification, per candidate: rasterising a submap into
// the likelihood grid with its bounding levels (LikelihoodGrid::build), and
// the branch-and-bound search of one key scan over a window. The submap is
// eleven 361-beam sweeps (the default submap_half_width of 5 on each side)
// taken along 5 m of a 24 m x 14 m hall with furniture, 1 cm range noise;
// the query is a sweep from the middle of that path, placed 1 m and 0.2 rad
// off, searched over a 2 m, 0.35 rad window.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "ekf_slam_core/loop_closure/correlative_matcher.h"
#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

sim::PolygonWorld hall() {
  sim::PolygonWorld world;
  world.addBox(Vector2(0.0, 0.0), 24.0, 14.0);
  for (int i = 0; i < 6; ++i) {
    world.addBox(Vector2(-9.0 + 3.6 * i, 4.5 - 1.5 * (i % 3)), 0.8, 0.5, 0.3 * i);
    world.addBox(Vector2(-8.0 + 3.2 * i, -4.0 + 1.2 * (i % 2)), 1.2, 0.6, -0.2 * i);
  }
  return world;
}

// One sweep from `pose`, as points in `pose`'s frame.
std::vector<Vector2> sweepPoints(const sim::PolygonWorld& world, const Pose2& pose,
                                 std::mt19937* rng) {
  sim::SweepGeometry sweep;
  sweep.angle_min = -kPi / 2.0;
  sweep.angle_increment = kPi / 360.0;
  sweep.count = 361;
  sweep.max_range = 30.0;
  const Scan scan = sim::simulateScan(world, pose, sweep, 0.01, rng, 0.0);
  std::vector<Vector2> points;
  for (int i = 0; i < scan.size(); ++i) {
    if (!scan.isValid(i)) continue;
    points.emplace_back(scan.ranges[i] * std::cos(scan.angle(i)),
                        scan.ranges[i] * std::sin(scan.angle(i)));
  }
  return points;
}

struct Place {
  std::vector<Vector2> submap;  // in the frame of the middle sweep's pose
  std::vector<Vector2> query;   // the middle sweep again, a new noise draw
};

Place place() {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(5);
  Place out;
  const Pose2 middle(-1.0, 0.0, 0.1);
  for (int k = -5; k <= 5; ++k) {
    const Pose2 pose(middle.x + 0.5 * k, 0.05 * k, middle.theta + 0.02 * k);
    const Pose2 in_middle = between(middle, pose);
    for (const Vector2& p : sweepPoints(world, pose, &rng)) {
      out.submap.push_back(transformFrom(in_middle, p));
    }
  }
  out.query = sweepPoints(world, middle, &rng);
  return out;
}

void BM_LikelihoodGridBuild(benchmark::State& state) {
  const Place p = place();
  const CorrelativeMatcherOptions options;
  LikelihoodGrid grid;  // rebuilt in place, as the loop closer does
  for (auto _ : state) {
    grid.build(p.submap, options);
    benchmark::DoNotOptimize(grid.fine(0, 0));
  }
  state.counters["submap_points"] = static_cast<double>(p.submap.size());
}
BENCHMARK(BM_LikelihoodGridBuild)->Unit(benchmark::kMillisecond);

void BM_CorrelativeSearch(benchmark::State& state) {
  const Place p = place();
  const CorrelativeMatcherOptions options;
  const LikelihoodGrid grid(p.submap, options);
  // A sparse query, as the loop closer searches with (every fourth point).
  std::vector<Vector2> query;
  for (size_t i = 0; i < p.query.size(); i += 4) query.push_back(p.query[i]);
  const Pose2 guess(1.0, 0.0, 0.2);
  for (auto _ : state) {
    CorrelativeResult r = correlativeSearch(query, grid, guess, 2.0, 0.35, options);
    benchmark::DoNotOptimize(r);
  }
  // The search finds the place: its score and how far from the true pose.
  const CorrelativeResult found = correlativeSearch(query, grid, guess, 2.0, 0.35, options);
  state.counters["score"] = found.score;
  state.counters["error_m"] = std::hypot(found.pose.x, found.pose.y);
}
BENCHMARK(BM_CorrelativeSearch)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ekf_slam

BENCHMARK_MAIN();
