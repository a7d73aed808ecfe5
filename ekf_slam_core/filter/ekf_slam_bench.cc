// One full EKF-SLAM iteration (predict + associate + update + augment) with
// 20 observations per scan (19 of mapped landmarks, 1 new), for maps of 50 to
// 2,000 landmarks, alone and followed by the removal of a landmark from the
// middle of the map. Issue targets: ≤ 1 ms at 200, ≤ 13 ms at 1,000 landmarks.
#include <benchmark/benchmark.h>

#include <random>

#include "ekf_slam_core/filter/slam_iteration.h"

namespace ekf_slam {
namespace {

constexpr int kObservationsPerScan = 20;

// A filter holding `landmarks` landmarks scattered around the robot, built
// through real augment and update steps so P is dense and correlated.
EkfSlam makeFilter(int landmarks, std::mt19937& rng) {
  FilterOptions options;
  options.tentative_max_age = 0;
  EkfSlam filter(options, Pose2(), Matrix3::Identity() * 1e-4);
  std::uniform_real_distribution<double> range(0.5, 8.0), bearing(-kPi, kPi);
  for (int i = 0; i < landmarks; ++i) {
    PointObservation obs;
    obs.z = {range(rng), bearing(rng)};
    obs.covariance = Matrix2::Identity() * 1e-4;
    filter.augment(obs);
    if (i % 50 == 49) filter.predict(OdometryControl{0.01, 0.05, 0.0}, 0.1);
  }
  return filter;
}

// Observations of 19 mapped landmarks, as seen after the motion `odom`, plus
// one far from every landmark (a new landmark).
std::vector<PointObservation> scan(const EkfSlam& filter, const Pose2& odom, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, 0.005);
  const Pose2 moved = compose(filter.pose(), odom);
  std::vector<PointObservation> observations;
  for (int i = 0; i < kObservationsPerScan - 1; ++i) {
    const int slot = (i * 7919) % filter.landmarkCount();
    PointObservation obs;
    predictPointObservation(moved, filter.options().laser_pose, filter.landmarkPosition(slot),
                            &obs.z);
    obs.z.range += noise(rng);
    obs.z.bearing += noise(rng) * 0.2;
    obs.covariance = Matrix2::Identity() * 1e-4;
    observations.push_back(obs);
  }
  PointObservation fresh;
  fresh.z = {30.0, 0.1};
  fresh.covariance = Matrix2::Identity() * 1e-4;
  observations.push_back(fresh);
  return observations;
}

// One timed iteration per loop at a constant map size. With
// `remove_middle`, the iteration is followed (timed) by the removal of a
// landmark from the middle of the map, as pruning a tentative landmark or
// merging a twin does: every later row and column of the covariance moves.
// Untimed, the new landmark is dropped again (the newest: it costs nothing)
// and, after a middle removal, landmarks are added at the end until the map
// has its size again (without it, merges of twins may shrink the map).
void timedIterations(benchmark::State& state, bool remove_middle) {
  const int landmarks = static_cast<int>(state.range(0));
  std::mt19937 rng(42);
  EkfSlam filter = makeFilter(landmarks, rng);
  AssociationOptions association;
  const Pose2 odom0, odom1(0.02, 0.0, 0.005);
  std::uniform_real_distribution<double> range(0.5, 8.0), bearing(-kPi, kPi);

  for (auto _ : state) {
    state.PauseTiming();
    const std::vector<PointObservation> observations = scan(filter, odom1, rng);
    state.ResumeTiming();

    const IterationReport report =
        runIteration(filter, association, odom0, odom1, 0.1, observations);
    if (remove_middle) filter.removeLandmark(filter.landmarks()[filter.landmarkCount() / 2].id);

    state.PauseTiming();
    benchmark::DoNotOptimize(report.matches.data());
    if (!report.ok() || report.new_landmark_ids.size() != 1)
      state.SkipWithError("iteration failed");
    state.counters["matches"] = static_cast<double>(report.matches.size());
    filter.removeLandmark(report.new_landmark_ids.front());
    while (remove_middle && filter.landmarkCount() < landmarks) {
      PointObservation obs;
      obs.z = {range(rng), bearing(rng)};
      obs.covariance = Matrix2::Identity() * 1e-4;
      filter.augment(obs);
    }
    state.ResumeTiming();
  }
  const int n = filter.stateDim();
  state.counters["state_dim"] = n;
  // Live covariance (n² doubles); the filter's storage may hold up to 2× the
  // dimension in reserve (4× the bytes) between reallocations.
  state.counters["covariance_MiB"] = n * static_cast<double>(n) * sizeof(double) / (1 << 20);
}

void BM_FullIteration(benchmark::State& state) { timedIterations(state, false); }
void BM_IterationRemovingAMiddleLandmark(benchmark::State& state) { timedIterations(state, true); }

BENCHMARK(BM_FullIteration)
    ->Arg(50)
    ->Arg(100)
    ->Arg(200)
    ->Arg(500)
    ->Arg(1000)
    ->Arg(1500)
    ->Arg(2000)
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(0.5);

BENCHMARK(BM_IterationRemovingAMiddleLandmark)
    ->Arg(200)
    ->Arg(1000)
    ->Arg(1500)
    ->Arg(2000)
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(0.5);

}  // namespace
}  // namespace ekf_slam

BENCHMARK_MAIN();
