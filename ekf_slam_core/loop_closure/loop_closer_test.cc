// Loop closure on synthetic scans: ray-cast sweeps of a room with boxes
// (sim::PolygonWorld), a drifting front end, and known true poses.
#include "ekf_slam_core/loop_closure/loop_closer.h"

#include "ekf_slam_core/loop_closure/back_end.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include "ekf_slam_core/sim/polygon_world.h"

namespace ekf_slam {
namespace {

// 20 m × 12 m with boxes of different sizes and angles: structure in every
// direction, no two places alike.
sim::PolygonWorld hall() {
  sim::PolygonWorld world;
  world.addPolygon({{-10, -6}, {10, -6}, {10, 6}, {-10, 6}});
  world.addBox({0.0, 0.0}, 2.0, 1.0, 0.3);
  world.addBox({-7.0, 3.5}, 1.0, 1.0);
  world.addBox({6.5, -4.0}, 1.5, 0.6, -0.5);
  world.addBox({7.0, 4.0}, 0.5, 0.5);
  world.addBox({-6.0, -4.5}, 0.8, 1.6, 0.2);
  world.addBox({3.0, 2.5}, 0.6, 0.6, 0.7);
  return world;
}

Scan sweep(const sim::RayCaster& world, const Pose2& robot, std::mt19937* rng) {
  sim::SweepGeometry geometry;
  geometry.angle_increment = kPi / 180;
  geometry.count = 181;
  geometry.max_range = 30.0;
  return sim::simulateScan(world, robot, geometry, 0.01, rng);
}

std::vector<Vector2> pointsOf(const Scan& scan) {
  return scanPointsInRobotFrame(scan, Pose2(), ScanMatcherOptions());
}

// Laps of a circle of radius 4.5 m around the hall's centre, 0.1 m apart.
std::vector<Pose2> laps(int count) {
  std::vector<Pose2> poses;
  const double radius = 4.5, step = 0.1;
  const int per_lap = static_cast<int>(2.0 * kPi * radius / step);
  for (int i = 0; i <= count * per_lap; ++i) {
    const double a = 2.0 * kPi * i / per_lap;
    poses.emplace_back(radius * std::sin(a), -radius * std::cos(a), a);
  }
  return poses;
}

std::vector<Pose2> twoLaps() { return laps(2); }

// A sweep taken at `pose`, its points placed in the world frame.
std::vector<Vector2> placedSweep(const sim::PolygonWorld& world, const Pose2& pose,
                                 std::mt19937* rng) {
  std::vector<Vector2> placed;
  for (const Vector2& p : pointsOf(sweep(world, pose, rng)))
    placed.push_back(transformFrom(pose, p));
  return placed;
}

TEST(CorrelativeSearch, FindsAPoseMetresAndDegreesFromTheGuess) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(3);
  const Pose2 reference_pose(-2.0, 1.0, 0.4), query_pose(-1.2, 0.6, 0.3);
  const std::vector<Vector2> reference = placedSweep(world, reference_pose, &rng);
  const CorrelativeMatcherOptions options;
  const LikelihoodGrid grid(reference, options);
  const Pose2 guess = compose(query_pose, Pose2(1.2, -0.9, degToRad(8.0)));
  const CorrelativeResult result =
      correlativeSearch(pointsOf(sweep(world, query_pose, &rng)), grid, guess, 2.0, 0.2, options);
  EXPECT_GT(result.score, 0.7);
  EXPECT_LT(std::hypot(result.pose.x - query_pose.x, result.pose.y - query_pose.y), 0.08);
  EXPECT_LT(std::abs(wrapAngle(result.pose.theta - query_pose.theta)), degToRad(1.0));
}

// A grid rebuilt in the storage of earlier ones (larger, smaller, empty,
// outsized) holds exactly what a grid built afresh from the same points
// holds, at every level and cell, and reuses its buffers when it fits.
TEST(LikelihoodGrid, RebuiltInPlaceEqualsAFreshGrid) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(11);
  const std::vector<Vector2> room = placedSweep(world, Pose2(-2.0, 1.0, 0.4), &rng);
  const std::vector<Vector2> corner(room.begin(), room.begin() + room.size() / 4);
  const std::vector<Vector2> far = {Vector2(0.0, 0.0), Vector2(1e5, 1e5)};  // beyond kMaxCells
  const CorrelativeMatcherOptions options;
  LikelihoodGrid reused;
  EXPECT_TRUE(reused.empty());
  const auto expectSame = [&](const std::vector<Vector2>& points) {
    reused.build(points, options);
    const LikelihoodGrid fresh(points, options);
    ASSERT_EQ(reused.empty(), fresh.empty());
    ASSERT_EQ(reused.levels(), fresh.levels());
    EXPECT_EQ(reused.lowerCorner(), fresh.lowerCorner());
    EXPECT_EQ(reused.upperCorner(), fresh.upperCorner());
    if (fresh.empty()) return;
    int ix_end, iy_end;
    fresh.cellOf(fresh.upperCorner(), &ix_end, &iy_end);
    long differing = 0, positive = 0;
    for (int level = 0; level < fresh.levels(); ++level) {
      const int pad = 1 << level;  // one cell beyond the level's padding
      for (int iy = -pad; iy <= iy_end + 1; ++iy) {
        for (int ix = -pad; ix <= ix_end + 1; ++ix) {
          differing += reused.value(level, ix, iy) != fresh.value(level, ix, iy);
          positive += fresh.value(level, ix, iy) > 0.0f;
        }
      }
    }
    EXPECT_EQ(differing, 0);
    EXPECT_GT(positive, 1000);
  };
  expectSame(room);
  const size_t room_bytes = reused.storageBytes();
  EXPECT_GT(room_bytes, 0u);
  expectSame(corner);
  EXPECT_EQ(reused.storageBytes(), room_bytes);  // a smaller grid allocates nothing
  reused.build({}, options);
  EXPECT_TRUE(reused.empty());
  EXPECT_EQ(reused.levels(), 0);
  reused.build(far, options);
  EXPECT_TRUE(reused.empty());
  expectSame(room);
  EXPECT_EQ(reused.storageBytes(), room_bytes);
  reused.release();
  EXPECT_TRUE(reused.empty());
  EXPECT_EQ(reused.storageBytes(), 0u);
  expectSame(corner);
}

