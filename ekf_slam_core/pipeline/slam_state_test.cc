#include "ekf_slam_core/pipeline/slam_state.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <random>

#include "ekf_slam_core/io/test_folder.h"
#include "ekf_slam_core/pipeline/global_localization.h"
#include "ekf_slam_core/pipeline/slam_pipeline.h"
#include "ekf_slam_core/pipeline/state_merge.h"
#include "ekf_slam_core/sim/drive.h"
#include "ekf_slam_core/sim/polygon_world.h"
#include "ekf_slam_core/testing/carton_room.h"

namespace ekf_slam {
namespace {

using testing::cartonRoom;

const Pose2 kLaser(0.1, 0.0, 0.0);

PipelineOptions islandOptions() {
  PipelineOptions options;
  options.filter.laser_pose = kLaser;
  options.landmarks = LandmarkSet::kPointsAndLines;
  options.loop_closure.min_loop_travel = 6.0;
  options.loop_closure.correction_delay = 0;
  return options;
}

// One and a half laps around the island with odometry that drifts in
// heading: the scans and the odometry at each.
struct Drive {
  std::vector<Scan> scans;
  std::vector<Pose2> odometry;
  std::vector<Pose2> truth;
};

Drive islandDrive() {
  const sim::PolygonWorld world = cartonRoom();
  std::mt19937 rng(5);
  sim::SweepGeometry sweep;
  sweep.max_range = 8.0;
  const double radius = 2.3, step = 0.08;
  const int scans = static_cast<int>(1.5 * 2.0 * kPi * radius / step);
  Drive drive;
  Pose2 odometry, previous;
  for (int i = 0; i <= scans; ++i) {
    const double a = step * i / radius;
    const Pose2 truth(3.0 + radius * std::sin(a), 1.5 - radius * std::cos(a), a);
    if (i > 0) odometry = compose(odometry, compose(between(previous, truth), Pose2(0, 0, 0.002)));
    previous = truth;
    Scan scan = sim::simulateScan(world, compose(truth, kLaser), sweep, 0.01, &rng, 0.05);
    scan.stamp = 0.1 * i;
    drive.scans.push_back(scan);
    drive.odometry.push_back(odometry);
    drive.truth.push_back(truth);
  }
  return drive;
}

// The first half of the drive, before any loop closes.
SlamPipeline firstHalf(const Drive& drive, const PipelineOptions& options = islandOptions()) {
  SlamPipeline pipeline(options);
  for (size_t i = 0; i < drive.scans.size() / 2; ++i) {
    pipeline.processScan(drive.scans[i], drive.odometry[i]);
  }
  return pipeline;
}

class SlamStateFile : public TestFolder {};

// The bytes of a state read back give the same bytes, and the filter, the
// key scans and the graph exactly as saved.
TEST_F(SlamStateFile, RoundTripsBitForBit) {
  const Drive drive = islandDrive();
  // As the live node runs it: the back end on its own thread, a bounded
  // history.
  PipelineOptions live = islandOptions();
  live.back_end_thread = true;
  live.history_scans = 20;
  const SlamState from_live = firstHalf(drive, live).state();
  EXPECT_EQ(from_live.back_end.key_filtered.size(), from_live.back_end.closer.keys.size());
  const SlamPipeline pipeline = firstHalf(drive);
  const SlamState state = pipeline.state("made by a test\n");
  ASSERT_GT(state.back_end.closer.keys.size(), 5u);
  ASSERT_GT(state.filter.landmarkCount(), 5);
  const std::string path = dir_ + "/office.state";
  ASSERT_EQ(writeSlamState(path, state), "");
  SlamState read;
  ASSERT_EQ(readSlamState(path, &read), "");
  EXPECT_EQ(encodeSlamState(read), encodeSlamState(state));
  EXPECT_EQ(read.configuration, "made by a test\n");
  EXPECT_EQ(read.filter.x.head(read.filter.dim), state.filter.x.head(state.filter.dim));
  EXPECT_EQ(read.filter.covariance(), state.filter.covariance());
  EXPECT_EQ(read.filter.slot_of_id, state.filter.slot_of_id);
  ASSERT_EQ(read.back_end.closer.keys.size(), state.back_end.closer.keys.size());
  EXPECT_EQ(read.back_end.closer.keys[3].points, state.back_end.closer.keys[3].points);
  EXPECT_EQ(read.back_end.closer.graph.poses().size(), state.back_end.closer.graph.poses().size());
  EXPECT_EQ(read.line_support.size(), state.line_support.size());
  EXPECT_EQ(read.scans, static_cast<long>(drive.scans.size() / 2));
}

// Continue mapping: a run resumed from the state of the first half closes
// its loops with the first half's key scans and is as close to the truth
// as one uninterrupted run. Two ways to go on: the same log's next scan,
// its odometry continuing (the motion since the save is taken); and
// another day, the robot where it stopped and its odometry starting
// anywhere.
TEST_F(SlamStateFile, AResumedRunClosesLoopsWithTheSavedKeyScans) {
  const Drive drive = islandDrive();
  const size_t half = drive.scans.size() / 2;
  const std::string path = dir_ + "/first_half.state";
  {
    const SlamPipeline first = firstHalf(drive);
    ASSERT_EQ(first.backEndCounters().accepted, 0) << "the loops close in the second half";
    ASSERT_EQ(writeSlamState(path, first.state()), "");
  }
  SlamPipeline whole(islandOptions());
  for (size_t i = 0; i < drive.scans.size(); ++i) {
    whole.processScan(drive.scans[i], drive.odometry[i]);
  }
  const std::vector<StampedPose> whole_causal = whole.causalScanPoses();
  for (const bool another_day : {false, true}) {
    SlamState state;
    ASSERT_EQ(readSlamState(path, &state), "");
    SlamPipeline resumed(islandOptions());
    ASSERT_EQ(resumed.resume(state), "");
    EXPECT_EQ(resumed.filter().state(), state.filter.x.head(state.filter.dim));
    // Another day: from the scan where the first half stopped, with
    // odometry from another origin.
    const size_t from = another_day ? half - 1 : half;
    const Pose2 origin(5.0, -3.0, 1.0);
    for (size_t i = from; i < drive.scans.size(); ++i) {
      Scan scan = drive.scans[i];
      if (another_day) scan.stamp += 86400.0;
      resumed.processScan(
          scan, another_day ? compose(origin, between(drive.odometry[from], drive.odometry[i]))
                            : drive.odometry[i]);
    }
    EXPECT_GT(resumed.backEndCounters().accepted, 0) << "no loop with the saved key scans";
    EXPECT_GT(resumed.backEndCounters().key_scans, state.back_end.closer.counters.key_scans);
    // The resumed run's poses are in the saved map (the first scan's pose
    // is its origin) and as close to the truth as one run's.
    // The history goes on from the saved scans' records.
    const std::vector<StampedPose> with_saved = resumed.causalScanPoses();
    ASSERT_EQ(with_saved.size(), half + drive.scans.size() - from);
    const std::vector<StampedPose> resumed_causal(with_saved.begin() + half, with_saved.end());
    double resumed_sum = 0.0, whole_sum = 0.0, resumed_worst = 0.0;
    for (size_t k = 0; k < resumed_causal.size(); ++k) {
      const Pose2 truth = between(drive.truth[0], drive.truth[from + k]);
      const Pose2& a = resumed_causal[k].pose;
      const Pose2& b = whole_causal[from + k].pose;
      const double resumed_error = std::hypot(a.x - truth.x, a.y - truth.y);
      resumed_sum += resumed_error;
      resumed_worst = std::max(resumed_worst, resumed_error);
      whole_sum += std::hypot(b.x - truth.x, b.y - truth.y);
    }
    const double resumed_mean = resumed_sum / resumed_causal.size();
    const double whole_mean = whole_sum / resumed_causal.size();
    std::cout << (another_day ? "another day" : "the log's next scan")
              << ": loops after the resume " << resumed.backEndCounters().accepted
              << "; second half's causal error against the truth: resumed " << resumed_mean
              << " m mean (largest " << resumed_worst << " m), one run " << whole_mean << " m\n";
    EXPECT_LT(resumed_mean, whole_mean + 0.01) << (another_day ? "another day" : "next scan");
    EXPECT_LT(resumed_worst, 0.05);
  }
}

// Global localisation: another day the robot starts a quarter of the way
// round the island, not where the first half stopped, with odometry from
// another origin and nobody saying where it is. Its first scans, searched
// over the saved map, place it; the run resumed there follows the truth.
TEST_F(SlamStateFile, ARobotStartedAnywhereIsFoundInTheSavedMapAndMapsOnFromThere) {
  const Drive drive = islandDrive();
  SlamState state = firstHalf(drive).state();
  ASSERT_FALSE(state.back_end.closer.keys.empty());
  const PipelineOptions options = islandOptions();
  GlobalLocalizer localizer(state, options.scan_matching, GlobalLocalizationOptions());
  ASSERT_EQ(localizer.mapError(), "");
  const size_t from = drive.scans.size() * 3 / 4;  // the first half passed here, 0.75 laps ago
  const Pose2 origin(-4.0, 7.0, 2.5);
  auto odometry = [&](size_t i) {
    return compose(origin, between(drive.odometry[from], drive.odometry[i]));
  };
  GlobalPlacement placement;
  size_t found = from;
  for (; found < drive.scans.size() && !placement.found; ++found) {
    placement = localizer.add(
        scanPointsInRobotFrame(drive.scans[found], kLaser, options.scan_matching), odometry(found));
  }
  --found;
  ASSERT_TRUE(placement.found) << placement.message;
  // The map frame: the robot's start in the first half.
  const Pose2 truth = between(drive.truth[0], drive.truth[found]);
  std::cout << "found after " << found - from + 1 << " scans (" << placement.joined_scans
            << " joined), score " << placement.score << ", runner-up " << placement.runner_up
            << "; off by " << (placement.map_pose.translation() - truth.translation()).norm()
            << " m, " << radToDeg(std::abs(wrapAngle(placement.map_pose.theta - truth.theta)))
            << " deg\n";
  EXPECT_LE(found - from, 20u);
  EXPECT_LT((placement.map_pose.translation() - truth.translation()).norm(), 0.05);
  EXPECT_LT(std::abs(wrapAngle(placement.map_pose.theta - truth.theta)), degToRad(1.0));

  EXPECT_TRUE(placement.has_front_end_pose);
  placeRobot(placement, Vector3(0.05 * 0.05, 0.05 * 0.05, 0.02 * 0.02).asDiagonal(), &state);
  SlamPipeline resumed(options);
  ASSERT_EQ(resumed.resume(state, ResumeAt::kPlacedRobot), "");
  for (size_t i = found; i < drive.scans.size(); ++i) {
    Scan scan = drive.scans[i];
    scan.stamp += 86400.0;
    resumed.processScan(scan, odometry(i));
  }
  // The new scans, after the saved ones' records.
  const std::vector<StampedPose> with_saved = resumed.causalScanPoses();
  const size_t saved = state.history.records.size();
  ASSERT_EQ(with_saved.size(), saved + drive.scans.size() - found);
  const std::vector<StampedPose> causal(with_saved.begin() + saved, with_saved.end());
  double sum = 0.0, worst = 0.0;
  for (size_t k = 0; k < causal.size(); ++k) {
    const Pose2 t = between(drive.truth[0], drive.truth[found + k]);
    const double e = (causal[k].pose.translation() - t.translation()).norm();
    sum += e;
    worst = std::max(worst, e);
  }
  std::cout << "placed and resumed: causal error " << sum / causal.size() << " m mean, largest "
            << worst << " m over " << causal.size() << " scans; loops "
            << resumed.backEndCounters().accepted << "\n";
  EXPECT_LT(sum / causal.size(), 0.05);
  EXPECT_LT(worst, 0.1);

  // Without key scans (loop closure off) there is nothing to search.
  PipelineOptions no_loops = islandOptions();
  no_loops.loop_closure.enabled = false;
  const GlobalLocalizer blind(firstHalf(drive, no_loops).state(), options.scan_matching,
                              GlobalLocalizationOptions());
  EXPECT_NE(blind.mapError().find("no key scans"), std::string::npos) << blind.mapError();
}

// The kidnapped robot: localising in the saved map (mapping off), the
// robot is carried a quarter lap on while its odometry stands still. Its
// scans stop fitting the map where it is estimated to stand, LostDetector
// says lost after lost_scans of them, the search finds it from the scans
// it sees after, and the state moved there (as the live node moves it)
// follows the truth again.
TEST_F(SlamStateFile, AKidnappedRobotIsLostThenFoundAgainInTheSavedMap) {
  const Drive drive = islandDrive();
  const SlamState saved = firstHalf(drive).state();
  const PipelineOptions options = islandOptions();
  const GlobalLocalizationOptions search_options;
  GlobalLocalizer localizer(saved, options.scan_matching, search_options);
  ASSERT_EQ(localizer.mapError(), "");
  const size_t half = drive.scans.size() / 2, carried = half + 30;
  const size_t skipped = drive.scans.size() / 6;  // a quarter lap of the 1.5
  // The scan at step i is taken at truth index truthIndex(i); the odometry
  // does not see the carrying (the wheels were off the floor).
  auto truthIndex = [&](size_t i) { return i < carried ? i : i + skipped; };
  auto odometry = [&](size_t i) {
    if (i < carried) return drive.odometry[i];
    return compose(drive.odometry[carried - 1],
                   between(drive.odometry[carried + skipped], drive.odometry[i + skipped]));
  };
  auto makePipeline = [&](const SlamState& state, ResumeAt at) {
    auto pipeline = std::make_unique<SlamPipeline>(options);
    EXPECT_EQ(pipeline->resume(state, at), "");
    pipeline->mutableFilter().setMappingEnabled(false);
    return pipeline;
  };
  std::unique_ptr<SlamPipeline> pipeline = makePipeline(saved, ResumeAt::kWhereItStopped);
  LostDetector lost(search_options);
  std::optional<GlobalPlacement> found;
  Pose2 found_odometry;
  size_t lost_at = 0, found_at = 0;
  double lowest_localised = 1.0, highest_carried = 0.0;
  double error_sum = 0.0, worst = 0.0;
  size_t after = 0, placed_at = 0;
  for (size_t i = half; i + skipped < drive.scans.size(); ++i) {
    const size_t t = truthIndex(i);
    if (found) {  // as the node does: at the next scan, carried on by the motion since
      SlamState state = pipeline->state();
      placeRobot(movedOn(*found, between(found_odometry, odometry(i))), placementCovariance(),
                 &state);
      placed_at = state.history.iterations.size();
      pipeline = makePipeline(state, ResumeAt::kPlacedRobot);
      found.reset();
      lost.reset();
    }
    const ScanResult result = pipeline->processScan(drive.scans[t], odometry(i));
    const std::vector<Vector2> points =
        scanPointsInRobotFrame(drive.scans[t], kLaser, options.scan_matching);
    if (found_at > 0) {
      const Pose2 truth = between(drive.truth[0], drive.truth[t]);
      const double e = (result.causal_pose.translation() - truth.translation()).norm();
      error_sum += e;
      worst = std::max(worst, e);
      ++after;
    }
    if (!lost.lost()) {
      const double score = localizer.fitNear(points, result.causal_pose);
      if (i < carried) lowest_localised = std::min(lowest_localised, score);
      if (i >= carried && lost_at == 0) highest_carried = std::max(highest_carried, score);
      if (lost.add(score)) {
        lost_at = i;
        localizer.restart();
      }
      continue;
    }
    const GlobalPlacement placement = localizer.add(points, odometry(i));
    if (placement.found) {
      found = placement;
      found_odometry = odometry(i);
      found_at = i;
    }
  }
  std::cout << "scores: localised at least " << lowest_localised << ", carried at most "
            << highest_carried << "; lost at scan " << lost_at - carried + 1
            << " after the carrying, found " << found_at - lost_at
            << " scans later; after: " << error_sum / std::max<size_t>(after, 1)
            << " m mean, largest " << worst << " m over " << after << " scans\n";
  EXPECT_GT(lowest_localised, search_options.lost_score) << "lost before it was carried";
  ASSERT_GT(lost_at, 0u) << "never lost";
  EXPECT_EQ(lost_at - carried + 1, static_cast<size_t>(search_options.lost_scans));
  ASSERT_GT(found_at, 0u) << "never found again";
  EXPECT_LE(found_at - lost_at, 20u);
  ASSERT_GT(after, 50u);
  EXPECT_LT(error_sum / after, 0.05);
  EXPECT_LT(worst, 0.1);
  // The history goes on across the placement, its chain of motion edges
  // broken there (placeRobot: the robot does not continue the saved run's
  // last iteration): the odometry did not see the carrying.
  const std::vector<SmootherIteration>& iterations = pipeline->smootherRecord().iterations();
  ASSERT_GT(iterations.size(), placed_at + 1);
  EXPECT_TRUE(iterations[placed_at - 1].has_control);
  EXPECT_FALSE(iterations[placed_at].has_control) << "a motion edge across the placement";
  EXPECT_TRUE(iterations[placed_at + 1].has_control);
}

// The history goes with the state: a run resumed at the log's next scan
// holds the saved scans' records, and its full smoother solves them with
// the new ones into the trajectory one uninterrupted run gives.
TEST_F(SlamStateFile, AResumedRunSmoothsTheSavedScansWithTheNewOnes) {
  const Drive drive = islandDrive();
  const size_t half = drive.scans.size() / 2;
  SlamState state;
  ASSERT_EQ(decodeSlamState(encodeSlamState(firstHalf(drive).state()), &state), "");
  EXPECT_EQ(state.history.records.size(), half);
  SlamPipeline resumed(islandOptions());
  ASSERT_EQ(resumed.resume(state), "");
  SlamPipeline whole(islandOptions());
  for (size_t i = 0; i < drive.scans.size(); ++i) {
    whole.processScan(drive.scans[i], drive.odometry[i]);
    if (i >= half) resumed.processScan(drive.scans[i], drive.odometry[i]);
  }
  whole.finishLoopClosure();
  resumed.finishLoopClosure();
  ASSERT_GT(resumed.backEndCounters().accepted, 0) << "no loop with the saved key scans";
  const std::vector<StampedPose> one = whole.smoothedScanPoses();
  const std::vector<StampedPose> two = resumed.smoothedScanPoses();
  ASSERT_EQ(two.size(), drive.scans.size()) << "the saved scans are smoothed too";
  ASSERT_EQ(one.size(), two.size());
  double largest = 0.0, one_error = 0.0, two_error = 0.0;
  for (size_t k = 0; k < one.size(); ++k) {
    EXPECT_EQ(two[k].stamp, drive.scans[k].stamp);
    largest =
        std::max(largest, std::hypot(one[k].pose.x - two[k].pose.x, one[k].pose.y - two[k].pose.y));
    const Pose2 truth = between(drive.truth[0], drive.truth[k]);
    one_error += std::hypot(one[k].pose.x - truth.x, one[k].pose.y - truth.y) / one.size();
    two_error += std::hypot(two[k].pose.x - truth.x, two[k].pose.y - truth.y) / two.size();
  }
  std::cout << "final trajectories: one run " << one_error << " m, two halves " << two_error
            << " m mean error; largest difference " << largest << " m\n";
  EXPECT_LT(largest, 0.01);
  EXPECT_LT(two_error, one_error * 1.05 + 0.001);
}

// A state keeps the newest scans' history only (kSavedHistoryScans),
// trimmed as a bounded history trims itself: the oldest kept iteration is
// the first, with the filter's estimate there as its prior. Resumed, it is
// smoothed with the new scans.
TEST_F(SlamStateFile, TheSavedHistoryKeepsTheNewestScans) {
  const Drive drive = islandDrive();
  const size_t half = drive.scans.size() / 2;
  SlamState state = firstHalf(drive).state();
  ASSERT_EQ(state.history.records.size(), half);
  const int iterations = static_cast<int>(state.history.iterations.size());
  keepNewestScans(40, &state.history);
  ASSERT_EQ(state.history.records.size(), 40u);
  EXPECT_EQ(state.history.first_record, static_cast<long>(half - 40));
  EXPECT_EQ(state.history.first_iteration, state.history.records.front().iteration);
  EXPECT_EQ(state.history.first_iteration + static_cast<int>(state.history.iterations.size()),
            iterations);
  EXPECT_EQ(state.history.steps.size(), state.history.iterations.size());
  EXPECT_EQ(state.history.prior_mean.x, state.history.steps.front().filtered.x);

  SlamPipeline resumed(islandOptions());
  ASSERT_EQ(resumed.resume(state), "");
  for (size_t i = half; i < drive.scans.size(); ++i) {
    resumed.processScan(drive.scans[i], drive.odometry[i]);
  }
  resumed.finishLoopClosure();
  const std::vector<StampedPose> poses = resumed.smoothedScanPoses();
  ASSERT_EQ(poses.size(), 40 + drive.scans.size() - half);
  EXPECT_EQ(poses.front().stamp, drive.scans[half - 40].stamp);
  double sum = 0.0;
  for (size_t k = 0; k < poses.size(); ++k) {
    const Pose2 truth = between(drive.truth[0], drive.truth[half - 40 + k]);
    sum += (poses[k].pose.translation() - truth.translation()).norm();
  }
  EXPECT_LT(sum / poses.size(), 0.02);
}

// Merging: the second half of the drive mapped on its own, another day
// (its odometry from another origin, its own map frame), and joined with
// the first half's state: found in the first map, loops closed between the
// two, one pose per scan of both, as close to the truth as one run.
TEST_F(SlamStateFile, TwoRunsOfOneBuildingMergeIntoOneMap) {
  const Drive drive = islandDrive();
  const size_t half = drive.scans.size() / 2;
  const SlamState first = firstHalf(drive).state();
  SlamPipeline other_day(islandOptions());
  const Pose2 origin(5.0, -3.0, 1.0);
  for (size_t i = half; i < drive.scans.size(); ++i) {
    Scan scan = drive.scans[i];
    scan.stamp += 86400.0;
    other_day.processScan(scan, compose(origin, between(drive.odometry[half], drive.odometry[i])));
  }
  SlamState second;
  ASSERT_EQ(decodeSlamState(encodeSlamState(other_day.state()), &second), "");
  SlamPipeline whole(islandOptions());
  for (size_t i = 0; i < drive.scans.size(); ++i) {
    whole.processScan(drive.scans[i], drive.odometry[i]);
  }
  whole.finishLoopClosure();
  const std::vector<StampedPose> one = whole.smoothedScanPoses();

  const StateMerge merge = mergeStates(first, second, islandOptions());
  ASSERT_EQ(merge.error, "");
  ASSERT_TRUE(merge.problem.has_value());
  EXPECT_GE(merge.aligned_key, 0);
  EXPECT_GT(merge.cross_loops, 0) << "no loop between the two runs";
  const std::vector<StampedPose> merged = merge.problem->solve();
  ASSERT_EQ(merged.size(), drive.scans.size()) << "one pose per scan of both runs";
  double merged_sum = 0.0, one_sum = 0.0, worst = 0.0;
  for (size_t k = 0; k < merged.size(); ++k) {
    EXPECT_EQ(merged[k].stamp, drive.scans[k].stamp + (k < half ? 0.0 : 86400.0));
    const Pose2 truth = between(drive.truth[0], drive.truth[k]);
    const double e = (merged[k].pose.translation() - truth.translation()).norm();
    merged_sum += e;
    worst = std::max(worst, e);
    one_sum += (one[k].pose.translation() - truth.translation()).norm();
  }
  std::cout << "merged: aligned at key scan " << merge.aligned_key << ", " << merge.cross_loops
            << " loops between the runs; error " << merged_sum / merged.size()
            << " m mean (largest " << worst << " m), one run " << one_sum / one.size() << " m\n";
  EXPECT_LT(merged_sum / merged.size(), one_sum / one.size() + 0.01);
  EXPECT_LT(worst, 0.05);

  // A state without key scans (loop closure off) cannot be searched.
  PipelineOptions no_loops = islandOptions();
  no_loops.loop_closure.enabled = false;
  const StateMerge refused = mergeStates(firstHalf(drive, no_loops).state(), second, no_loops);
  EXPECT_NE(refused.error.find("no key scans"), std::string::npos) << refused.error;
  EXPECT_FALSE(refused.problem.has_value());
}

TEST_F(SlamStateFile, RefusesWhatIsNotAWholeStateOfThisVersionAndMount) {
  const Drive drive = islandDrive();
  const SlamState state = firstHalf(drive).state();
  const std::string bytes = encodeSlamState(state);
  SlamState read;
  const auto refused = [&](const std::string& data) {
    read.scans = -7;
    const std::string error = decodeSlamState(data, &read);
    EXPECT_EQ(read.scans, -7) << "a refused state changed the output";
    return error;
  };
  EXPECT_NE(refused(bytes.substr(0, bytes.size() / 2)).find("truncated"), std::string::npos);
  EXPECT_NE(refused(bytes.substr(0, 20)).find("header"), std::string::npos);
  std::string corrupt = bytes;
  corrupt[bytes.size() / 2] ^= 0x40;
  EXPECT_NE(refused(corrupt).find("checksum"), std::string::npos);
  std::string other_version = bytes;
  other_version[15] = 9;  // the version's low byte, after the magic line
  EXPECT_NE(refused(other_version).find("version 9"), std::string::npos) << refused(other_version);
  other_version[15] = 2;  // an older build's: no history of the scans
  EXPECT_NE(refused(other_version).find("no history"), std::string::npos) << refused(other_version);
  EXPECT_NE(refused("P5\n640 480\n").find("not a SLAM state"), std::string::npos);
  EXPECT_EQ(decodeSlamState(bytes, &read), "");
  ASSERT_FALSE(state.back_end.point_seen_at.empty());
  EXPECT_EQ(read.back_end.point_seen_at, state.back_end.point_seen_at);

  // A version 3 state (the same, without the point landmarks' estimates at
  // their latest sightings, the last list of version 4) is still read.
  SlamState without = state;
  without.back_end.point_seen_at.clear();
  const std::string current = encodeSlamState(without);
  const size_t header = 15 + 4 + 8, checksum = 8, empty_list = 8;
  std::string payload = current.substr(header, current.size() - header - checksum - empty_list);
  std::string version3 = current.substr(0, 15) + std::string("\x03\0\0\0", 4);
  uint64_t length = payload.size(), hash = 14695981039346656037ULL;  // FNV-1a 64
  for (const char c : payload) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  for (int i = 0; i < 8; ++i) version3.push_back(static_cast<char>(length >> (8 * i)));
  version3 += payload;
  for (int i = 0; i < 8; ++i) version3.push_back(static_cast<char>(hash >> (8 * i)));
  ASSERT_EQ(decodeSlamState(version3, &read), "");
  EXPECT_EQ(encodeSlamState(read), current);

  EXPECT_NE(readSlamState(dir_ + "/missing.state", &read).find("missing.state"), std::string::npos);

  // Another laser mount: refused, and the pipeline goes on with its own map.
  PipelineOptions moved = islandOptions();
  moved.filter.laser_pose = Pose2(0.3, 0.0, 0.0);
  SlamPipeline other(moved);
  const std::string error = other.resume(state);
  EXPECT_NE(error.find("laser"), std::string::npos) << error;
  EXPECT_EQ(other.filter().landmarkCount(), 0);
  EXPECT_EQ(other.backEndCounters().key_scans, 0);
  // Only before the first scan.
  SlamPipeline started(islandOptions());
  started.processScan(drive.scans[0], drive.odometry[0]);
  EXPECT_NE(started.resume(state).find("before the first scan"), std::string::npos);
}

}  // namespace
}  // namespace ekf_slam