// The fine level is the definition: at each cell centre, exp(−d²/2σ²) for
// the nearest point d within 3σ's reach of whole cells, else 0, checked
// against a look at every point (float of the same double).
TEST(LikelihoodGrid, FineLevelIsTheLikelihoodOfTheNearestPoint) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(3);
  const std::vector<Vector2> points = placedSweep(world, Pose2(1.0, -0.5, 2.0), &rng);
  CorrelativeMatcherOptions options;
  const LikelihoodGrid grid(points, options);
  ASSERT_FALSE(grid.empty());
  const int cells = static_cast<int>(std::ceil(3.0 * options.sigma / options.resolution));
  int ix_end, iy_end;
  grid.cellOf(grid.upperCorner(), &ix_end, &iy_end);
  long checked = 0, positive = 0;
  for (int iy = 0; iy < iy_end; iy += 3) {
    for (int ix = 0; ix < ix_end; ix += 3) {
      const Vector2 centre = grid.lowerCorner() + options.resolution * Vector2(ix + 0.5, iy + 0.5);
      double nearest = std::numeric_limits<double>::infinity();
      for (const Vector2& p : points) {
        int px, py;
        grid.cellOf(p, &px, &py);
        if (std::abs(px - ix) > cells || std::abs(py - iy) > cells) continue;
        nearest = std::min(nearest, (centre - p).squaredNorm());
      }
      const float expected =
          std::isinf(nearest)
              ? 0.0f
              : static_cast<float>(std::exp(-nearest / (2.0 * options.sigma * options.sigma)));
      EXPECT_NEAR(grid.fine(ix, iy), expected, 1e-6f) << "cell " << ix << " " << iy;
      ++checked;
      positive += expected > 0.0f;
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(positive, 100);
}

// Level k is the definition of the bound: at cell (x, y) the largest fine
// value over the block [x, x + 2^k) × [y, y + 2^k), blocks reaching in from
// below the grid's lower edges included, and 0 for a block wholly outside.
TEST(LikelihoodGrid, EachLevelIsTheMaximumOverItsBlock) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(5);
  const std::vector<Vector2> points = placedSweep(world, Pose2(0.5, 0.5, -1.0), &rng);
  CorrelativeMatcherOptions options;
  options.levels = 5;
  const LikelihoodGrid grid(points, options);
  ASSERT_EQ(grid.levels(), 5);
  int ix_end, iy_end;
  grid.cellOf(grid.upperCorner(), &ix_end, &iy_end);
  long checked = 0, positive = 0, wrong = 0;
  for (int level = 1; level < grid.levels(); ++level) {
    const int size = 1 << level;
    for (int iy = -size - 1; iy <= iy_end + 1; iy += 2) {
      for (int ix = -size - 1; ix <= ix_end + 1; ix += 2) {
        float expected = 0.0f;
        for (int y = iy; y < iy + size; ++y) {
          for (int x = ix; x < ix + size; ++x) expected = std::max(expected, grid.fine(x, y));
        }
        wrong += grid.value(level, ix, iy) != expected;
        ++checked;
        positive += expected > 0.0f;
      }
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(checked, 1000);
  EXPECT_GT(positive, 500);
}

// A window of ±60 m and any heading around a guess 25 m and 150 deg off:
// the multi-level bound prunes the empty space, and the pose is found.
TEST(CorrelativeSearch, FindsThePoseAnywhereInAHugeWindowAtAnyHeading) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(7);
  const Pose2 pose(3.0, -2.0, 2.0);
  const std::vector<Vector2> reference = placedSweep(world, pose, &rng);
  const Pose2 query_pose = compose(pose, Pose2(0.4, 0.2, 0.3));
  const CorrelativeMatcherOptions options;
  const LikelihoodGrid grid(reference, options);
  const Pose2 guess = compose(query_pose, Pose2(-20.0, 15.0, degToRad(150.0)));
  const CorrelativeResult result = correlativeSearch(pointsOf(sweep(world, query_pose, &rng)), grid,
                                                     guess, 60.0, kPi, options, 0.5);
  EXPECT_GT(result.score, 0.7);
  EXPECT_LT(std::hypot(result.pose.x - query_pose.x, result.pose.y - query_pose.y), 0.08);
  EXPECT_LT(std::abs(wrapAngle(result.pose.theta - query_pose.theta)), degToRad(1.0));
}

// With a minimum score no pose reaches, the search reports none.
TEST(CorrelativeSearch, ReportsNothingBelowTheMinimumScore) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(8);
  const Pose2 pose(3.0, -2.0, 2.0);
  const std::vector<Vector2> reference = placedSweep(world, pose, &rng);
  const CorrelativeMatcherOptions options;
  const std::vector<Vector2> query = pointsOf(sweep(world, pose, &rng));
  const CorrelativeResult best =
      correlativeSearch(query, LikelihoodGrid(reference, options), pose, 1.0, 0.1, options);
  ASSERT_GT(best.score, 0.5);
  const CorrelativeResult none = correlativeSearch(query, LikelihoodGrid(reference, options), pose,
                                                   1.0, 0.1, options, best.score + 1e-6);
  EXPECT_EQ(none.score, 0.0);
  const CorrelativeResult same = correlativeSearch(query, LikelihoodGrid(reference, options), pose,
                                                   1.0, 0.1, options, best.score - 1e-3);
  EXPECT_NEAR(same.score, best.score, 1e-9);
  EXPECT_LT(maxAbsDifference(same.pose, best.pose), 1e-9);
}

TEST(CorrelativeSearch, BranchAndBoundEqualsTheExhaustiveSearch) {
  // One level makes the bound exact per translation, i.e. exhaustive.
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(4);
  const Pose2 pose(3.0, -2.0, 2.0);
  const std::vector<Vector2> reference = placedSweep(world, pose, &rng);
  const std::vector<Vector2> query =
      pointsOf(sweep(world, compose(pose, Pose2(0.3, 0.1, 0.05)), &rng));
  CorrelativeMatcherOptions exhaustive;
  exhaustive.levels = 1;
  const CorrelativeMatcherOptions bounded;  // 7 levels
  const CorrelativeResult a =
      correlativeSearch(query, LikelihoodGrid(reference, exhaustive), pose, 1.0, 0.1, exhaustive);
  const CorrelativeResult b =
      correlativeSearch(query, LikelihoodGrid(reference, bounded), pose, 1.0, 0.1, bounded);
  EXPECT_NEAR(a.score, b.score, 1e-6);
  EXPECT_LT(maxAbsDifference(a.pose, b.pose), 1e-9);
}

// A corridor 80 m long and 2.4 m wide with a pillar against its north wall
// every 3 m: every place looks like the places 3 m along.
sim::PolygonWorld pillaredCorridor() {
  sim::PolygonWorld world;
  world.addPolygon({{-40, -1.2}, {40, -1.2}, {40, 1.2}, {-40, 1.2}});
  for (int k = -13; k <= 13; ++k) world.addBox({3.0 * k, 1.0}, 0.4, 0.4);
  return world;
}

// A submap as the loop closer builds one: sweeps 0.4 m apart along a line
// through `pose` (its heading), from 4 m behind it to 4 m ahead.
std::vector<Vector2> submapAround(const sim::PolygonWorld& world, const Pose2& pose,
                                  std::mt19937* rng) {
  std::vector<Vector2> points;
  for (int k = -10; k <= 10; ++k) {
    const std::vector<Vector2> sweep_k =
        placedSweep(world, compose(pose, Pose2(0.4 * k, 0, 0)), rng);
    points.insert(points.end(), sweep_k.begin(), sweep_k.end());
  }
  return points;
}

// The runner-up search leaves out the translations near the best pose and
// finds the best of the rest: in the corridor the view 3 m along scores
// nearly as well as the true pose, in the hall no other place comes near.
TEST(CorrelativeSearch, RunnerUpIsAnotherPlaceAndTellsAnAliasedCorridorFromAHall) {
  const CorrelativeMatcherOptions options;
  struct Case {
    sim::PolygonWorld world;
    Pose2 pose;
  };
  const std::vector<Case> cases = {{pillaredCorridor(), Pose2(0.7, -0.2, 0.0)},
                                   {hall(), Pose2(-3.0, 2.0, -0.6)}};
  std::vector<double> ratios;
  for (const Case& c : cases) {
    std::mt19937 rng(11);
    const std::vector<Vector2> reference = submapAround(c.world, c.pose, &rng);
    const std::vector<Vector2> query =
        pointsOf(sweep(c.world, compose(c.pose, Pose2(0.2, 0.1, 0.03)), &rng));
    const LikelihoodGrid grid(reference, options);
    const Pose2 guess = compose(c.pose, Pose2(0.5, -0.3, 0.05));
    const CorrelativeResult best = correlativeSearch(query, grid, guess, 5.0, 0.3, options);
    ASSERT_GT(best.score, 0.7);
    const CorrelativeResult rival =
        correlativeRunnerUp(query, grid, guess, 5.0, 0.3, options, best.pose, 1.0, 0.0);
    EXPECT_GT(std::hypot(rival.pose.x - best.pose.x, rival.pose.y - best.pose.y), 1.0);
    EXPECT_LE(rival.score, best.score);
    ratios.push_back(rival.score / best.score);
  }
  EXPECT_GT(ratios[0], 0.95) << "the corridor's places one pillar apart";
  EXPECT_LT(ratios[1], 0.7) << "the hall";
}

// The bound prunes only what cannot beat the best outside the excluded
// disc: the runner-up equals the exhaustive search's (one level).
TEST(CorrelativeSearch, RunnerUpOfTheBranchAndBoundEqualsTheExhaustiveOne) {
  const sim::PolygonWorld world = pillaredCorridor();
  std::mt19937 rng(5);
  const Pose2 pose(1.0, 0.1, 0.0);
  const std::vector<Vector2> reference = submapAround(world, pose, &rng);
  const std::vector<Vector2> query =
      pointsOf(sweep(world, compose(pose, Pose2(0.3, 0.1, 0.02)), &rng));
  CorrelativeMatcherOptions exhaustive;
  exhaustive.levels = 1;
  const CorrelativeMatcherOptions bounded;
  const Pose2 best =
      correlativeSearch(query, LikelihoodGrid(reference, exhaustive), pose, 4.0, 0.1, exhaustive)
          .pose;
  const CorrelativeResult a = correlativeRunnerUp(query, LikelihoodGrid(reference, exhaustive),
                                                  pose, 4.0, 0.1, exhaustive, best, 1.0, 0.0);
  const CorrelativeResult b = correlativeRunnerUp(query, LikelihoodGrid(reference, bounded), pose,
                                                  4.0, 0.1, bounded, best, 1.0, 0.0);
  ASSERT_GT(a.score, 0.5);
  EXPECT_NEAR(a.score, b.score, 1e-6);
  EXPECT_LT(maxAbsDifference(a.pose, b.pose), 1e-9);
}

// The front end's next pose: the true step from `from` to `to` (0.1 m),
// turned 0.4 deg too far per metre.
Pose2 driftedStep(const Pose2& front_end, const Pose2& from, const Pose2& to) {
  return compose(front_end, compose(between(from, to), Pose2(0, 0, degToRad(0.4) * 0.1)));
}

struct LoopRun {
  std::vector<Pose2> truth, front_end, closed;
  std::vector<Pose2> causal;       // latestPose() right after each scan
  std::vector<long> accepted_by;   // loops accepted up to each scan
  std::vector<long> optimised_by;  // optimisations of the graph up to each scan
  std::vector<Pose2> loops;        // the final graph's loop edges (relative poses)
  std::vector<Pose2> loop_errors;  // each one's measurement against the truth
  LoopClosureCounters counters;
};

// Sweeps of `world` along `truth`, given to a loop closer with a front end
// that turns 0.4 deg too far per metre (driftedStep). `after_scan` (may be
// empty) is called after each scan with its index.
LoopRun runPath(const sim::PolygonWorld& world, const std::vector<Pose2>& truth,
                const LoopClosureOptions& options,
                const std::function<void(LoopCloser*, size_t)>& after_scan = {}) {
  std::mt19937 rng(11);
  LoopRun run;
  run.truth = truth;
  LoopCloser closer(options, ScanMatcherOptions());
  Pose2 front_end = run.truth.front();
  for (size_t i = 0; i < run.truth.size(); ++i) {
    if (i > 0) front_end = driftedStep(front_end, run.truth[i - 1], run.truth[i]);
    run.front_end.push_back(front_end);
    closer.addScan(0.1 * i, sweep(world, run.truth[i], &rng), Pose2(), front_end, true);
    if (after_scan) after_scan(&closer, i);
    run.causal.push_back(closer.latestPose());
    run.accepted_by.push_back(closer.counters().accepted);
    run.optimised_by.push_back(closer.counters().optimisations);
  }
  closer.finish();
  for (const StampedPose& p : closer.scanPoses()) run.closed.push_back(p.pose);
  const std::vector<PoseGraphEdge>& edges = closer.graph().edges();
  for (size_t e = 0; e < edges.size(); ++e) {
    if (edges[e].robust && !closer.isHeadingEdge(static_cast<int>(e))) {
      run.loops.push_back(edges[e].measurement);
      const Pose2 truth_relative = between(run.truth[closer.keyScanIndex(edges[e].from)],
                                           run.truth[closer.keyScanIndex(edges[e].to)]);
      run.loop_errors.push_back(between(truth_relative, edges[e].measurement));
    }
  }
  run.counters = closer.counters();
  return run;
}

// Two laps of the hall: after a lap of 28 m the front end's heading is
// 11 deg off and the position metres. `false_loops` wrong loops are
// injected during the second lap, each claiming that the newest key scan
// is where a key scan on the far side of the circle was. `tweak` (may be
// empty) changes the loop closer's options first.
LoopRun runTwoLaps(bool enabled, int false_loops = 0,
                   const std::function<void(LoopClosureOptions*)>& tweak = {}) {
  LoopClosureOptions options;
  options.enabled = enabled;
  if (tweak) tweak(&options);
  const std::vector<Pose2> truth = twoLaps();
  const size_t second_lap = truth.size() / 2;
  return runPath(hall(), truth, options, [&](LoopCloser* closer, size_t i) {
    if (false_loops > 0 && i > second_lap && (i - second_lap) % 40 == 0 &&
        static_cast<int>((i - second_lap) / 40) <= false_loops) {
      const int newest = closer->keyCount() - 1;
      EXPECT_FALSE(closer->addLoop(newest / 4, newest, Pose2(0.2, 0.0, 0.1)));
    }
  });
}

double positionError(const Pose2& a, const Pose2& b) { return std::hypot(a.x - b.x, a.y - b.y); }

bool samePose(const Pose2& a, const Pose2& b) {
  return a.x == b.x && a.y == b.y && a.theta == b.theta;
}

// A bound on the per-scan entries (scan_history) leaves the loop search
// alone: the same scans give the same graph, loops and causal poses, and
// scanPoses() is the newest part of the unbounded closer's, while the
// entries stay at the bound.
TEST(LoopCloser, AScanHistoryBoundKeepsTheGraphAndTheNewestScanPoses) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(11);
  const std::vector<Pose2> truth = twoLaps();
  const long history = 50;
  LoopCloser full{LoopClosureOptions(), ScanMatcherOptions()};
  LoopCloser bounded(LoopClosureOptions(), ScanMatcherOptions(), history);
  Pose2 front_end = truth.front();
  int most_entries = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (i > 0) front_end = driftedStep(front_end, truth[i - 1], truth[i]);
    const Scan scan = sweep(world, truth[i], &rng);
    full.addScan(0.1 * i, scan, Pose2(), front_end, true);
    bounded.addScan(0.1 * i, scan, Pose2(), front_end, true);
    ASSERT_TRUE(samePose(full.latestPose(), bounded.latestPose())) << "scan " << i;
    most_entries = std::max(most_entries, bounded.scanCount() - bounded.firstScan());
  }
  EXPECT_GT(full.counters().accepted, 3);
  EXPECT_EQ(bounded.counters().accepted, full.counters().accepted);
  EXPECT_LE(most_entries, history + history / 8);
  EXPECT_EQ(bounded.scanCount(), full.scanCount());
  EXPECT_GT(bounded.firstScan(), 0);
  ASSERT_EQ(bounded.keyCount(), full.keyCount());
  for (int k = 0; k < full.keyCount(); ++k) {
    EXPECT_TRUE(samePose(bounded.graph().pose(k), full.graph().pose(k))) << "key " << k;
    EXPECT_EQ(bounded.keyStamp(k), full.keyStamp(k)) << "key " << k;
    EXPECT_EQ(bounded.keyScanIndex(k), full.keyScanIndex(k)) << "key " << k;
  }
  const std::vector<StampedPose> all = full.scanPoses(), newest = bounded.scanPoses();
  ASSERT_EQ(static_cast<int>(newest.size()), bounded.scanCount() - bounded.firstScan());
  for (size_t i = 0; i < newest.size(); ++i) {
    const StampedPose& same = all[bounded.firstScan() + i];
    EXPECT_EQ(newest[i].stamp, same.stamp);
    EXPECT_TRUE(samePose(newest[i].pose, same.pose)) << "scan " << bounded.firstScan() + i;
    EXPECT_EQ(bounded.scanKey(bounded.firstScan() + i), full.scanKey(bounded.firstScan() + i));
  }
}

// Five laps with one key scan kept per place: a key scan whose place (1 m,
// 29 deg) holds one with readings already lets its readings go, so the
// readings kept stay below one lap's worth while the graph grows by a node
// per key scan; loops keep closing against the first lap (released
// key scans are never candidates) and the drifting front end stays pulled
// back to the truth to the end.
TEST(LoopCloser, KeyScansOfAFullPlaceLetTheirReadingsGoAndLoopsStillClose) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(11);
  const std::vector<Pose2> truth = laps(5);
  const size_t per_lap = truth.size() / 5;
  LoopClosureOptions options;
  options.max_keyscans_per_place = 1;
  LoopCloser closer(options, ScanMatcherOptions());
  Pose2 front_end = truth.front();
  long accepted_after_two_laps = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (i > 0) front_end = driftedStep(front_end, truth[i - 1], truth[i]);
    closer.addScan(0.1 * i, sweep(world, truth[i], &rng), Pose2(), front_end, true);
    if (i == 2 * per_lap) accepted_after_two_laps = closer.counters().accepted;
  }
  closer.finish();
  int with_readings = 0, first_lap_keys = 0;
  for (int k = 0; k < closer.keyCount(); ++k) {
    with_readings += closer.keyPoints(k).empty() ? 0 : 1;
    first_lap_keys += closer.keyScanIndex(k) <= static_cast<int>(per_lap) ? 1 : 0;
  }
  EXPECT_EQ(closer.counters().released, closer.keyCount() - with_readings);
  EXPECT_GE(closer.keyCount(), 4 * first_lap_keys);
  EXPECT_LT(with_readings, 1.5 * first_lap_keys) << closer.keyCount() << " key scans";
  EXPECT_GT(closer.counters().accepted, accepted_after_two_laps + 3);  // laps 3 to 5 close too
  const std::vector<StampedPose> closed = closer.scanPoses();
  ASSERT_EQ(closed.size(), truth.size());
  EXPECT_GT(positionError(front_end, truth.back()), 3.0);
  EXPECT_LT(positionError(closed.back().pose, truth.back()), 0.15);
  double worst = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    worst = std::max(worst, positionError(closed[i].pose, truth[i]));
  }
  EXPECT_LT(worst, 0.4);
}

std::vector<Vector2> segment(const Vector2& a, const Vector2& b, int count) {
  std::vector<Vector2> points;
  for (int i = 0; i <= count; ++i) points.push_back(a + (b - a) * (static_cast<double>(i) / count));
  return points;
}

// A view down a corridor, its end wall included, matched onto an old view
// that saw only the corridor's side walls (a false loop found on the
// simulated office): along the corridor the query's structure is the end
// wall, which nothing in the reference explains, so the share is 0 there
// and 1 across the corridor. With the end wall in the reference it is all
// explained; a query without structure along the corridor has nothing to
// explain. The same in a query frame turned and moved against the reference.
TEST(ExplainedStructure, AWallAcrossTheCorridorMustBeInTheReference) {
  const ScanMatcherOptions options;
  std::vector<Vector2> sides = segment({0.0, -1.0}, {6.0, -1.0}, 120);
  const std::vector<Vector2> north = segment({0.0, 1.0}, {6.0, 1.0}, 120);
  sides.insert(sides.end(), north.begin(), north.end());
  std::vector<Vector2> with_end = sides;
  const std::vector<Vector2> end = segment({6.3, -0.8}, {6.3, 0.8}, 32);
  with_end.insert(with_end.end(), end.begin(), end.end());
  const PointCloudReference side_walls(sides, options.normal_radius,
                                       options.correspondence_distance);
  const PointCloudReference every_wall(with_end, options.normal_radius,
                                       options.correspondence_distance);
  const Vector2 along(1.0, 0.0), across(0.0, 1.0);
  for (const Pose2& pose : {Pose2(), Pose2(1.0, 0.5, 0.3)}) {
    std::vector<Vector2> query, query_sides;
    for (const Vector2& p : with_end) query.push_back(transformTo(pose, p));
    for (const Vector2& p : sides) query_sides.push_back(transformTo(pose, p));
    EXPECT_LT(explainedStructure(query, side_walls, pose, along, options), 0.05);
    EXPECT_GT(explainedStructure(query, side_walls, pose, across, options), 0.95);
    EXPECT_GT(explainedStructure(query, every_wall, pose, along, options), 0.95);
    EXPECT_EQ(explainedStructure(query_sides, side_walls, pose, along, options), 1.0);
  }
}

// Each loop of the final graph measures its two key scans' true relative
// pose to a few centimetres and a degree.
void expectTrueLoops(const LoopRun& run) {
  for (size_t i = 0; i < run.loop_errors.size(); ++i) {
    const Pose2& e = run.loop_errors[i];
    EXPECT_LT(std::hypot(e.x, e.y), 0.05) << "loop " << i;
    EXPECT_LT(std::abs(e.theta), degToRad(1.0)) << "loop " << i;
  }
}

TEST(LoopCloser, ClosesADriftedLoopAndPullsTheTrajectoryBack) {
  const LoopRun run = runTwoLaps(/*enabled=*/true);
  ASSERT_EQ(run.closed.size(), run.truth.size());
  EXPECT_GT(run.counters.accepted, 3);
  EXPECT_EQ(run.counters.dropped, 0);
  expectTrueLoops(run);
  const Pose2& truth_end = run.truth.back();
  EXPECT_GT(positionError(run.front_end.back(), truth_end), 1.5);  // open without the back end
  EXPECT_LT(positionError(run.closed.back(), truth_end), 0.15);
  double worst = 0.0;
  for (size_t i = 0; i < run.truth.size(); ++i) {
    worst = std::max(worst, positionError(run.closed[i], run.truth[i]));
  }
  EXPECT_LT(worst, 0.4);
}

// Three quarters of the lap of laps() (21 m), a half turn on the spot,
// and back along the same arc to the start facing the other way: 0.1 m or
// 0.1 rad a scan.
std::vector<Pose2> outAndBack() {
  std::vector<Pose2> out = laps(1);
  out.resize(out.size() * 3 / 4);
  std::vector<Pose2> poses = out;
  const Pose2 turn = out.back();
  for (int i = 1; i <= 31; ++i) poses.emplace_back(turn.x, turn.y, turn.theta + kPi * i / 31.0);
  for (auto p = out.rbegin() + 1; p != out.rend(); ++p) {
    poses.emplace_back(p->x, p->y, p->theta + kPi);
  }
  return poses;
}

// The return sees what the outbound key scans before each place saw ahead
// of them: with the submap reaching back along the outbound path the
// return closes loops facing the other way and ends where it started; with
// the usual submap (the candidate's neighbours, whose view points the
// other way) no loop is found.
TEST(LoopCloser, APlaceDrivenTheOtherWayRoundClosesALoop) {
  const LoopRun run = runPath(hall(), outAndBack(), LoopClosureOptions());
  ASSERT_EQ(run.closed.size(), run.truth.size());
  ASSERT_FALSE(run.loops.empty());
  for (const Pose2& loop : run.loops) EXPECT_GT(std::abs(loop.theta), kPi / 2.0);
  expectTrueLoops(run);
  const Pose2& truth_end = run.truth.back();
  EXPECT_GT(positionError(run.front_end.back(), truth_end), 0.5);  // open without the loops
  EXPECT_LT(positionError(run.closed.back(), truth_end), 0.05);
  EXPECT_LT(std::abs(wrapAngle(run.closed.back().theta - truth_end.theta)), degToRad(2.0));

  LoopClosureOptions usual;
  usual.reverse_submap_travel = 0.0;
  EXPECT_TRUE(runPath(hall(), outAndBack(), usual).loops.empty());
}

TEST(LoopSubmapKeys, AReverseRevisitReachesBackAlongTheCandidatesPath) {
  LoopClosureOptions options;  // 5 each side, 15 m back for a reverse revisit
  const auto travel = [](int) { return 0.4; };
  KeyRange same = loopSubmapKeys(options, 100, 200, 0.3, travel);
  EXPECT_EQ(same.first, 95);
  EXPECT_EQ(same.last, 105);
  KeyRange reverse = loopSubmapKeys(options, 100, 200, -2.5, travel);
  EXPECT_EQ(reverse.first, 100 - 38);  // 38 steps of 0.4 m reach 15 m
  EXPECT_EQ(reverse.last, 105);
  reverse = loopSubmapKeys(options, 10, 12, kPi, travel);  // clipped at both ends
  EXPECT_EQ(reverse.first, 0);
  EXPECT_EQ(reverse.last, 11);
  options.reverse_submap_travel = 0.0;
  reverse = loopSubmapKeys(options, 100, 200, kPi, travel);
  EXPECT_EQ(reverse.first, 95);
}

long refusalsByReason(const LoopClosureCounters& c) {
  return c.refused_by_score + c.refused_by_fit + c.refused_as_degenerate + c.ambiguous;
}

// Every refused candidate is counted once with its reason: in a normal
// run (the arc out and back, where some candidates fail) the reasons add up
// to the refusals, and a bound no match can meet refuses every candidate
// with that bound's reason.
TEST(LoopCloser, EveryRefusedCandidateIsCountedWithItsReason) {
  const LoopRun normal = runPath(hall(), outAndBack(), LoopClosureOptions());
  EXPECT_GT(normal.counters.candidates, normal.counters.accepted);
  EXPECT_EQ(normal.counters.refused, refusalsByReason(normal.counters));

  // A mean likelihood of 1 needs every point exactly on the reference.
  const LoopRun by_score =
      runTwoLaps(/*enabled=*/true, 0, [](LoopClosureOptions* o) { o->min_score = 1.0; });
  EXPECT_EQ(by_score.counters.accepted, 0);
  EXPECT_GT(by_score.counters.refused, 0);
  EXPECT_EQ(by_score.counters.refused_by_score, by_score.counters.refused);
  EXPECT_EQ(by_score.counters.refused, by_score.counters.candidates);

  // No match is pinned to a micrometre along its weakest direction.
  const LoopRun degenerate = runTwoLaps(
      /*enabled=*/true, 0, [](LoopClosureOptions* o) { o->max_degenerate_sigma = 1e-6; });
  EXPECT_EQ(degenerate.counters.accepted, 0);
  EXPECT_GT(degenerate.counters.refused_as_degenerate, 0);
  EXPECT_EQ(degenerate.counters.refused, refusalsByReason(degenerate.counters));
  EXPECT_EQ(degenerate.counters.refused, degenerate.counters.candidates);

  // An ICP that may not move the correlative pose at all.
  const LoopRun by_fit =
      runTwoLaps(/*enabled=*/true, 0, [](LoopClosureOptions* o) { o->max_icp_shift = 1e-9; });
  EXPECT_EQ(by_fit.counters.accepted, 0);
  EXPECT_GT(by_fit.counters.refused_by_fit, 0);
  EXPECT_EQ(by_fit.counters.refused, refusalsByReason(by_fit.counters));
}

// The causal estimate (what a live node publishes at each scan) is the front
// end's until the graph is first optimised (a loop accepted, or heading
// loops); from then on it follows the loop-closed graph, so the robot's
// pose at the end of the second lap is centimetres from the truth while the
// front end is metres off.
TEST(LoopCloser, CausalPoseFollowsTheFrontEndUntilTheFirstLoopThenTheClosedGraph) {
  const LoopRun run = runTwoLaps(/*enabled=*/true);
  ASSERT_EQ(run.causal.size(), run.truth.size());
  size_t first_loop = run.causal.size();
  for (size_t i = 0; i < run.causal.size(); ++i) {
    if (run.optimised_by[i] > 0) {
      first_loop = i;
      break;
    }
    EXPECT_LT(maxAbsDifference(run.causal[i], run.front_end[i]), 1e-9) << "scan " << i;
  }
  ASSERT_LT(first_loop, run.causal.size());
  EXPECT_LT(positionError(run.causal.back(), run.truth.back()), 0.2);
  EXPECT_GT(positionError(run.front_end.back(), run.truth.back()), 1.5);
  double causal_error = 0.0, front_end_error = 0.0;
  for (size_t i = first_loop; i < run.causal.size(); ++i) {
    causal_error += positionError(run.causal[i], run.truth[i]);
    front_end_error += positionError(run.front_end[i], run.truth[i]);
  }
  EXPECT_LT(causal_error, 0.25 * front_end_error);
}

// Five wrong loops injected among the true ones (each claims that the
// newest key scan is where one a quarter of the way round was) fail the
// consistency test against the graph and are refused: the trajectory is
// the one without them. (Entering at full weight, they bent the map by
// 0.85 m and pushed the true loops out of their search windows.)
TEST(LoopCloser, InjectedFalseLoopsAreRefusedAndChangeNothing) {
  const LoopRun clean = runTwoLaps(/*enabled=*/true);
  const LoopRun injected = runTwoLaps(/*enabled=*/true, /*false_loops=*/5);
  EXPECT_EQ(injected.counters.accepted, clean.counters.accepted);
  EXPECT_EQ(injected.counters.inconsistent, clean.counters.inconsistent + 5);
  double worst = 0.0;
  for (size_t i = 0; i < clean.closed.size(); ++i) {
    worst = std::max(worst, positionError(injected.closed[i], clean.closed[i]));
  }
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(positionError(injected.closed.back(), injected.truth.back()), 0.15);
}

// Walls along two perpendicular directions, rotated by `angle`: the
// direction comes back modulo 90 deg, whatever the quarter turn.
TEST(WallDirection, IsTheWallsAngleModuloAQuarterTurn) {
  const ScanMatcherOptions options;
  for (const double degrees : {0.0, 20.0, 40.0, 70.0, -30.0, 125.0}) {
    const Pose2 turn(0.0, 0.0, degToRad(degrees));
    std::vector<Vector2> points;
    for (const Vector2& p : segment({-4.0, 3.0}, {4.0, 3.0}, 160)) {
      points.push_back(transformFrom(turn, p));
    }
    for (const Vector2& p : segment({4.0, 3.0}, {4.0, -3.0}, 120)) {
      points.push_back(transformFrom(turn, p));
    }
    double concentration = 0.0;
    int normals = 0;
    const double direction = wallDirection(points, options, &concentration, &normals);
    EXPECT_NEAR(direction, wrapAngle(degToRad(degrees) - kPi / 2 * std::round(degrees / 90.0)),
                0.002)
        << degrees << " deg";
    EXPECT_GE(direction, -kPi / 4);
    EXPECT_LT(direction, kPi / 4);
    EXPECT_GT(concentration, 0.95);
    EXPECT_GT(normals, 200);
  }
}

// Walls at every angle (a round room) have no direction.
TEST(WallDirection, ARoundRoomHasNone) {
  std::vector<Vector2> points;
  for (int i = 0; i < 300; ++i) {
    const double a = 2.0 * kPi * i / 300;
    points.emplace_back(4.0 * std::cos(a), 4.0 * std::sin(a));
  }
  double concentration = 1.0;
  int normals = 0;
  wallDirection(points, ScanMatcherOptions(), &concentration, &normals);
  EXPECT_GT(normals, 200);
  EXPECT_LT(concentration, 0.1);
}

// Two laps of the hall with every scan match refused (the scores can never
// reach 1): only heading loops can correct the front end, which turns 0.4
// deg too far per metre (22 deg after the two laps). The walls of the
// places passed again tie the second lap's heading to the first's: the
// causal heading ends 4-6 deg off instead of 22 (what is left is the first
// lap's own drift where it is met again), and the positions are 40 % better
// than the front end's; without the heading loops the causal estimate is
// the front end's.
TEST(LoopCloser, HeadingLoopsHoldTheHeadingWhereNoScanMatches) {
  const sim::PolygonWorld world = hall();
  const std::vector<Pose2> truth = twoLaps();
  auto run = [&](double heading_radius, LoopClosureCounters* counters) {
    std::mt19937 rng(5);
    LoopClosureOptions options;
    options.min_score = 1.0;
    options.heading_radius = heading_radius;
    LoopCloser closer(options, ScanMatcherOptions());
    Pose2 front_end = truth.front();
    std::vector<Pose2> causal;
    for (size_t i = 0; i < truth.size(); ++i) {
      if (i > 0) front_end = driftedStep(front_end, truth[i - 1], truth[i]);
      closer.addScan(0.1 * i, sweep(world, truth[i], &rng), Pose2(), front_end, true);
      causal.push_back(closer.latestPose());
    }
    closer.finish();
    *counters = closer.counters();
    return causal;
  };
  LoopClosureCounters with, without;
  const std::vector<Pose2> held = run(LoopClosureOptions().heading_radius, &with);
  const std::vector<Pose2> open = run(0.0, &without);
  EXPECT_EQ(with.accepted, 0);
  EXPECT_GT(with.heading_loops, 20);
  EXPECT_EQ(without.heading_loops, 0);
  const double open_heading = std::abs(wrapAngle(open.back().theta - truth.back().theta));
  const double held_heading = std::abs(wrapAngle(held.back().theta - truth.back().theta));
  EXPECT_GT(open_heading, degToRad(15.0));
  EXPECT_LT(held_heading, open_heading / 3.0);
  double open_error = 0.0, held_error = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    open_error += positionError(open[i], truth[i]);
    held_error += positionError(held[i], truth[i]);
  }
  EXPECT_LT(held_error, 0.7 * open_error);
}

// The two laps through a LoopClosureBackEnd: the pose each scan is given
// and the loops its view holds.
struct BackEndRun {
  std::vector<Pose2> causal;
  std::vector<long> accepted_by, scans_seen;
  std::vector<Pose2> closed;  // after finish()
  // The loops of the last view: per loop (not heading-only), the true
  // distance between its two key scans and how many key scans apart they are.
  std::vector<double> loop_true_distance;
  std::vector<int> loop_key_gap;
  int heading_loops = 0;
};

BackEndRun runTwoLapsThroughBackEnd(bool own_thread, int delay) {
  const sim::PolygonWorld world = hall();
  std::mt19937 rng(11);
  const std::vector<Pose2> truth = twoLaps();
  LoopClosureOptions options;
  options.correction_delay = delay;
  LoopClosureBackEnd back_end(options, ScanMatcherOptions(), own_thread);
  BackEndRun run;
  Pose2 front_end = truth.front();
  std::shared_ptr<const BackEndView> view;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (i > 0) front_end = driftedStep(front_end, truth[i - 1], truth[i]);
    view = back_end.addScan(0.1 * i, sweep(world, truth[i], &rng), Pose2(), front_end, true);
    run.causal.push_back(view->poseOf(front_end));
    run.accepted_by.push_back(view->counters.accepted);
    run.scans_seen.push_back(view->scans);
  }
  const int keys = static_cast<int>(view->key_poses.size());
  for (const LoopLink& link : view->loops) {
    EXPECT_TRUE(link.from >= 0 && link.from < keys && link.to >= 0 && link.to < keys);
    if (link.heading_only) {
      ++run.heading_loops;
      continue;
    }
    const Pose2& a = truth[view->key_scan_index[link.from]];
    const Pose2& b = truth[view->key_scan_index[link.to]];
    run.loop_true_distance.push_back(std::hypot(a.x - b.x, a.y - b.y));
    run.loop_key_gap.push_back(std::abs(link.to - link.from));
  }
  LoopCloser& closer = back_end.drained();
  closer.finish();
  for (const StampedPose& p : closer.scanPoses()) run.closed.push_back(p.pose);
  return run;
}

void expectBitIdentical(const std::vector<Pose2>& a, const std::vector<Pose2>& b,
                        const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_TRUE(a[i].x == b[i].x && a[i].y == b[i].y && a[i].theta == b[i].theta)
        << what << ", scan " << i;
  }
}

// Delay 0 is the synchronous back end: each scan sees the graph its own key
// scan produced, exactly as LoopCloser::latestPose() gives it.
TEST(LoopClosureBackEnd, DelayZeroIsTheSynchronousLoopCloser) {
  const LoopRun sync = runTwoLaps(/*enabled=*/true);
  const BackEndRun inline_run = runTwoLapsThroughBackEnd(/*own_thread=*/false, 0);
  ASSERT_GT(sync.counters.accepted, 0);
  expectBitIdentical(inline_run.causal, sync.causal, "inline, delay 0");
  EXPECT_EQ(inline_run.accepted_by, sync.accepted_by);
  expectBitIdentical(inline_run.closed, sync.closed, "final");
  // The view names the graph's loops, for drawing them: as many as were
  // accepted (none is dropped before finish), each joining key scans of
  // the two laps that stood in the same part of the hall, within 3 m
  // (ClosesADriftedLoopAndPullsTheTrajectoryBack checks that the same
  // loops measure the truth).
  EXPECT_EQ(static_cast<long>(inline_run.loop_true_distance.size()), sync.counters.accepted);
  EXPECT_EQ(inline_run.heading_loops, sync.counters.heading_loops);
  for (size_t i = 0; i < inline_run.loop_true_distance.size(); ++i) {
    EXPECT_LT(inline_run.loop_true_distance[i], 3.0) << "loop " << i;
    EXPECT_GT(inline_run.loop_key_gap[i], 10) << "loop " << i;
  }
}

// The deterministic mode: on its own thread the back end gives every scan
// the very view the inline run gives it, with the corrections d scans
// after the scan that triggered them.
TEST(LoopClosureBackEnd, OwnThreadGivesTheInlineViewsInTheDeterministicMode) {
  const BackEndRun at_once = runTwoLapsThroughBackEnd(/*own_thread=*/false, 0);
  for (const int delay : {0, 7}) {
    const BackEndRun inline_run = runTwoLapsThroughBackEnd(/*own_thread=*/false, delay);
    const BackEndRun threaded = runTwoLapsThroughBackEnd(/*own_thread=*/true, delay);
    expectBitIdentical(threaded.causal, inline_run.causal, "threaded vs inline");
    EXPECT_EQ(threaded.accepted_by, inline_run.accepted_by) << "delay " << delay;
    expectBitIdentical(threaded.closed, inline_run.closed, "final");
    // The corrections arrive exactly `delay` scans late.
    for (size_t i = 0; i < at_once.accepted_by.size(); ++i) {
      const long expected = i >= static_cast<size_t>(delay) ? at_once.accepted_by[i - delay] : 0;
      ASSERT_EQ(inline_run.accepted_by[i], expected) << "delay " << delay << ", scan " << i;
    }
  }
}

// As soon as ready: the caller never waits for the back end, the views it
// gets move forward only, and the back end ends with the graph of the
// synchronous run (it saw the same scans in the same order).
TEST(LoopClosureBackEnd, AsSoonAsReadyEndsWithTheSameGraph) {
  const BackEndRun inline_run = runTwoLapsThroughBackEnd(/*own_thread=*/false, -1);
  const BackEndRun threaded = runTwoLapsThroughBackEnd(/*own_thread=*/true, -1);
  expectBitIdentical(threaded.closed, inline_run.closed, "final");
  for (size_t i = 0; i < threaded.scans_seen.size(); ++i) {
    ASSERT_LE(threaded.scans_seen[i], static_cast<long>(i) + 1);
    if (i > 0) ASSERT_GE(threaded.scans_seen[i], threaded.scans_seen[i - 1]);
  }
  EXPECT_GT(inline_run.accepted_by.back(), 0);
}

TEST(LoopCloser, DisabledKeepsTheFrontEndTrajectory) {
  const LoopRun run = runTwoLaps(/*enabled=*/false);
  EXPECT_EQ(run.counters.accepted, 0);
  for (size_t i = 0; i < run.truth.size(); ++i) {
    EXPECT_LT(maxAbsDifference(run.closed[i], run.front_end[i]), 1e-9);
  }
}

TEST(LoopClosureOptions, ValidateNamesTheBadField) {
  LoopClosureOptions options;
  EXPECT_EQ(options.validate(), "");
  options.search_radius_max = 0.1;
  EXPECT_NE(options.validate().find("search_radius_max"), std::string::npos);
  options = LoopClosureOptions();
  options.correlative.resolution = 0.0;
  EXPECT_NE(options.validate().find("correlative.resolution must be in (0, 10] (m)"),
            std::string::npos)
      << options.validate();
}

}  // namespace
}  // namespace ekf_slam
